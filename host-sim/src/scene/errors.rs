//! A scene's mistakes: where they are (line, column and the span shown
//! with a caret) and what they are, with the shape errors of serde made to
//! point at the value at fault.

use std::fmt;
use std::ops::Range;

use serde::de::{self, DeserializeSeed, Visitor};
use toml::Spanned;
use toml::de::{DeTable, DeValue, ValueDeserializer};

use crate::family::EffectByTag;
use crate::family::backbone::BackboneByTag;
use crate::profile::ProfileByTag;

/// Where in a file something went wrong: 1-based line and column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    /// Line, from 1.
    pub line: usize,
    /// Column, from 1 (in characters).
    pub column: usize,
}

impl Location {
    /// Location of byte offset `at` in `text`.
    pub fn of(text: &str, at: usize) -> Self {
        let at = at.min(text.len());
        let before = text.get(..at).unwrap_or(text);
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        Self { line, column }
    }
}

/// A scene that could not be read or built.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// File name as given.
    pub file: String,
    /// Position of the mistake, when known.
    pub at: Option<Location>,
    /// What was expected.
    pub message: String,
    /// The scene's text and the byte range at fault, for a report that
    /// shows the line with a caret ([`miette::Diagnostic`]).
    pub source: Option<(std::sync::Arc<str>, Range<usize>)>,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.at {
            Some(l) => write!(f, "{}:{}:{}: {}", self.file, l.line, l.column, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for SceneError {}

impl miette::Diagnostic for SceneError {
    fn source_code(&self) -> Option<&dyn miette::SourceCode> {
        self.source
            .as_ref()
            .map(|(text, _)| text as &dyn miette::SourceCode)
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        let (text, span) = self.source.as_ref()?;
        let start = span.start.min(text.len());
        // The first line of the span: a whole table would hide the caret.
        let line_end = text[start..].find('\n').map_or(text.len(), |n| start + n);
        let end = span.end.clamp(start, line_end).max(start);
        Some(Box::new(std::iter::once(miette::LabeledSpan::at(
            start..end,
            "here",
        ))))
    }
}

/// The place and the message of a TOML or shape error (a missing key, a
/// value of the wrong type), as precise as the document allows: a mistake
/// inside a tagged table (`[backbone]`, `[[effects]]`, `[profile]`) is found
/// again by reading the table as its variant ([`tagged_mistake`]), and the
/// message starts with where it is (`effects[0] (maxwell): cells[1].g: `).
pub(super) fn shape_error(text: &str, e: &toml::de::Error) -> (Option<Range<usize>>, String) {
    let message = e.message().trim().to_string();
    let Some(mut span) = e.span() else {
        return (None, message);
    };
    // A syntax error: the parser's own place and message.
    let Ok(doc) = DeTable::parse(text) else {
        return (Some(span), message);
    };
    let doc = doc.into_inner();
    if let Some(at) = tagged_mistake(&doc, &span, &message) {
        span = at;
    }
    let mut path = Vec::new();
    let mut best = None;
    find_value(&doc, &span, &mut path, &mut best);
    let Some((path, value)) = best else {
        return (Some(span), message);
    };
    let Some(value) = value else {
        // A key (an unknown one): name the table it is in.
        let table = path.split_last().map_or(&[][..], |(_, t)| t);
        return (Some(span), format!("{}{message}", prefix(&doc, table)));
    };
    let opens = |s: &str| text.get(span.start..).is_some_and(|t| t.starts_with(s));
    let (path, message) = match (value, &path[..]) {
        // `[effects]` for `[[effects]]`, `cells = { … }` for `cells = [{ … }]`.
        (DeValue::Table(_), _) if message.starts_with("invalid type: map, expected a sequence") => {
            let name = dotted(&path);
            let message = if opens("[") {
                format!(
                    "a single table `[{name}]` where an array of tables is expected: \
                     write `[[{name}]]` above each entry"
                )
            } else {
                "a table where an array is expected: write `[{ … }, { … }]`".to_string()
            };
            (&path[..], message)
        }
        // `[[backbone]]` for `[backbone]`: serde reads the table's fields
        // from the array's entries, the first of which is a whole table.
        (DeValue::Table(_), [table @ Step::Key(name), Step::Index(0)])
            if opens("[[") && message.starts_with("invalid type: map") =>
        {
            let message = format!(
                "`[[{name}]]` starts an array of tables where a single table is expected: \
                 write `[{name}]`"
            );
            (std::slice::from_ref(table), message)
        }
        _ => (&path[..], message),
    };
    (Some(span), format!("{}{message}", prefix(&doc, path)))
}

/// Where the mistake is when an error points at a tagged table (or at the
/// `[[effects]]` array, as errors inside its entries do): the first such
/// table that does not read as its variant, at the value the variant names
/// (at the table itself for unknown keys and names, whose message lists
/// what the table takes). `None` to leave the error where it is.
fn tagged_mistake(doc: &DeTable<'_>, span: &Range<usize>, message: &str) -> Option<Range<usize>> {
    // Errors inside an `[[effects]]` entry point at the array, whose span
    // is that of its first entry.
    let in_effects = doc.get("effects").is_some_and(|e| e.span() == *span);
    let candidates = tagged_tables(doc)
        .into_iter()
        .filter(|(table, _, entry)| table.span() == *span || (*entry && in_effects));
    for (table, read, _) in candidates {
        let Some(tag) = tag_of(table) else {
            // No string `type` (or not a table): serde stops here too.
            return Some(table.span());
        };
        let Err(again) = read(by_tag(table, tag)) else {
            continue;
        };
        // The same mistake, found where it is; otherwise leave it.
        if again.message().trim() != message {
            return None;
        }
        // An unknown field, or the table's own `type`, is shown at the
        // table; an unknown name in a value (a `form`) at the value.
        let at_table = message.starts_with("unknown field")
            || message.starts_with(&format!("unknown variant `{tag}`"));
        return Some(match again.span() {
            Some(at) if !at_table => at,
            _ => table.span(),
        });
    }
    None
}

/// Reads one tagged table's content as the variant its `type` names.
type ReadByTag = for<'i> fn(ByTag<'i>) -> Result<(), toml::de::Error>;

/// The tagged tables of a scene document in the order serde reads them,
/// each with its variant reader and whether it is an `[[effects]]` entry.
fn tagged_tables<'a, 'i>(doc: &'a DeTable<'i>) -> Vec<(&'a Spanned<DeValue<'i>>, ReadByTag, bool)> {
    let mut tables: Vec<(&Spanned<DeValue<'i>>, ReadByTag, bool)> = Vec::new();
    if let Some(t) = doc.get("backbone") {
        tables.push((t, |d| BackboneByTag::deserialize(d).map(drop), false));
    }
    if let Some(DeValue::Array(effects)) = doc.get("effects").map(Spanned::get_ref) {
        for t in effects.iter() {
            tables.push((t, |d| EffectByTag::deserialize(d).map(drop), true));
        }
    }
    if let Some(t) = doc.get("profile") {
        tables.push((t, |d| ProfileByTag::deserialize(d).map(drop), false));
    }
    tables
}

/// The `type` of a tagged table, if it is a table with a string `type`.
fn tag_of<'a>(table: &'a Spanned<DeValue<'_>>) -> Option<&'a str> {
    table.get_ref().get("type")?.get_ref().as_str()
}

/// A tagged table's content, without its `type`, as variant `tag`.
fn by_tag<'i>(table: &Spanned<DeValue<'i>>, tag: &str) -> ByTag<'i> {
    let mut content = match table.get_ref() {
        DeValue::Table(t) => t.clone(),
        _ => DeTable::new(),
    };
    content.remove("type");
    ByTag {
        tag: tag.to_string(),
        content: Spanned::new(table.span(), DeValue::Table(content)),
    }
}

/// A tagged table's content (its keys but `type`) presented as variant
/// `tag` of an externally tagged enum.
struct ByTag<'i> {
    tag: String,
    content: Spanned<DeValue<'i>>,
}

impl<'de> de::Deserializer<'de> for ByTag<'de> {
    type Error = toml::de::Error;

    fn deserialize_any<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Self::Error> {
        visitor.visit_enum(self)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
        bytes byte_buf option unit unit_struct newtype_struct seq tuple
        tuple_struct map struct enum identifier ignored_any
    }
}

impl<'de> de::EnumAccess<'de> for ByTag<'de> {
    type Error = toml::de::Error;
    type Variant = VariantContent<'de>;

    fn variant_seed<V: DeserializeSeed<'de>>(
        self,
        seed: V,
    ) -> Result<(V::Value, Self::Variant), Self::Error> {
        let tag = de::value::StringDeserializer::<toml::de::Error>::new(self.tag);
        Ok((seed.deserialize(tag)?, VariantContent(self.content)))
    }
}

/// The content of a variant read by [`ByTag`].
struct VariantContent<'i>(Spanned<DeValue<'i>>);

impl<'de> de::VariantAccess<'de> for VariantContent<'de> {
    type Error = toml::de::Error;

    fn unit_variant(self) -> Result<(), Self::Error> {
        Ok(())
    }

    fn newtype_variant_seed<T: DeserializeSeed<'de>>(
        self,
        seed: T,
    ) -> Result<T::Value, Self::Error> {
        seed.deserialize(ValueDeserializer::from(self.0))
    }

    fn tuple_variant<V: Visitor<'de>>(
        self,
        _len: usize,
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        de::Deserializer::deserialize_seq(ValueDeserializer::from(self.0), visitor)
    }

    fn struct_variant<V: Visitor<'de>>(
        self,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Self::Error> {
        de::Deserializer::deserialize_struct(ValueDeserializer::from(self.0), "", fields, visitor)
    }
}

/// One step of the way to a value: a key of a table or an index of an
/// array.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Step<'a> {
    Key(&'a str),
    Index(usize),
}

/// Deepest nesting [`find_value`] looks into (a scene nests four deep).
const MAX_DEPTH: usize = 32;

/// The deepest value (or key, with `None`) of a document whose span is
/// some span, and the way to it.
type Found<'a, 'i> = Option<(Vec<Step<'a>>, Option<&'a DeValue<'i>>)>;

/// Looks through `table` (at `path`) for the deepest value or key whose
/// span is `span`, into `best`.
fn find_value<'a, 'i>(
    table: &'a DeTable<'i>,
    span: &Range<usize>,
    path: &mut Vec<Step<'a>>,
    best: &mut Found<'a, 'i>,
) {
    for (key, value) in table.iter() {
        path.push(Step::Key(key.get_ref()));
        if key.span() == *span && best.as_ref().is_none_or(|(p, _)| p.len() < path.len()) {
            *best = Some((path.clone(), None));
        }
        visit_value(value, span, path, best);
        path.pop();
    }
}

fn visit_value<'a, 'i>(
    value: &'a Spanned<DeValue<'i>>,
    span: &Range<usize>,
    path: &mut Vec<Step<'a>>,
    best: &mut Found<'a, 'i>,
) {
    if value.span() == *span && best.as_ref().is_none_or(|(p, _)| p.len() < path.len()) {
        *best = Some((path.clone(), Some(value.get_ref())));
    }
    if path.len() >= MAX_DEPTH {
        return;
    }
    match value.get_ref() {
        DeValue::Table(t) => find_value(t, span, path, best),
        DeValue::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                path.push(Step::Index(i));
                visit_value(v, span, path, best);
                path.pop();
            }
        }
        _ => {}
    }
}

/// `cells[1].g` for the way `cells`, 1, `g`.
fn dotted(path: &[Step<'_>]) -> String {
    let mut s = String::new();
    for step in path {
        match step {
            Step::Key(k) if s.is_empty() => s.push_str(k),
            Step::Key(k) => {
                s.push('.');
                s.push_str(k);
            }
            Step::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// What an error message at `path` starts with: the section as the
/// parameter checks name it (`backbone: `, `profile: `,
/// `effects[0] (maxwell): `), then the key inside it (`cells[1].g: `);
/// outside those sections the dotted key (`run.rate_hz: `).
fn prefix(doc: &DeTable<'_>, path: &[Step<'_>]) -> String {
    let (section, rest) = match path {
        [] => return String::new(),
        [Step::Key("effects"), Step::Index(i), rest @ ..] => {
            let kind = doc
                .get("effects")
                .and_then(|e| e.get_ref().get(*i))
                .and_then(|e| e.get_ref().get("type"))
                .and_then(|t| t.get_ref().as_str());
            match kind {
                // Not when the kind itself is the mistake.
                Some(kind) if rest != [Step::Key("type")] => {
                    (format!("effects[{i}] ({kind})"), rest)
                }
                _ => (format!("effects[{i}]"), rest),
            }
        }
        [Step::Key(k @ ("backbone" | "profile")), rest @ ..] => ((*k).to_string(), rest),
        _ => return format!("{}: ", dotted(path)),
    };
    if rest.is_empty() {
        format!("{section}: ")
    } else {
        format!("{section}: {}: ", dotted(rest))
    }
}
