//! Tables whose `type` key names their variant, read twice: once as serde
//! reads an internally tagged enum, and once by tag, so that a mistake
//! inside one can be reported at the value rather than at the table.

/// Declares a table whose variant its `type` key names
/// (`#[serde(tag = "type")]`), and beside it the same variants read
/// externally tagged: `$by_tag::deserialize` (a serde `remote` of the enum)
/// reads a table's content, without its `type`, as the variant `type`
/// names. Serde reads a tagged table through a buffer that forgets where
/// each value was, so a wrong value inside one is reported at the table;
/// read again by [`tagged_mistake`], the same mistake points at the value.
macro_rules! tagged_table {
    (
        $(#[$meta:meta])*
        pub enum $name:ident, read by tag as $by_tag:ident($remote:literal) $body:tt
    ) => {
        $(#[$meta])*
        #[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
        pub enum $name $body

        #[derive(Deserialize)]
        #[serde(remote = $remote, rename_all = "kebab-case", deny_unknown_fields)]
        #[allow(dead_code)] // never built: its `deserialize` builds the public enum
        pub(crate) enum $by_tag $body
    };
}
