//! Small CSV files written whole (`modulus.csv`, `powertrain.csv`,
//! `accuracy-cost.csv`), through the `csv` crate like the streamed
//! `trace.csv`: fields are quoted where they must be, numbers keep the form
//! the caller gives them.

/// A CSV document built in memory, one record at a time.
#[derive(Debug)]
pub struct CsvText {
    writer: csv::Writer<Vec<u8>>,
}

impl CsvText {
    /// A document whose first record is `header`.
    pub fn new<I, S>(header: I) -> Self
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        let mut text = Self {
            writer: csv::Writer::from_writer(Vec::new()),
        };
        text.record(header);
        text
    }

    /// Appends one record.
    pub fn record<I, S>(&mut self, fields: I)
    where
        I: IntoIterator<Item = S>,
        S: AsRef<[u8]>,
    {
        // Writing into memory cannot fail: the only errors of a csv writer
        // are its sink's.
        let _ = self.writer.write_record(fields);
    }

    /// The document.
    pub fn finish(self) -> String {
        let bytes = self
            .writer
            .into_inner()
            .map_err(|e| e.into_inner().get_ref().clone())
            .unwrap_or_else(|partial| partial);
        String::from_utf8_lossy(&bytes).into_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_quoted_only_where_needed() {
        let mut t = CsvText::new(["a", "b"]);
        t.record(["1e0", "plain"]);
        t.record(["x,y", "say \"hi\""]);
        assert_eq!(t.finish(), "a,b\n1e0,plain\n\"x,y\",\"say \"\"hi\"\"\"\n");
    }
}
