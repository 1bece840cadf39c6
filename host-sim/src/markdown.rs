//! Markdown tables for the reports (the accuracy-cost report, the
//! identification report).

/// Markdown cell text: `|` escaped.
pub fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// The writer of every Markdown table of the reports: a Markdown table of a header
/// row, a `|---|` rule and one line per row, each cell as given with `|`
/// escaped. The columns are not padded to a common width (a long note
/// would widen every line of its column), so each line reads as written.
pub struct Table {
    text: String,
    columns: usize,
}

impl Table {
    /// A table of these column titles.
    pub fn new<S: AsRef<str>>(header: impl IntoIterator<Item = S>) -> Self {
        let mut table = Self {
            text: String::new(),
            columns: 0,
        };
        table.columns = table.line(header);
        table.text.push('|');
        table.text.push_str(&"---|".repeat(table.columns));
        table.text.push('\n');
        table
    }

    /// Appends one row.
    pub fn row<S: AsRef<str>>(&mut self, cells: impl IntoIterator<Item = S>) {
        let n = self.line(cells);
        debug_assert_eq!(
            n, self.columns,
            "a row of {n} cells in a table of {}",
            self.columns
        );
    }

    /// Writes `| a | b |` and a newline; returns the number of cells.
    fn line<S: AsRef<str>>(&mut self, cells: impl IntoIterator<Item = S>) -> usize {
        self.text.push('|');
        let mut n = 0;
        for c in cells {
            self.text.push(' ');
            self.text.push_str(&cell(c.as_ref()));
            self.text.push_str(" |");
            n += 1;
        }
        self.text.push('\n');
        n
    }

    /// The table's text, each line ended by a newline.
    pub fn finish(self) -> String {
        self.text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_unpadded_markdown_with_pipes_escaped() {
        let mut t = Table::new(["a", "long title"]);
        t.row(["x|y", ""]);
        t.row([String::from("1"), String::from("2")]);
        assert_eq!(
            t.finish(),
            "| a | long title |\n|---|---|\n| x\\|y |  |\n| 1 | 2 |\n"
        );
    }
}
