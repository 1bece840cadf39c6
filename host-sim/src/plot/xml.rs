//! Text made safe for XML, and a checker of well-formedness for the
//! tests (here and in the integration suites).

/// `text` made safe to hand to the SVG backend, which escapes the markup
/// characters itself: the control characters XML 1.0 does not allow (and
/// U+FFFE, U+FFFF) dropped, tabs and line breaks made spaces.
pub fn sanitize(text: &str) -> String {
    text.chars()
        .filter_map(|c| match c {
            '\t' | '\n' | '\r' => Some(' '),
            c if c.is_control() || matches!(c, '\u{FFFE}' | '\u{FFFF}') => None,
            c => Some(c),
        })
        .collect()
}

/// Checks that `xml` is one well-formed element: every tag closed in
/// order, attributes quoted, `<` and `&` only as markup or entities, no
/// forbidden control character. Enough for the documents this module
/// writes (no DTD, no CDATA); returns what is wrong and where.
pub fn well_formed(xml: &str) -> Result<(), String> {
    let mut stack: Vec<&str> = Vec::new();
    let mut roots = 0usize;
    let mut rest = xml;
    let at = |r: &str| xml.len() - r.len();
    while !rest.is_empty() {
        let Some(lt) = rest.find('<') else {
            check_text(rest, at(rest))?;
            if !rest.trim().is_empty() && stack.is_empty() {
                return Err(format!("byte {}: text after the root element", at(rest)));
            }
            break;
        };
        let (text, tail) = rest.split_at(lt);
        check_text(text, at(rest))?;
        if stack.is_empty() && !text.trim().is_empty() {
            return Err(format!("byte {}: text outside the root element", at(rest)));
        }
        rest = tail;
        if let Some(r) = rest.strip_prefix("<?") {
            let end = r
                .find("?>")
                .ok_or_else(|| format!("byte {}: unclosed <?", at(rest)))?;
            rest = r.get(end + 2..).unwrap_or("");
            continue;
        }
        if let Some(r) = rest.strip_prefix("<!--") {
            let end = r
                .find("-->")
                .ok_or_else(|| format!("byte {}: unclosed comment", at(rest)))?;
            rest = r.get(end + 3..).unwrap_or("");
            continue;
        }
        let start = at(rest);
        let end = rest
            .find('>')
            .ok_or_else(|| format!("byte {start}: unclosed tag"))?;
        let inner = rest.get(1..end).unwrap_or("");
        rest = rest.get(end + 1..).unwrap_or("");
        if let Some(name) = inner.strip_prefix('/') {
            let name = name.trim_end();
            check_name(name, start)?;
            match stack.pop() {
                Some(open) if open == name => {}
                Some(open) => {
                    return Err(format!("byte {start}: </{name}> closes <{open}>"));
                }
                None => return Err(format!("byte {start}: </{name}> closes nothing")),
            }
            continue;
        }
        let (body, empty) = match inner.strip_suffix('/') {
            Some(b) => (b, true),
            None => (inner, false),
        };
        let name_end = body.find(|c: char| c.is_whitespace()).unwrap_or(body.len());
        let (name, attrs) = body.split_at(name_end);
        check_name(name, start)?;
        check_attributes(attrs, start)?;
        if stack.is_empty() {
            roots += 1;
            if roots > 1 {
                return Err(format!("byte {start}: a second root element <{name}>"));
            }
        }
        if !empty {
            stack.push(name);
        }
    }
    if let Some(open) = stack.last() {
        return Err(format!("<{open}> is never closed"));
    }
    if roots == 0 {
        return Err("no element".into());
    }
    Ok(())
}

fn check_name(name: &str, at: usize) -> Result<(), String> {
    let ok = name
        .chars()
        .next()
        .is_some_and(|c| c.is_alphabetic() || c == '_' || c == ':')
        && name
            .chars()
            .all(|c| c.is_alphanumeric() || matches!(c, '_' | ':' | '-' | '.'));
    if ok {
        Ok(())
    } else {
        Err(format!("byte {at}: bad tag name '{name}'"))
    }
}

fn check_attributes(mut s: &str, at: usize) -> Result<(), String> {
    let mut seen: Vec<&str> = Vec::new();
    loop {
        s = s.trim_start();
        if s.is_empty() {
            return Ok(());
        }
        let eq = s
            .find('=')
            .ok_or_else(|| format!("byte {at}: attribute without a value in '{s}'"))?;
        let name = s.get(..eq).unwrap_or("").trim_end();
        check_name(name, at)?;
        if seen.contains(&name) {
            return Err(format!("byte {at}: attribute '{name}' given twice"));
        }
        seen.push(name);
        let value = s.get(eq + 1..).unwrap_or("").trim_start();
        let quote = value
            .chars()
            .next()
            .filter(|c| matches!(c, '"' | '\''))
            .ok_or_else(|| format!("byte {at}: attribute '{name}' is not quoted"))?;
        let body = value.get(1..).unwrap_or("");
        let close = body
            .find(quote)
            .ok_or_else(|| format!("byte {at}: attribute '{name}' is not closed"))?;
        let text = body.get(..close).unwrap_or("");
        if text.contains('<') {
            return Err(format!("byte {at}: '<' in attribute '{name}'"));
        }
        check_text(text, at)?;
        s = body.get(close + 1..).unwrap_or("");
        if !(s.is_empty() || s.starts_with(char::is_whitespace)) {
            return Err(format!("byte {at}: no space after attribute '{name}'"));
        }
    }
}

/// Character data: every `&` starts an entity; no forbidden character.
fn check_text(text: &str, at: usize) -> Result<(), String> {
    if let Some(c) = text
        .chars()
        .find(|c| c.is_control() && !matches!(c, '\t' | '\n' | '\r'))
    {
        return Err(format!("byte {at}: control character {:?}", c));
    }
    let mut rest = text;
    while let Some(amp) = rest.find('&') {
        let tail = rest.get(amp + 1..).unwrap_or("");
        let semi = tail
            .find(';')
            .ok_or_else(|| format!("byte {at}: '&' without ';'"))?;
        let entity = tail.get(..semi).unwrap_or("");
        let known = matches!(entity, "amp" | "lt" | "gt" | "quot" | "apos")
            || entity
                .strip_prefix("#x")
                .is_some_and(|h| !h.is_empty() && h.chars().all(|c| c.is_ascii_hexdigit()))
            || entity
                .strip_prefix('#')
                .is_some_and(|d| !d.is_empty() && d.chars().all(|c| c.is_ascii_digit()));
        if !known {
            return Err(format!("byte {at}: unknown entity '&{entity};'"));
        }
        rest = tail.get(semi + 1..).unwrap_or("");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sanitized_text_has_no_forbidden_character() {
        assert_eq!(sanitize("a\u{1}b\tc\u{FFFF}\u{7f}<&>"), "ab c<&>");
    }

    #[test]
    fn the_checker_finds_what_breaks_xml() {
        well_formed(r#"<?xml version="1.0"?><a x="1"><!-- c --><b/>t &amp; &#233;</a>"#).unwrap();
        for bad in [
            "<a><b></a></b>",
            "<a>",
            "</a>",
            "<a></a><b/>",
            "<a x=1/>",
            r#"<a x="1" x="2"/>"#,
            r#"<a x="<"/>"#,
            "<a>1 < 2</a>",
            "<a>&nbsp;</a>",
            "<a>fish & chips</a>",
            "<a>\u{1}</a>",
            "<1a/>",
            "text<a/>",
            "",
        ] {
            assert!(well_formed(bad).is_err(), "{bad:?} accepted");
        }
    }
}
