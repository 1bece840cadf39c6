//! No two modules import each other, in any crate of the workspace.
//!
//! Module A imports module B when A's own code names a path into B, through
//! `crate::`, `super::`, `self::`, a `use` tree, or a name that a `use` (or
//! a glob `use` of a module) bound to a module, and B is neither A nor one
//! of A's descendants: a parent using its own children is how a module is
//! built from parts. Each path is resolved to the deepest module it names
//! (`crate::tracker::fast::clamp` is a reference into `tracker::fast`).
//! The test builds that graph for every crate root of every workspace crate
//! (library, binaries, integration tests, benches, fuzz targets), finds its
//! strongly connected components and fails listing each one of more than
//! one module with the import lines that close it: two modules that import
//! each other, and longer rings A → B → C → A alike.
//!
//! The scanner is written by hand: no crate kept for this workspace gives a
//! module graph (the tools that do, such as `cargo-modules`, need a
//! rust-analyzer build far heavier than this check). It reads tokens, not
//! syntax: comments and literals are skipped, `mod` declarations are
//! followed from each crate root (`a/b.rs` and `a/b/mod.rs` are `a::b`),
//! inline `mod x { .. }` blocks are modules of their own, and names that
//! only a macro or a glob import of items brings into scope are not
//! followed.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// The crates scanned, relative to the workspace root: the workspace's
/// `members` and the fuzz crate, which is a workspace of its own.
fn crates(workspace: &Path) -> Vec<String> {
    let manifest = fs::read_to_string(workspace.join("Cargo.toml")).unwrap();
    let start = manifest.find("members = [").expect("workspace members");
    let list = &manifest[start..];
    let list = &list[..list.find(']').expect("end of the members list")];
    let mut crates: Vec<String> = list
        .split('"')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect();
    assert!(
        crates.len() >= 4,
        "members read from Cargo.toml: {crates:?}"
    );
    crates.push("fuzz".into());
    crates
}
/// Directories (relative to a crate) whose `.rs` files are crate roots.
const ROOT_DIRS: &[&str] = &["src/bin", "tests", "benches", "examples", "fuzz_targets"];

/// A module path below the crate root (empty for the root).
type Module = Vec<String>;

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    PathSep,
    Punct(char),
}

/// Tokens with their line numbers; comments, strings and chars dropped.
fn lex(text: &str) -> Vec<(Tok, usize)> {
    let c: Vec<char> = text.chars().collect();
    let at = |i: usize| c.get(i).copied().unwrap_or('\0');
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    let (mut out, mut i, mut line) = (Vec::new(), 0, 1);
    // Skips to just past the closing `"` (raw: followed by `hashes` `#`).
    let string_end = |mut i: usize, raw: bool, hashes: usize, line: &mut usize| {
        while i < c.len() {
            match c[i] {
                '\\' if !raw => {
                    i += 1;
                    *line += usize::from(at(i) == '\n');
                }
                '\n' => *line += 1,
                '"' if (1..=hashes).all(|k| at(i + k) == '#') => return i + 1 + hashes,
                _ => {}
            }
            i += 1;
        }
        i
    };
    while i < c.len() {
        let ch = c[i];
        if ch == '/' && at(i + 1) == '/' {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && at(i + 1) == '*' {
            let (mut depth, mut j) = (1, i + 2);
            while j < c.len() && depth > 0 {
                match (c[j], at(j + 1)) {
                    ('/', '*') => (depth, j) = (depth + 1, j + 1),
                    ('*', '/') => (depth, j) = (depth - 1, j + 1),
                    ('\n', _) => line += 1,
                    _ => {}
                }
                j += 1;
            }
            i = j;
        } else if ch == '"' {
            i = string_end(i + 1, false, 0, &mut line);
        } else if ch == '\'' {
            // A char literal, or a lifetime (then only the quote is skipped).
            i += match (at(i + 1), at(i + 2)) {
                ('\\', _) => 4 + (i + 3..c.len()).position(|j| c[j] == '\'').unwrap_or(0),
                (_, '\'') => 3,
                _ => 1,
            };
        } else if ident(ch) {
            let start = i;
            while ident(at(i)) {
                i += 1;
            }
            let word: String = c[start..i].iter().collect();
            let hashes = (i..).take_while(|&j| at(j) == '#').count();
            if matches!(word.as_str(), "r" | "br" | "cr") && at(i + hashes) == '"' {
                i = string_end(i + hashes + 1, true, hashes, &mut line);
            } else if matches!(word.as_str(), "b" | "c") && at(i) == '"' {
                i = string_end(i + 1, false, 0, &mut line);
            } else if !ch.is_ascii_digit() {
                out.push((Tok::Ident(word), line));
            }
        } else if ch == ':' && at(i + 1) == ':' {
            out.push((Tok::PathSep, line));
            i += 2;
        } else {
            if ch == '\n' {
                line += 1;
            } else if !ch.is_whitespace() {
                out.push((Tok::Punct(ch), line));
            }
            i += 1;
        }
    }
    out
}

/// A leaf of a `use` tree: whether it is a glob, and the name it binds.
type Leaf = (bool, Option<String>);

/// A path named in module `from` at `line`; `leaf` for a `use`.
#[derive(Debug)]
struct Named {
    from: Module,
    path: Vec<String>,
    line: usize,
    leaf: Option<Leaf>,
}

/// What one file declares and names.
#[derive(Debug, Default)]
struct Parsed {
    /// Inline `mod x { .. }` modules.
    inline: Vec<Module>,
    /// `mod x;` declarations: the declaring module and x.
    declared: Vec<(Module, String)>,
    named: Vec<Named>,
}

fn parse(text: &str, module: &Module) -> Parsed {
    let toks = lex(text);
    let tok = |i: usize| toks.get(i).map(|t| &t.0);
    let word = |i: usize| match tok(i) {
        Some(Tok::Ident(w)) => w.as_str(),
        _ => "",
    };
    let mut parsed = Parsed::default();
    // Enclosing modules and the brace depth at which each opened.
    let (mut scopes, mut depth, mut i) = (vec![(module.clone(), 0)], 0, 0);
    while i < toks.len() {
        let (here, line) = (
            scopes.last().map(|s| s.0.clone()).unwrap_or_default(),
            toks[i].1,
        );
        let named = |path, leaf| Named {
            from: here.clone(),
            path,
            line,
            leaf,
        };
        match (&toks[i].0, word(i + 1), tok(i + 2)) {
            (Tok::Punct('{'), ..) => depth += 1,
            (Tok::Punct('}'), ..) => {
                if scopes.len() > 1 && scopes.last().is_some_and(|s| s.1 == depth) {
                    scopes.pop();
                }
                depth -= 1;
            }
            (Tok::Ident(w), name, Some(Tok::Punct('{'))) if w == "mod" && !name.is_empty() => {
                let inner = [here.clone(), vec![name.to_string()]].concat();
                parsed.inline.push(inner.clone());
                depth += 1;
                scopes.push((inner, depth));
                i += 2;
            }
            (Tok::Ident(w), name, Some(Tok::Punct(';'))) if w == "mod" && !name.is_empty() => {
                parsed.declared.push((here.clone(), name.to_string()));
            }
            (Tok::Ident(w), ..) if w == "use" => {
                let mut leaves = Vec::new();
                i = use_tree(&toks, i + 1, Vec::new(), &mut leaves) - 1;
                let leaves = leaves
                    .into_iter()
                    .map(|(path, leaf)| named(path, Some(leaf)));
                parsed.named.extend(leaves);
            }
            // A path's head (not its tail, not `$crate`, not `pub(in path)`).
            (Tok::Ident(w), ..)
                if tok(i + 1) == Some(&Tok::PathSep)
                    && !matches!(
                        i.checked_sub(1).map(tok),
                        Some(Some(Tok::PathSep | Tok::Punct('$')))
                    )
                    && !(i >= 2 && word(i - 1) == "in" && tok(i - 2) == Some(&Tok::Punct('('))) =>
            {
                let mut path = vec![w.clone()];
                while tok(i + 1) == Some(&Tok::PathSep) && !word(i + 2).is_empty() {
                    path.push(word(i + 2).to_string());
                    i += 2;
                }
                parsed.named.push(named(path, None));
            }
            _ => {}
        }
        i += 1;
    }
    parsed
}

/// Flattens the `use` tree at `i` into `(path, leaf)`; returns the index
/// past it.
fn use_tree(
    toks: &[(Tok, usize)],
    mut i: usize,
    mut prefix: Vec<String>,
    out: &mut Vec<(Vec<String>, Leaf)>,
) -> usize {
    let at = |i: usize| toks.get(i).map(|t| &t.0);
    while let Some(t) = at(i) {
        match t {
            Tok::PathSep => i += 1,
            Tok::Punct('{') => {
                i += 1;
                while !matches!(at(i), None | Some(Tok::Punct('}'))) {
                    i = use_tree(toks, i, prefix.clone(), out);
                    i += usize::from(at(i) == Some(&Tok::Punct(',')));
                }
                return i + 1;
            }
            Tok::Punct('*') => {
                out.push((prefix, (true, None)));
                return i + 1;
            }
            Tok::Ident(w) if at(i + 1) == Some(&Tok::PathSep) => {
                prefix.push(w.clone());
                i += 1;
            }
            Tok::Ident(w) => {
                prefix.push(w.clone());
                let alias = match (at(i + 1), at(i + 2)) {
                    (Some(Tok::Ident(kw)), Some(Tok::Ident(a))) if kw == "as" => Some(a),
                    _ => None,
                };
                i += if alias.is_some() { 3 } else { 1 };
                out.push((prefix, (false, alias.cloned())));
                return i;
            }
            _ => return i + 1,
        }
    }
    i
}

/// One source file of a crate target.
struct Source {
    module: Module,
    file: String,
    text: String,
}

/// Reads the crate rooted at `root`, following its `mod` declarations;
/// file names are given relative to `base`.
fn load(root: &Path, base: &Path) -> Result<Vec<Source>, String> {
    let mut queue = vec![(root.to_path_buf(), Module::new(), root.with_file_name(""))];
    let mut sources = Vec::new();
    while let Some((path, module, dir)) = queue.pop() {
        let text = fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        for (parent, name) in parse(&text, &module).declared {
            let sub = parent[module.len()..]
                .iter()
                .fold(dir.clone(), |d, s| d.join(s));
            let files = [
                sub.join(format!("{name}.rs")),
                sub.join(&name).join("mod.rs"),
            ];
            let Some(file) = files.into_iter().find(|p| p.is_file()) else {
                return Err(format!("{}: no file for `mod {name};`", path.display()));
            };
            queue.push((file, [parent, vec![name.clone()]].concat(), sub.join(&name)));
        }
        let file = path
            .strip_prefix(base)
            .unwrap_or(&path)
            .display()
            .to_string();
        sources.push(Source { module, file, text });
    }
    Ok(sources)
}

/// Module → imported module → where (the first import line).
type Graph = BTreeMap<Module, BTreeMap<Module, String>>;

fn graph(sources: &[Source]) -> Graph {
    let parsed: Vec<_> = sources
        .iter()
        .map(|s| (s, parse(&s.text, &s.module)))
        .collect();
    let mut modules: BTreeSet<Module> = sources.iter().map(|s| s.module.clone()).collect();
    modules.extend(parsed.iter().flat_map(|(_, p)| p.inline.iter().cloned()));
    // Walks `rest` down from `here` while the modules exist; true when
    // every segment was one.
    let descend = |mut here: Module, rest: &[String]| {
        for (k, seg) in rest.iter().enumerate() {
            let next = [here.clone(), vec![seg.clone()]].concat();
            match seg.as_str() {
                "self" => {}
                "super" if rest[..k].iter().all(|s| s == "super") => {
                    here.pop();
                }
                _ if modules.contains(&next) => here = next,
                _ => return (here, false),
            }
        }
        (here, true)
    };
    // Names that `use` bound to modules: aliases, and glob-imported modules.
    let mut aliases: BTreeMap<(Module, String), Module> = BTreeMap::new();
    let mut globs: BTreeMap<Module, Vec<Module>> = BTreeMap::new();
    let mut edges = Graph::new();
    // The `use` declarations first, so that the paths see their names.
    for uses in [true, false] {
        for (source, n) in parsed
            .iter()
            .flat_map(|(s, p)| p.named.iter().map(move |n| (s, n)))
        {
            if n.leaf.is_some() != uses {
                continue;
            }
            let first = n.path.first().cloned().unwrap_or_default();
            let child = |m: &Module| {
                let child = [m.clone(), vec![first.clone()]].concat();
                modules.contains(&child).then_some(child)
            };
            let (start, rest) = match first.as_str() {
                "crate" => (Some(Module::new()), &n.path[1..]),
                "self" | "super" => (Some(n.from.clone()), &n.path[..]),
                _ => {
                    let alias = aliases.get(&(n.from.clone(), first.clone())).cloned();
                    let glob = || globs.get(&n.from).into_iter().flatten().find_map(child);
                    (alias.or_else(|| child(&n.from)).or_else(glob), &n.path[1..])
                }
            };
            let Some(start) = start else { continue };
            let (target, whole) = descend(start, rest);
            match &n.leaf {
                Some((true, _)) if whole => globs
                    .entry(n.from.clone())
                    .or_default()
                    .push(target.clone()),
                Some((false, alias)) if whole => {
                    let name = alias
                        .clone()
                        .or_else(|| target.last().cloned())
                        .unwrap_or_default();
                    aliases.insert((n.from.clone(), name), target.clone());
                }
                _ => {}
            }
            if !target.starts_with(&n.from) {
                let at = format!("{}:{}", source.file, n.line);
                edges
                    .entry(n.from.clone())
                    .or_default()
                    .entry(target)
                    .or_insert(at);
            }
        }
    }
    edges
}

/// Strongly connected components of more than one module (Tarjan).
fn cycles(g: &Graph) -> Vec<Vec<Module>> {
    struct Walk<'a> {
        g: &'a Graph,
        /// Visit order and lowest order reachable, per module.
        index: BTreeMap<&'a Module, (usize, usize)>,
        stack: Vec<&'a Module>,
        found: Vec<Vec<Module>>,
    }
    fn visit<'a>(w: &mut Walk<'a>, v: &'a Module) {
        let (n, g) = (w.index.len(), w.g);
        w.index.insert(v, (n, n));
        w.stack.push(v);
        for u in g.get(v).into_iter().flat_map(|e| e.keys()) {
            let low = match w.index.get(u) {
                None => {
                    visit(w, u);
                    w.index[u].1
                }
                Some(&(k, _)) if w.stack.contains(&u) => k,
                Some(_) => continue,
            };
            let entry = w.index.get_mut(v).expect("visited");
            entry.1 = entry.1.min(low);
        }
        if w.index[v].0 == w.index[v].1 {
            let at = w.stack.iter().rposition(|m| *m == v).unwrap_or(0);
            let ring: Vec<Module> = w.stack.drain(at..).cloned().collect();
            if ring.len() > 1 {
                w.found.push(ring);
            }
        }
    }
    let mut w = Walk {
        g,
        index: BTreeMap::new(),
        stack: Vec::new(),
        found: Vec::new(),
    };
    for v in g.keys() {
        if !w.index.contains_key(v) {
            visit(&mut w, v);
        }
    }
    w.found
}

fn name(m: &Module) -> String {
    if m.is_empty() {
        "crate".into()
    } else {
        m.join("::")
    }
}

/// The report of one crate target's cycles, empty when there is none.
fn report(target: &str, g: &Graph) -> String {
    let mut out = String::new();
    for mut ring in cycles(g) {
        ring.sort();
        let names: Vec<String> = ring.iter().map(name).collect();
        out += &format!("{target}: import cycle among {}\n", names.join(", "));
        for a in &ring {
            for (b, at) in g[a].iter().filter(|(b, _)| ring.contains(*b)) {
                let mutual = g.get(b).is_some_and(|e| e.contains_key(a));
                let tag = if mutual { "  (mutual)" } else { "" };
                out += &format!("    {} -> {} at {at}{tag}\n", name(a), name(b));
            }
        }
    }
    out
}

/// Every `.rs` file below `dir`.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let entries = fs::read_dir(dir).into_iter().flatten().flatten();
    let (dirs, files): (Vec<PathBuf>, Vec<PathBuf>) =
        entries.map(|e| e.path()).partition(|p| p.is_dir());
    let rust = files
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "rs"));
    rust.chain(dirs.into_iter().flat_map(|d| rust_files(&d)))
        .collect()
}

#[test]
fn no_two_modules_import_each_other() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let (mut failures, mut targets) = (String::new(), 0);
    for krate in crates(&workspace) {
        let dir = workspace.join(&krate);
        let mut roots = vec![dir.join("src/lib.rs"), dir.join("src/main.rs")];
        for sub in ROOT_DIRS {
            let entries = fs::read_dir(dir.join(sub)).into_iter().flatten().flatten();
            let paths = entries.map(|e| e.path());
            roots.extend(paths.map(|p| if p.is_dir() { p.join("main.rs") } else { p }));
        }
        let mut reached = BTreeSet::new();
        for root in roots
            .iter()
            .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "rs"))
        {
            let target = root
                .strip_prefix(&workspace)
                .unwrap_or(root)
                .display()
                .to_string();
            match load(root, &dir) {
                Ok(sources) => {
                    failures += &report(&target, &graph(&sources));
                    reached.extend(sources.iter().map(|s| dir.join(&s.file)));
                }
                Err(e) => failures += &format!("{target}: {e}\n"),
            }
            targets += 1;
        }
        // A file that no root reaches is a module the graph never saw.
        for file in rust_files(&dir.join("src"))
            .iter()
            .filter(|f| !reached.contains(*f))
        {
            failures += &format!(
                "{krate}: {} is reached from no crate root\n",
                file.display()
            );
        }
    }
    println!("{targets} crate roots scanned");
    assert!(
        failures.is_empty(),
        "modules that import each other:\n{failures}"
    );
}

fn m(path: &str) -> Module {
    path.split("::")
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect()
}

/// The graph of sources given as `(module path, text)`.
fn graph_of(files: &[(&str, &str)]) -> Graph {
    let source = |(path, text): &(&str, &str)| Source {
        module: m(path),
        file: format!("{path}.rs"),
        text: text.to_string(),
    };
    graph(&files.iter().map(source).collect::<Vec<_>>())
}

fn rings(g: &Graph) -> Vec<Vec<Module>> {
    let sorted = |mut ring: Vec<Module>| {
        ring.sort();
        ring
    };
    cycles(g).into_iter().map(sorted).collect()
}

#[test]
fn comments_strings_and_chars_name_nothing() {
    let text = "// crate::b\n/* crate::b /* nested */ crate::b */ let s = \"crate::b\";\n\
                let r = r#\"crate::b\"#; let c = '\"'; fn f<'a>(x: &'a str) { crate::g::h(); }";
    let g_at: Vec<_> = lex(text)
        .into_iter()
        .filter(|t| t.0 == Tok::Ident("g".into()))
        .collect();
    assert_eq!(g_at, [(Tok::Ident("g".into()), 3)]);
    let g = graph_of(&[("", "mod a; mod b;"), ("a", text), ("b", "")]);
    assert_eq!(g[&m("a")].keys().collect::<Vec<_>>(), [&m("")]);
}

#[test]
fn use_groups_resolve_to_the_deepest_module() {
    let g = graph_of(&[
        ("", "mod a; mod b;"),
        ("a", "use crate::b::{c::{self, X}, d::Y as Z, e};"),
        ("b", "pub mod c {} mod d; fn e() {}"),
        ("b::d", ""),
    ]);
    assert_eq!(
        g[&m("a")].keys().collect::<Vec<_>>(),
        [&m("b"), &m("b::c"), &m("b::d")]
    );
}

#[test]
fn parents_may_use_children_but_a_mutual_pair_is_found() {
    let g = graph_of(&[
        ("", "mod a; mod b; use a::x; fn f() { crate::a::y(); }"),
        ("a", "use super::b::z;"),
        ("b", "fn t() { super::a::x(); }"),
    ]);
    assert!(
        !g.contains_key(&m("")),
        "a parent using its children imports nothing"
    );
    assert_eq!(rings(&g), [[m("a"), m("b")]]);
    let text = report("demo", &g);
    assert!(text.contains("a -> b at a.rs:1  (mutual)"), "{text}");
    assert!(text.contains("b -> a at b.rs:1  (mutual)"), "{text}");
}

#[test]
fn a_ring_through_globs_aliases_and_inline_modules_is_found() {
    let g = graph_of(&[
        ("", "mod a; mod b; mod c;"),
        ("a", "use super::*; fn f() { b::g(); }"),
        ("b", "use crate::c; fn g() { c::inner::h(); }"),
        ("c", "mod inner { pub fn h() { crate::a::f(); } }"),
    ]);
    assert_eq!(g[&m("a")].keys().collect::<Vec<_>>(), [&m(""), &m("b")]);
    assert_eq!(
        g[&m("b")].keys().collect::<Vec<_>>(),
        [&m("c"), &m("c::inner")]
    );
    assert_eq!(rings(&g), [[m("a"), m("b"), m("c::inner")]]);
    assert!(!report("demo", &g).contains("(mutual)"));
}
