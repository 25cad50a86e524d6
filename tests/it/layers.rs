//! The house's rule, kept by a test: imports run one way. The workspace's crates are the
//! coarse layers, and Cargo keeps their order; inside them, every file belongs to a layer
//! (the table [`LAYERS`]; ARCHITECTURE.md gives it crate by crate), and a file may import
//! only from its own layer or the ones below; and no files import each other in a circle,
//! in any layer.
//! A `pub use` re-export is a door, not a use, and test code (`#[cfg(test)]` items and the
//! files they declare) may reach anywhere.
//!
//! The crates are read as one module tree, as the `arbvis` library names them ([`CRATES`]).
//! The imports are read from the text: `use` trees, and `crate::`, `super::` and `self::`
//! paths anywhere in the code, resolved to the longest module they name.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Layers from the ground up; a module takes the layer of the longest pattern matching
/// its path (`*` matches one segment).
const LAYERS: &[(&str, &[&str])] = &[
    (
        "ground: the shared vocabulary",
        &[
            "budget",
            "input",
            "vocab",
            "camera",
            "image",
            "png_io",
            "colortable",
            "progress",
            "secrets",
        ],
    ),
    (
        "data and GL",
        &[
            "le", "memory", "fetch", "sniff", "volume", "store", "mesh", "points", "surface",
            "lines", "gl",
        ],
    ),
    ("program texts", &["programs"]),
    ("what panels show of prepared data", &["summary"]),
    ("techniques", &["techniques", "error"]),
    ("the catalog of techniques", &["catalog"]),
    ("a scene's layers in one frame", &["layered"]),
    (
        "scenes and rendering",
        &["scene", "session", "render", "annotate", "inspect", "info"],
    ),
    ("studies", &["study", "techniques::*::study"]),
    ("the viewer", &["viewer"]),
    (
        "the crate root and the binary",
        &["", "main", "cli", "commands", "studies"],
    ),
];

type ModPath = Vec<String>;

fn layer_of(module: &[String]) -> Option<usize> {
    let mut best: Option<(usize, usize)> = None;
    for (layer, (_, patterns)) in LAYERS.iter().enumerate() {
        for pattern in *patterns {
            let parts: Vec<&str> = if pattern.is_empty() {
                Vec::new()
            } else {
                pattern.split("::").collect()
            };
            let matches = parts.len() <= module.len()
                && parts.iter().zip(module).all(|(p, m)| *p == "*" || p == m);
            let exact_root = parts.is_empty() && module.is_empty();
            if ((matches && !parts.is_empty()) || exact_root)
                && best.is_none_or(|(len, _)| parts.len() > len)
            {
                best = Some((parts.len(), layer));
            }
        }
    }
    best.map(|(_, layer)| layer)
}

/// The module path of a file under `src/`.
fn module_of(relative: &Path) -> ModPath {
    let mut parts: Vec<String> = relative
        .with_extension("")
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
        parts.pop();
    }
    parts
}

/// Code without comments, string and character literals (blanked, so that paths inside
/// them do not count).
fn code_only(text: &str) -> String {
    let b: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let next = b.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < b.len() && b[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == '/' && b.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == '*' && b.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
            out.push(' ');
        } else if c == 'r' && (next == Some('"') || next == Some('#')) && !ident_before(&b, i) {
            let mut j = i + 1;
            let mut hashes = 0;
            while b.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if b.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                if j >= b.len() {
                    break;
                }
                if b[j] == '"' && (0..hashes).all(|k| b.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                j += 1;
            }
            out.push_str("\"\"");
            i = j;
        } else if c == '"' {
            i += 1;
            while i < b.len() && b[i] != '"' {
                if b[i] == '\\' {
                    i += 1;
                }
                i += 1;
            }
            i += 1;
            out.push_str("\"\"");
        } else if c == '\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime ('a).
            let close = if next == Some('\\') {
                (i + 2..b.len().min(i + 12)).find(|&k| b[k] == '\'')
            } else if b.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match close {
                Some(k) => {
                    out.push_str("' '");
                    i = k + 1;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

fn ident_before(b: &[char], i: usize) -> bool {
    i > 0 && (b[i - 1].is_alphanumeric() || b[i - 1] == '_')
}

/// Remove `#[cfg(test)]` items; returns the code and the names of modules declared under
/// `#[cfg(test)]` without a body (`mod tests;`), whose files are test code.
fn without_tests(code: &str) -> (String, Vec<String>) {
    let mut out = String::new();
    let mut test_mods = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let item = &rest[at + "#[cfg(test)]".len()..];
        let brace = item.find('{');
        let semi = item.find(';');
        let end = match (brace, semi) {
            (Some(b), Some(s)) if s < b => {
                let decl = item[..s].trim();
                if let Some(name) = decl.strip_prefix("mod ") {
                    test_mods.push(name.trim().to_string());
                }
                s + 1
            }
            (Some(b), _) => {
                let mut depth = 0;
                let mut end = item.len();
                for (k, ch) in item[b..].char_indices() {
                    match ch {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = b + k + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                end
            }
            (None, Some(s)) => s + 1,
            (None, None) => item.len(),
        };
        rest = &item[end..];
    }
    out.push_str(rest);
    (out, test_mods)
}

/// Expand a `use` tree (`a::{b, c::{d, e}}`) into paths.
fn expand(prefix: &[String], tree: &str, out: &mut Vec<ModPath>) {
    let tree = tree.trim();
    if let Some(open) = tree.find('{') {
        let head: Vec<String> = tree[..open]
            .split("::")
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect();
        let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
        let base: Vec<String> = prefix.iter().cloned().chain(head).collect();
        let mut depth = 0;
        let mut start = 0;
        for (k, ch) in inner.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand(&base, &inner[start..k], out);
                    start = k + 1;
                }
                _ => {}
            }
        }
        expand(&base, &inner[start..], out);
    } else if !tree.is_empty() {
        let path = tree.split(" as ").next().unwrap_or("").trim();
        let mut p: ModPath = prefix.to_vec();
        p.extend(path.split("::").map(|s| s.trim().to_string()));
        out.push(p);
    }
}

/// The paths a file's code names.
fn paths_in(code: &str) -> Vec<ModPath> {
    let mut out = Vec::new();
    let mut code_without_uses = String::new();
    let mut rest = code;
    // `use` statements (a `pub use` is a re-export: skipped).
    while let Some(at) = find_word(rest, "use") {
        let before = rest[..at].trim_end();
        let is_reexport = before.ends_with("pub") || before.ends_with(')');
        let end = rest[at..].find(';').map_or(rest.len(), |e| at + e + 1);
        code_without_uses.push_str(&rest[..at]);
        if !is_reexport {
            expand(&[], &rest[at + 3..end - 1], &mut out);
        }
        rest = &rest[end..];
    }
    code_without_uses.push_str(rest);
    // Paths written in the code.
    let b = code_without_uses.as_bytes();
    for start in ["crate::", "super::", "self::"] {
        let mut from = 0;
        while let Some(k) = code_without_uses[from..].find(start) {
            let at = from + k;
            from = at + start.len();
            if at > 0
                && (b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_' || b[at - 1] == b':')
            {
                continue;
            }
            let end = code_without_uses[at..]
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .map_or(code_without_uses.len(), |e| at + e);
            let path: ModPath = code_without_uses[at..end]
                .split("::")
                .filter(|s| !s.is_empty())
                .map(String::from)
                .collect();
            out.push(path);
        }
    }
    out
}

fn find_word(text: &str, word: &str) -> Option<usize> {
    let b = text.as_bytes();
    let mut from = 0;
    while let Some(k) = text[from..].find(word) {
        let at = from + k;
        let before_ok = at == 0 || !(b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_');
        let after = b.get(at + word.len()).copied();
        if before_ok && after.is_some_and(|c| c.is_ascii_whitespace()) {
            return Some(at);
        }
        from = at + word.len();
    }
    None
}

/// Resolve a written path to a module of the crate, from module `me`.
fn resolve(me: &[String], path: &[String], modules: &BTreeSet<ModPath>) -> Option<ModPath> {
    let mut full: ModPath;
    let mut rest = path;
    match path.first().map(String::as_str) {
        Some("crate") => {
            full = Vec::new();
            rest = &path[1..];
        }
        Some("super") | Some("self") => {
            full = me.to_vec();
            while let Some(first) = rest.first() {
                match first.as_str() {
                    "super" => {
                        full.pop();
                    }
                    "self" => {}
                    _ => break,
                }
                rest = &rest[1..];
            }
        }
        Some(first) => {
            // A child module named without `self::` (2018 paths).
            let mut child = me.to_vec();
            child.push(first.to_string());
            if !modules.contains(&child) {
                return None;
            }
            full = me.to_vec();
        }
        None => return None,
    }
    full.extend(rest.iter().cloned());
    (0..=full.len())
        .rev()
        .map(|k| full[..k].to_vec())
        .find(|m| modules.contains(m))
}

struct Graph {
    /// Module to the modules it imports, with the file holding the module.
    edges: BTreeMap<ModPath, BTreeSet<ModPath>>,
    files: BTreeMap<ModPath, String>,
}

/// The workspace's crates as one module tree: each crate's folder of sources and the
/// module its root stands for (`None`: its modules sit at the top, as `arbvis` names them).
/// A crate's `lib.rs` other than a module's own only declares its modules (Cargo.toml keeps
/// the crates' order), so it is not read.
const CRATES: [(&str, Option<&str>); 6] = [
    ("src", None),
    ("crates/arbvis-core/src", None),
    ("crates/arbvis-gl/src", Some("gl")),
    ("crates/arbvis-data/src", None),
    ("crates/arbvis-techniques/src", None),
    ("crates/arbvis-viewer/src", Some("viewer")),
];

/// A file's text with its paths written as in one crate: `crate::` inside a crate that is a
/// module (`gl`, `viewer`) gains that module, and the crates below (each named where it is
/// used, never re-exported as a crate's own module) are named as `crate::`.
fn as_one_crate(text: &str, own: Option<&str>) -> String {
    let mut text = text.to_string();
    if let Some(own) = own {
        let mut out = String::with_capacity(text.len());
        let mut rest = text.as_str();
        while let Some(at) = rest.find("crate::") {
            out.push_str(&rest[..at + "crate::".len()]);
            rest = &rest[at + "crate::".len()..];
            out.push_str(own);
            out.push_str("::");
        }
        out.push_str(rest);
        text = out;
    }
    for (name, module) in [
        ("arbvis_core::", "crate::"),
        ("arbvis_data::", "crate::"),
        ("arbvis_techniques::", "crate::"),
        ("arbvis_gl::", "crate::gl::"),
        ("arbvis_viewer::", "crate::viewer::"),
    ] {
        text = text.replace(name, module);
    }
    text
}

fn read_graph() -> Graph {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut sources = BTreeMap::new();
    for (folder, own) in CRATES {
        let src = root.join(folder);
        let mut stack = vec![src.clone()];
        while let Some(dir) = stack.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    stack.push(path);
                } else if path.extension().is_some_and(|e| e == "rs") {
                    let rel = path.strip_prefix(&src).unwrap().to_path_buf();
                    let is_root = rel == Path::new("lib.rs");
                    if is_root && own.is_none() && folder != "src" {
                        continue;
                    }
                    let mut module: ModPath = own.iter().map(|m| m.to_string()).collect();
                    module.extend(module_of(&rel));
                    let text = as_one_crate(&std::fs::read_to_string(&path).unwrap(), own);
                    let file = Path::new(folder).join(&rel).display().to_string();
                    assert!(
                        sources.insert(module.clone(), (file, text)).is_none(),
                        "two files are module {module:?}"
                    );
                }
            }
        }
    }
    // Files declared by `#[cfg(test)] mod NAME;` are test code.
    let mut test_only = BTreeSet::new();
    let mut cleaned = BTreeMap::new();
    for (module, (file, text)) in &sources {
        let (code, test_mods) = without_tests(&code_only(text));
        for name in test_mods {
            let mut m = module.clone();
            m.push(name);
            test_only.insert(m);
        }
        cleaned.insert(module.clone(), (file.clone(), code));
    }
    let is_test = |m: &ModPath| (1..=m.len()).any(|k| test_only.contains(&m[..k]));
    let modules: BTreeSet<ModPath> = cleaned.keys().cloned().collect();
    let mut edges = BTreeMap::new();
    let mut files = BTreeMap::new();
    for (module, (file, code)) in &cleaned {
        if is_test(module) {
            continue;
        }
        let targets: BTreeSet<ModPath> = paths_in(code)
            .iter()
            .filter_map(|p| resolve(module, p, &modules))
            .filter(|t| t != module && !t.is_empty() && !is_test(t))
            .collect();
        edges.insert(module.clone(), targets);
        files.insert(module.clone(), file.clone());
    }
    Graph { edges, files }
}

fn name(m: &ModPath) -> String {
    if m.is_empty() {
        "crate".into()
    } else {
        m.join("::")
    }
}

#[test]
fn every_file_has_a_layer_and_imports_only_downward() {
    let g = read_graph();
    let mut problems = Vec::new();
    for (module, targets) in &g.edges {
        let Some(mine) = layer_of(module) else {
            problems.push(format!(
                "{} ({}) has no layer: add it to LAYERS in tests/it/layers.rs and to its crate in ARCHITECTURE.md",
                name(module),
                g.files[module]
            ));
            continue;
        };
        for t in targets {
            if let Some(theirs) = layer_of(t) {
                if theirs > mine {
                    problems.push(format!(
                        "{} ({}, layer \"{}\") imports {} from the layer above, \"{}\"",
                        name(module),
                        g.files[module],
                        LAYERS[mine].0,
                        name(t),
                        LAYERS[theirs].0
                    ));
                }
            }
        }
    }
    assert!(problems.is_empty(), "\n{}", problems.join("\n"));
}

#[test]
fn no_files_import_each_other_in_a_circle() {
    let g = read_graph();
    let mut circles = Vec::new();
    // Tarjan's strongly connected components.
    struct State<'a> {
        g: &'a Graph,
        index: BTreeMap<ModPath, usize>,
        low: BTreeMap<ModPath, usize>,
        stack: Vec<ModPath>,
        on: BTreeSet<ModPath>,
        next: usize,
        found: Vec<Vec<ModPath>>,
    }
    fn visit(s: &mut State, v: &ModPath) {
        s.index.insert(v.clone(), s.next);
        s.low.insert(v.clone(), s.next);
        s.next += 1;
        s.stack.push(v.clone());
        s.on.insert(v.clone());
        for w in s.g.edges.get(v).into_iter().flatten() {
            if !s.g.edges.contains_key(w) {
                continue;
            }
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if s.on.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on.remove(&w);
                let done = &w == v;
                component.push(w);
                if done {
                    break;
                }
            }
            if component.len() > 1 {
                s.found.push(component);
            }
        }
    }
    let mut s = State {
        g: &g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        next: 0,
        found: Vec::new(),
    };
    for v in g.edges.keys() {
        if !s.index.contains_key(v) {
            visit(&mut s, v);
        }
    }
    for component in s.found {
        let mut files: Vec<String> = component.iter().map(|m| g.files[m].clone()).collect();
        files.sort();
        circles.push(format!(
            "{} files import each other in a circle: {}",
            files.len(),
            files.join(", ")
        ));
    }
    assert!(circles.is_empty(), "\n{}", circles.join("\n"));
}

#[test]
fn the_reader_sees_the_imports_it_must() {
    // The checks above are only as good as the reading: a few facts of this crate that
    // the reader must find, so a parser slip cannot make both tests pass vacuously.
    let g = read_graph();
    let m = |s: &str| -> ModPath { s.split("::").map(String::from).collect() };
    let has = |a: &str, b: &str| g.edges.get(&m(a)).is_some_and(|t| t.contains(&m(b)));
    assert!(has("render", "scene"), "render uses the scene");
    assert!(
        has("scene", "catalog"),
        "the scene holds the catalog's TechniqueScene"
    );
    assert!(has("techniques::cellproj::renderer", "gl"));
    assert!(has(
        "techniques::cellproj::renderer",
        "techniques::cellproj::prepare"
    ));
    assert!(g.edges.len() > 100, "{} files read", g.edges.len());
    // Test code is left out: opacity3d's unit tests read the demo scenes.
    assert!(!has("techniques::opacity3d", "scene"));
    // Re-exports are not uses.
    let (code, tests) = without_tests(&code_only(
        "pub use a::b;\n#[cfg(test)]\nmod tests;\nuse crate::x::{y, z::{w}};\n#[cfg(test)]\nmod t { use crate::q; }\nfn f() { crate::r::s(); let s = \"crate::no\"; }",
    ));
    assert_eq!(tests, vec!["tests".to_string()]);
    let paths: Vec<String> = paths_in(&code).iter().map(|p| p.join("::")).collect();
    assert_eq!(paths, ["crate::x::y", "crate::x::z::w", "crate::r::s"]);
    assert_eq!(
        layer_of(&m("techniques::splats::study")),
        layer_of(&m("study"))
    );
    assert_eq!(
        layer_of(&m("techniques::splats::sort")),
        layer_of(&m("techniques"))
    );
}

/// No crate below the command line names a lower crate's module as its own
/// (`use arbvis_core::{budget, ...}` in its root made `crate::budget` another crate's
/// module, which neither a reader nor this graph could tell): each file names the crate.
#[test]
fn crates_name_the_crates_below_where_they_use_them() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (folder, _) in &CRATES[1..] {
        let lib = root.join(folder).join("lib.rs");
        let text = std::fs::read_to_string(&lib).unwrap();
        let aliases: Vec<&str> = text
            .lines()
            .filter(|l| {
                let l = l.trim_start_matches("pub ");
                l.starts_with("use arbvis_") && (l.contains("::{") || l.contains(" as "))
            })
            .collect();
        assert!(aliases.is_empty(), "{}: {aliases:?}", lib.display());
    }
}
