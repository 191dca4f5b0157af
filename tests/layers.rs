//! The module layers (ARCHITECTURE.md, "Layers"): every file under `src/` belongs to the top-level module it
//! sits in, and may name through `crate::` only its own module and modules of a lower rank. Modules of the
//! same rank are independent of each other. The check reads the source text: `crate::` paths in code
//! (`use` lines and inline paths, grouped `crate::{a, b}` too), not in comments or string literals.
//! `super::` paths stay inside a module, and `src/main.rs` is a separate crate, so neither is checked for
//! ranks. A second check forbids circles of imports between files (below, "Import circles between files").

use std::fs;
use std::path::{Path, PathBuf};

/// Every top-level module of the library and its rank, lowest first. A module may import modules of a lower
/// rank; a top-level module missing from the table fails the test, so a new one gets a place here.
const LAYERS: &[(&str, u32)] = &[
    // Numbers: Real, V3, Affine, Rgb, SplitMix64.
    ("math", 0),
    // Lane types over math.
    ("simd", 1),
    // Rays, packets and the intersection kernels the kinds share (the ray/sphere kernel among them).
    ("geometry", 2),
    // The generic tree: boxes and item ranges, its walks over a leaf-query trait, the probes that count them.
    ("bvh", 3),
    // The image buffer.
    ("film", 3),
    // The primitive kinds of the registry, one folder each, and the list of them.
    ("kinds", 4),
    // The scene's geometry over the kinds (Geometry) and the packet queries over it.
    ("accel", 5),
    // The plain scene description (SceneDesc).
    ("scene", 5),
    // The camera from its description: frames and rays.
    ("camera", 6),
    // Sample offsets and the postfilter on a film.
    ("sample", 6),
    // Readers and generators: files and parameters into a SceneDesc (they build a Camera to validate it).
    ("io", 7),
    // The compiled runtime Scene and what it uses.
    ("compile", 8),
    // Changes to a description's settings (the command line's and the Python module's) and their names.
    ("settings", 8),
    // Whitted shading over the queries.
    ("shade", 9),
    // Image files from a film.
    ("output", 9),
    // Tiles, packets, threads: the renderer.
    ("render", 10),
    // Tools over the renderer and images.
    ("aov", 11),
    ("accuracy", 11),
    ("imagediff", 11),
    // Run time against error, over the renderer and the accuracy twin.
    ("converge", 12),
    // Renders timed, repeated and split by ray kind (`bareray bench`'s measurements).
    ("bench", 12),
    // Stills of any size: bands streamed into files, pre-checks, regions and their merge.
    ("still", 12),
    // Whole renders in memory for programs and bindings: arrays or a file in, an image out; its bench is
    // `bench`'s measurement. The command line does not use it.
    ("api", 13),
    // The binary crate (declared by src/main.rs; the library is `bareray::` there, which this check does not
    // rank): the platform pieces it starts with, and the command line over them.
    ("cpu", 14),
    ("huge_pages", 14),
    ("cli", 15),
];

/// Files that belong to no layer: the crate root declares the modules.
const ROOTS: &[&str] = &["lib.rs", "main.rs"];

fn rank(module: &str) -> Option<u32> {
    LAYERS.iter().find(|(m, _)| *m == module).map(|&(_, r)| r)
}

/// `source` with the contents of comments and string and character literals replaced by spaces (line breaks
/// kept, so line numbers still hold).
fn code_only(source: &str) -> String {
    let c: Vec<char> = source.chars().collect();
    let mut out = String::with_capacity(source.len());
    let blank = |out: &mut String, ch: char| out.push(if ch == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                blank(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
        } else if c[i] == 'r' && (next == Some('"') || next == Some('#')) && !ident_before(&c, i) {
            // A raw string r"…" or r#"…"#: ends at a quote followed by as many hashes.
            let mut j = i + 1;
            while c.get(j) == Some(&'#') {
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            let hashes = j - i - 1;
            out.extend(std::iter::repeat_n(' ', j + 1 - i));
            i = j + 1;
            while i < c.len() {
                if c[i] == '"' && (1..=hashes).all(|k| c.get(i + k) == Some(&'#')) {
                    out.extend(std::iter::repeat_n(' ', hashes + 1));
                    i += hashes + 1;
                    break;
                }
                blank(&mut out, c[i]);
                i += 1;
            }
        } else if c[i] == '"' {
            out.push(' ');
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    blank(&mut out, c[i]);
                    i += 1;
                }
                if i < c.len() {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
            out.push(' ');
            i += 1;
        } else if c[i] == '\'' && (c.get(i + 2) == Some(&'\'') || next == Some('\\')) {
            // A character literal ('x' or an escape); a lifetime has no closing quote there.
            out.push(' ');
            i += 1;
            while i < c.len() && c[i] != '\'' {
                if c[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                out.push(' ');
                i += 1;
            }
            out.push(' ');
            i += 1;
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

fn ident_before(c: &[char], i: usize) -> bool {
    i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_')
}

/// The first path segments named through `crate::` in `code` (comments and literals already blanked), with
/// their 1-based line: `crate::a::b` gives `a`, `crate::{a::b, c}` gives `a` and `c`.
fn crate_paths(code: &str) -> Vec<(usize, String)> {
    let c: Vec<char> = code.chars().collect();
    let line_of = |i: usize| c[..i].iter().filter(|&&ch| ch == '\n').count() + 1;
    let ident_at = |mut j: usize| {
        while c.get(j).is_some_and(|ch| ch.is_whitespace()) {
            j += 1;
        }
        let start = j;
        while c.get(j).is_some_and(|&ch| ch.is_alphanumeric() || ch == '_') {
            j += 1;
        }
        (c[start..j].iter().collect::<String>(), j)
    };
    let mut found = Vec::new();
    let mut i = 0;
    while i + 7 <= c.len() {
        let is_crate = c[i..i + 7].iter().collect::<String>() == "crate::"
            && !(ident_before(&c, i) || (i > 0 && c[i - 1] == '$'));
        if !is_crate {
            i += 1;
            continue;
        }
        let mut j = i + 7;
        while c.get(j).is_some_and(|ch| ch.is_whitespace()) {
            j += 1;
        }
        if c.get(j) == Some(&'{') {
            // A group: the first segment of each item at depth 1.
            let mut depth = 0;
            let mut item_start = true;
            while j < c.len() {
                match c[j] {
                    '{' => {
                        depth += 1;
                        item_start = depth == 1;
                    }
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    ',' if depth == 1 => item_start = true,
                    ch if item_start && depth == 1 && !ch.is_whitespace() => {
                        let (name, end) = ident_at(j);
                        if !name.is_empty() && name != "self" {
                            found.push((line_of(j), name));
                        }
                        item_start = false;
                        j = end.max(j + 1);
                        continue;
                    }
                    _ => {}
                }
                j += 1;
            }
        } else {
            let (name, _) = ident_at(j);
            if !name.is_empty() {
                found.push((line_of(i), name));
            }
        }
        i += 7;
    }
    found
}

/// The layer violations of one file of module `module`: `file:line: ...` messages.
fn violations(file: &str, module: &str, source: &str) -> Vec<String> {
    let Some(own) = rank(module) else {
        return vec![format!("{file}: module `{module}` has no place in the layer table of tests/layers.rs")];
    };
    let mut out = Vec::new();
    for (line, target) in crate_paths(&code_only(source)) {
        if target == module {
            continue;
        }
        match rank(&target) {
            Some(r) if r < own => {}
            Some(r) => out.push(format!(
                "{file}:{line}: `{module}` (rank {own}) imports `crate::{target}` (rank {r}); a module may import only \
                 lower ranks"
            )),
            // Crate-root items (none today) or a module the table does not know yet.
            None => out.push(format!("{file}:{line}: `crate::{target}` is not a module of the layer table")),
        }
    }
    out
}

fn rust_files(dir: &Path, into: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("read src/") {
        let path = entry.expect("dir entry").path();
        if path.is_dir() {
            rust_files(&path, into);
        } else if path.extension().is_some_and(|e| e == "rs") {
            into.push(path);
        }
    }
}

/// Every Rust file under `src/` but the crate roots: its path relative to `src/` and its source, sorted.
fn src_files() -> Vec<(String, String)> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut paths = Vec::new();
    rust_files(&src, &mut paths);
    paths.sort();
    assert!(paths.len() > 20, "found only {} files under {}", paths.len(), src.display());
    paths
        .iter()
        .map(|p| p.strip_prefix(&src).expect("under src").to_str().expect("UTF-8 path").replace('\\', "/"))
        .filter(|rel| !ROOTS.contains(&rel.as_str()))
        .map(|rel| {
            let source = fs::read_to_string(src.join(&rel)).expect("read source");
            (rel, source)
        })
        .collect()
}

#[test]
fn every_module_imports_only_lower_layers() {
    let mut problems = Vec::new();
    for (rel, source) in src_files() {
        let first = rel.split('/').next().expect("non-empty");
        let module = first.strip_suffix(".rs").unwrap_or(first);
        problems.extend(violations(&format!("src/{rel}"), module, &source));
    }
    assert!(problems.is_empty(), "layer violations (ARCHITECTURE.md, \"Layers\"):\n{}", problems.join("\n"));
}

#[test]
fn every_table_entry_is_a_module() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    for (module, _) in LAYERS {
        assert!(
            src.join(format!("{module}.rs")).is_file() || src.join(module).join("mod.rs").is_file(),
            "the layer table names `{module}`, which is not a module under src/"
        );
    }
}

#[test]
fn an_upward_import_is_reported() {
    let v = violations("src/geometry/x.rs", "geometry", "use crate::math::V3;\nuse crate::accel::Spheres;\n");
    assert_eq!(v.len(), 1, "{v:?}");
    assert!(v[0].starts_with("src/geometry/x.rs:2:"), "{v:?}");
    assert!(v[0].contains("crate::accel"), "{v:?}");
}

#[test]
fn inline_paths_groups_and_siblings_are_reported() {
    let inline = violations("src/simd/x.rs", "simd", "fn f() -> crate::geometry::Ray<f32> { todo!() }\n");
    assert_eq!(inline.len(), 1, "{inline:?}");
    let group =
        violations("src/math/x.rs", "math", "use crate::{\n    math::V3,\n    simd::{Lanes, IdLanes},\n};\n");
    assert_eq!(group.len(), 1, "{group:?}");
    assert!(group[0].starts_with("src/math/x.rs:3:") && group[0].contains("crate::simd"), "{group:?}");
    // accel and scene share a rank: neither may import the other.
    let sibling = violations("src/accel/x.rs", "accel", "use crate::scene::desc::SceneDesc;\n");
    assert_eq!(sibling.len(), 1, "{sibling:?}");
}

#[test]
fn downward_and_own_imports_comments_and_strings_pass() {
    let source = r##"
//! Doc links may point anywhere: [`crate::render`].
use crate::geometry::Ray;
use crate::accel::{self, Geometry};
use crate::{math::V3, simd::Lanes};
/* crate::cli::main() in a block comment */
fn f<'a>(x: &'a str) -> char { let _ = "crate::cli"; let _ = r#"crate::render"#; 'c' }
pub(crate) fn g() {}
"##;
    assert_eq!(violations("src/accel/x.rs", "accel", source), Vec::<String>::new());
}

#[test]
fn an_unknown_module_is_reported() {
    assert_eq!(violations("src/newthing.rs", "newthing", "").len(), 1);
    assert_eq!(violations("src/accel/x.rs", "accel", "use crate::newthing::X;\n").len(), 1);
}

// ---- Import circles between files ----
//
// Within and across modules, no file may reach itself through the files it imports: a file's imports are the
// paths it names through `crate::`, `super::` and `self::` (grouped `{…}` paths expanded), each resolved to
// the deepest module that has a file of its own. A file and the modules above or below it (a parent declaring
// its children, a child using its parent's items) are one unit and make no edge; every other pair of files
// does, and the check fails on any circle of such edges.

/// The module path of a file under `src/`: `accel/bvh/build.rs` is `accel::bvh::build`, a `mod.rs` its folder.
fn module_of(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel.trim_end_matches(".rs").split('/').map(str::to_owned).collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// Tokens of blanked code: identifiers, `::`, braces and commas, each with its line.
fn path_tokens(code: &str) -> Vec<(usize, String)> {
    let c: Vec<char> = code.chars().collect();
    let (mut out, mut line, mut i) = (Vec::new(), 1, 0);
    while i < c.len() {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
        }
        if ch.is_alphanumeric() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            let prev = if start > 0 { c[start - 1] } else { ' ' };
            // `$crate` and `r#ident` are not paths of this crate's files.
            let word: String = c[start..i].iter().collect();
            out.push((line, if prev == '$' { format!("${word}") } else { word }));
            continue;
        }
        if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push((line, "::".into()));
            i += 2;
            continue;
        }
        if matches!(ch, '{' | '}' | ',') {
            out.push((line, ch.to_string()));
        } else if !ch.is_whitespace() {
            out.push((line, ";".into()));
        }
        i += 1;
    }
    out
}

/// Reads the path segments after `tokens[*at]` (which is `::`), expanding one level of `{…}` groups at a
/// time, into `out` as full paths prefixed by `prefix`.
fn expand(
    tokens: &[(usize, String)],
    at: &mut usize,
    prefix: Vec<String>,
    line: usize,
    out: &mut Vec<(usize, Vec<String>)>,
) {
    let mut path = prefix;
    while tokens.get(*at).is_some_and(|t| t.1 == "::") {
        *at += 1;
        match tokens.get(*at).map(|t| t.1.as_str()) {
            Some("{") => {
                *at += 1;
                loop {
                    match tokens.get(*at).map(|t| t.1.as_str()) {
                        Some("}") => {
                            *at += 1;
                            return;
                        }
                        Some(",") => *at += 1,
                        Some(word) if word.chars().all(|c| c.is_alphanumeric() || c == '_') => {
                            let mut inner = path.clone();
                            match word {
                                "self" => {}
                                "super" => {
                                    inner.pop();
                                }
                                _ => inner.push(word.to_owned()),
                            }
                            let l = tokens[*at].0;
                            *at += 1;
                            let before = out.len();
                            expand(tokens, at, inner.clone(), l, out);
                            if out.len() == before {
                                out.push((l, inner));
                            }
                        }
                        _ => {
                            *at += 1;
                        }
                    }
                    if *at >= tokens.len() {
                        return;
                    }
                }
            }
            Some(word) if word.chars().all(|c| c.is_alphanumeric() || c == '_') => {
                path.push(word.to_owned());
                *at += 1;
            }
            _ => break,
        }
    }
    out.push((line, path));
}

/// The full module paths a file of module `own` names (`is_mod`: it is a `mod.rs`), with their lines.
fn named_paths(own: &[String], code: &str) -> Vec<(usize, Vec<String>)> {
    let tokens = path_tokens(code);
    let mut out = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        let (line, word) = (tokens[i].0, tokens[i].1.as_str());
        let after_path = i > 0 && tokens[i - 1].1 == "::";
        let base = match word {
            "crate" if !after_path => Some(Vec::new()),
            "self" if !after_path && tokens.get(i + 1).is_some_and(|t| t.1 == "::") => Some(own.to_vec()),
            "super" if !after_path => {
                let mut base = own.to_vec();
                base.pop();
                let mut j = i + 1;
                // `super::super::…`
                while tokens.get(j).is_some_and(|t| t.1 == "::")
                    && tokens.get(j + 1).is_some_and(|t| t.1 == "super")
                {
                    base.pop();
                    j += 2;
                }
                i = j - 1;
                Some(base)
            }
            _ => None,
        };
        i += 1;
        if let Some(base) = base {
            expand(&tokens, &mut i, base, line, &mut out);
        }
    }
    out
}

/// The import edges between files that are not above or below one another: (from, to, line).
fn file_edges(files: &[(Vec<String>, String)]) -> Vec<(usize, usize, usize)> {
    let related = |a: &[String], b: &[String]| a.starts_with(b) || b.starts_with(a);
    let mut edges = Vec::new();
    for (from, (own, code)) in files.iter().enumerate() {
        for (line, path) in named_paths(own, &code_only(code)) {
            // The deepest prefix of the path that is a file's module.
            let target = (0..=path.len()).rev().find_map(|n| files.iter().position(|(m, _)| *m == path[..n]));
            if let Some(to) = target.filter(|&to| !related(own, &files[to].0)) {
                if !edges.iter().any(|&(f, t, _)| f == from && t == to) {
                    edges.push((from, to, line));
                }
            }
        }
    }
    edges
}

/// Every circle of imports among `files` (module path, source), each as `a.rs:line → b.rs:line → … → a.rs`.
fn import_circles(files: &[(Vec<String>, String)]) -> Vec<String> {
    let edges = file_edges(files);
    let name = |i: usize| files[i].0.join("::");
    let mut circles = Vec::new();
    // A depth-first search from each file for a way back to it through files later in the list (each
    // circle found once, from its first file).
    for start in 0..files.len() {
        let mut stack = vec![(start, vec![(start, 0usize)])];
        let mut seen = vec![false; files.len()];
        while let Some((at, trail)) = stack.pop() {
            for &(_, t, line) in edges.iter().filter(|e| e.0 == at) {
                let mut next = trail.clone();
                next.last_mut().expect("non-empty").1 = line;
                if t == start {
                    let hops: Vec<String> = next.iter().map(|&(i, l)| format!("{}:{l}", name(i))).collect();
                    circles.push(format!("{} → {}", hops.join(" → "), name(start)));
                } else if t > start && !seen[t] {
                    seen[t] = true;
                    next.push((t, 0));
                    stack.push((t, next));
                }
            }
        }
    }
    circles
}

#[test]
fn no_file_reaches_itself_through_its_imports() {
    let files: Vec<(Vec<String>, String)> =
        src_files().into_iter().map(|(rel, source)| (module_of(&rel), source)).collect();
    assert!(file_edges(&files).len() > 20, "the import edges were not found");
    let circles = import_circles(&files);
    assert!(
        circles.is_empty(),
        "import circles between files (ARCHITECTURE.md, \"Layers\"):\n{}",
        circles.join("\n")
    );
}

/// A small tree: `m/a.rs` and `m/b.rs` import each other, `m/c.rs` imports `a` only, `m/mod.rs` declares and
/// re-exports its children (parent and child: no edge), and `n.rs` names `m::c` through a group.
fn toy(a_uses_b: &str) -> Vec<(Vec<String>, String)> {
    [
        ("m/mod.rs", "mod a;\nmod b;\nmod c;\npub use a::A;\nuse self::b::B;\n"),
        ("m/a.rs", a_uses_b),
        ("m/b.rs", "use super::a::A;\npub struct B;\n"),
        ("m/c.rs", "use super::{a::A, super::n};\nfn f() -> super::super::m::a::A { todo!() }\n"),
        ("n.rs", "use crate::m::{self, c::{self}};\n"),
    ]
    .iter()
    .map(|(p, s)| (module_of(p), (*s).to_owned()))
    .collect()
}

#[test]
fn the_circle_checker_finds_circles_and_only_circles() {
    let circles = import_circles(&toy("pub struct A;\nfn g() { let _ = crate::m::b::B; }\n"));
    let want = ["m::a:2 → m::b:1 → m::a", "m::c:1 → n:1 → m::c"].map(str::to_owned);
    assert_eq!(circles, want, "{circles:?}");
    // Through a group, across modules and with `super::super`: c → n (line 1) and n → c (line 1), c → a.
    let edges = file_edges(&toy("pub struct A;\n"));
    let names: Vec<(String, String)> = edges
        .iter()
        .map(|&(f, t, _)| (toy("").get(f).unwrap().0.join("::"), toy("").get(t).unwrap().0.join("::")))
        .collect();
    for want in [("m::b", "m::a"), ("m::c", "m::a"), ("m::c", "n"), ("n", "m::c"), ("n", "m")] {
        assert!(names.contains(&(want.0.to_owned(), want.1.to_owned())), "{want:?} missing from {names:?}");
    }
    assert_eq!(names.len(), 5, "parent and child make no edge: {names:?}");
    let circles = import_circles(&toy("pub struct A;\n"));
    assert_eq!(circles, vec!["m::c:1 → n:1 → m::c".to_owned()], "{circles:?}");
}

/// Lines of `src/` (crate roots included) that declare a `pub` item, as `grep -rE '^\s*pub ' src` counts
/// them: `pub(crate)` and narrower do not count.
fn pub_lines() -> usize {
    let mut paths = Vec::new();
    rust_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src"), &mut paths);
    let declares = |source: String| source.lines().filter(|l| l.trim_start().starts_with("pub ")).count();
    paths.iter().map(|p| declares(fs::read_to_string(p).expect("read source"))).sum()
}

/// The library's public surface is what a library user needs (the README's "Use it as a library", the
/// rustdoc); everything else is `pub(crate)`. The bound keeps it at under half the 1125 lines it once had.
#[test]
fn the_public_surface_stays_small() {
    let lines = pub_lines();
    assert!(
        lines <= 562,
        "{lines} lines of src/ declare `pub` items (at most 562): make new items pub(crate)"
    );
}

/// The command's files parse, call the library and print: none grows past 300 lines.
#[test]
fn no_cli_file_is_long() {
    let mut paths = Vec::new();
    rust_files(&Path::new(env!("CARGO_MANIFEST_DIR")).join("src/cli"), &mut paths);
    assert!(!paths.is_empty(), "no files under src/cli");
    for path in paths {
        let lines = fs::read_to_string(&path).expect("read source").lines().count();
        assert!(lines <= 300, "{}: {lines} lines (at most 300)", path.display());
    }
}
