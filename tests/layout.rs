//! The source tree keeps its architecture: folders are layers and import only downwards, no two
//! modules import each other (directly or round a loop), the top level holds only the crate
//! roots, and no file or function outside tests grows past what can be read at once. These checks
//! read the source files; they fail with the offending file and line, so a newcomer sees which
//! rule a change broke.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers of `src/`, lowest first. A module may name `crate::X` only for an `X` listed at or
/// before its own folder. `cli` is the binary's (it names the library as `bkpbs::`, which is
/// above everything).
const LAYERS: [&str; 13] = [
    "io",
    "config",
    "model",
    "sumo",
    "predict",
    "planner",
    "policy",
    "controller",
    "episode",
    "train",
    "campaign",
    "report",
    "cli",
];

/// Files allowed at the top of `src/`; everything else lives in a layer's folder.
const TOP_LEVEL_FILES: [&str; 2] = ["lib.rs", "main.rs"];

/// Longest function body, in lines, outside tests.
const MAX_FUNCTION_LINES: usize = 60;

/// Longest file, in lines outside its test modules: one concept, read in one sitting.
const MAX_FILE_LINES: usize = 600;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|e| e == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The layer a file of `src/` belongs to: its top folder, or its stem at the top level.
fn layer_of(src: &Path, file: &Path) -> Option<usize> {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    LAYERS.iter().position(|l| *l == name)
}

/// The code of a line without its `//` comment (doc links may point anywhere).
fn code_part(line: &str) -> &str {
    match line.find("//") {
        Some(i) => &line[..i],
        None => line,
    }
}

/// Each `crate::X` a line names, with `X`.
fn crate_paths(line: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = code_part(line);
    while let Some(i) = rest.find("crate::") {
        let before = rest[..i].chars().last();
        rest = &rest[i + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue; // e.g. `bkpbs_crate::`, not this crate
        }
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        out.push(&rest[..end]);
    }
    out
}

#[test]
fn src_top_level_holds_only_the_roots_the_settings_and_folders() {
    let src = root().join("src");
    let mut stray = Vec::new();
    for entry in std::fs::read_dir(&src).unwrap() {
        let p = entry.unwrap().path();
        let name = p.file_name().unwrap().to_str().unwrap().to_string();
        if p.is_file() && !TOP_LEVEL_FILES.contains(&name.as_str()) {
            stray.push(name);
        } else if p.is_dir() && !LAYERS.contains(&name.as_str()) {
            stray.push(format!(
                "{name}/ (not a layer: add it to LAYERS in its place)"
            ));
        }
    }
    assert!(
        stray.is_empty(),
        "src/ should hold only {TOP_LEVEL_FILES:?} and layer folders; found {stray:?}"
    );
}

#[test]
fn no_module_imports_from_a_layer_above_its_own() {
    let src = root().join("src");
    let mut upward = Vec::new();
    for file in rust_files(&src) {
        let Some(own) = layer_of(&src, &file) else {
            continue; // lib.rs and main.rs are the roots
        };
        let text = std::fs::read_to_string(&file).unwrap();
        for (n, line) in text.lines().enumerate() {
            if code_part(line).contains("super::super::") {
                upward.push(format!(
                    "{}:{}: super::super crosses folders; name the path from crate::",
                    file.display(),
                    n + 1
                ));
            }
            for target in crate_paths(line) {
                let Some(to) = LAYERS.iter().position(|l| *l == target) else {
                    continue;
                };
                if to > own {
                    upward.push(format!(
                        "{}:{}: {} (layer {}) imports {} (layer {})",
                        file.strip_prefix(root()).unwrap().display(),
                        n + 1,
                        LAYERS[own],
                        own,
                        target,
                        to
                    ));
                }
            }
        }
    }
    assert!(upward.is_empty(), "upward imports:\n{}", upward.join("\n"));
}

/// Line ranges of the functions in `text` outside `#[cfg(test)]` items: (name, first line,
/// length in lines). Braces are counted per line, which the formatter's layout makes reliable.
fn functions(text: &str) -> Vec<(String, usize, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let line = code_part(lines[i]).trim_start();
        if line.starts_with("#[cfg(test)]") {
            i = end_of_item(&lines, i + 1) + 1;
            continue;
        }
        if let Some(name) = fn_name(line) {
            let end = end_of_item(&lines, i);
            if end > i || code_part(lines[i]).contains('{') {
                out.push((name, i + 1, end - i + 1));
            }
        }
        i += 1;
    }
    out
}

/// The name of the function a line declares, if it does.
fn fn_name(line: &str) -> Option<String> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let k = words.iter().position(|w| *w == "fn")?;
    let qualifiers_only = words[..k].iter().all(|w| {
        w.starts_with("pub") || ["const", "unsafe", "async", "extern", "\"C\""].contains(w)
    });
    let name: String = words
        .get(k + 1)?
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    (qualifiers_only && !name.is_empty()).then_some(name)
}

/// The line where the item starting at `start` closes (its braces balance), or where a
/// brace-less declaration ends with `;`.
fn end_of_item(lines: &[&str], start: usize) -> usize {
    let mut depth = 0i64;
    let mut opened = false;
    for (k, raw) in lines.iter().enumerate().skip(start) {
        let line = code_part(raw);
        for c in line.chars() {
            match c {
                '{' => {
                    depth += 1;
                    opened = true;
                }
                '}' => depth -= 1,
                _ => {}
            }
        }
        if opened && depth <= 0 {
            return k;
        }
        if !opened && line.trim_end().ends_with(';') {
            return k;
        }
    }
    lines.len() - 1
}

#[test]
fn no_function_outside_tests_is_longer_than_the_limit() {
    let mut long = Vec::new();
    for dir in ["src", "bindings/src"] {
        for file in rust_files(&root().join(dir)) {
            let text = std::fs::read_to_string(&file).unwrap();
            for (name, line, len) in functions(&text) {
                if len > MAX_FUNCTION_LINES {
                    long.push(format!(
                        "{}:{line}: fn {name} has {len} lines",
                        file.strip_prefix(root()).unwrap().display()
                    ));
                }
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines (split them into named pieces):\n{}",
        long.join("\n")
    );
}

/// `text` with every `#[cfg(test)]` item blanked out (its lines kept, empty), so that line
/// numbers still point into the file.
fn without_tests(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    let mut i = 0;
    while i < lines.len() {
        if code_part(lines[i]).trim_start().starts_with("#[cfg(test)]") {
            let end = end_of_item(&lines, i + 1);
            for line in &mut out[i..=end] {
                line.clear();
            }
            i = end + 1;
        } else {
            i += 1;
        }
    }
    out
}

/// Lines of `text` outside its test modules (blank lines and comments count: they are read).
fn lines_outside_tests(text: &str) -> usize {
    let lines: Vec<&str> = text.lines().collect();
    let kept = without_tests(text);
    lines
        .iter()
        .zip(&kept)
        .filter(|(l, k)| !k.is_empty() || l.trim().is_empty())
        .count()
}

/// The names of the file modules that `text` declares under `#[cfg(test)]` (`mod tests;`):
/// such a file is a test module of its own.
fn test_module_files(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        if !code_part(line).trim_start().starts_with("#[cfg(test)]") {
            continue;
        }
        let Some(next) = lines.get(k + 1) else {
            continue;
        };
        let next = code_part(next).trim();
        let decl = next.strip_prefix("pub ").unwrap_or(next);
        if let Some(name) = decl.strip_prefix("mod ").and_then(|r| r.strip_suffix(';')) {
            out.push(name.trim().to_string());
        }
    }
    out
}

/// Every `.rs` file of `dirs` that is not a test module, with its text.
fn library_files(dirs: &[&str]) -> Vec<(PathBuf, String)> {
    let mut files = Vec::new();
    for dir in dirs {
        files.extend(rust_files(&root().join(dir)).into_iter().map(|f| {
            let text = std::fs::read_to_string(&f).unwrap();
            (f, text)
        }));
    }
    let mut tests = BTreeSet::new();
    for (file, text) in &files {
        let folder = if file
            .file_name()
            .is_some_and(|n| n == "mod.rs" || n == "lib.rs")
        {
            file.parent().unwrap().to_path_buf()
        } else {
            file.with_extension("")
        };
        for name in test_module_files(text) {
            tests.insert(folder.join(format!("{name}.rs")));
            tests.insert(folder.join(&name).join("mod.rs"));
        }
    }
    files.retain(|(f, _)| !tests.contains(f));
    files
}

#[test]
fn no_file_outside_tests_is_longer_than_the_limit() {
    let mut long = Vec::new();
    for (file, text) in library_files(&["src", "bindings/src"]) {
        let n = lines_outside_tests(&text);
        if n > MAX_FILE_LINES {
            long.push(format!(
                "{}: {n} lines outside tests",
                file.strip_prefix(root()).unwrap().display()
            ));
        }
    }
    assert!(
        long.is_empty(),
        "files over {MAX_FILE_LINES} lines (split them by concept, tests into a sibling \
         `tests.rs`):\n{}",
        long.join("\n")
    );
}

/// The module path of a file of `src/` (`src/campaign/results.rs` → `["campaign", "results"]`).
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_str().unwrap().to_string())
        .collect();
    if parts
        .last()
        .is_some_and(|p| p == "mod" || p == "lib" || p == "main")
    {
        parts.pop();
    }
    parts
}

/// The `use` declarations and inline paths of `code` (test items removed), as module paths
/// relative to the crate: `crate::a::b::{c, d::e}` gives `a::b::c` and `a::b::d::e`;
/// `super::x` is resolved against `own`, the module the code is in.
fn named_paths(code: &str, own: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for statement in code.split(';') {
        for start in ["crate::", "super::"] {
            let mut rest = statement;
            while let Some(i) = rest.find(start) {
                let before = rest[..i].chars().last();
                let tail = &rest[i..];
                rest = &rest[i + start.len()..];
                if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                    continue;
                }
                for path in expand_braces(&take_path(tail)) {
                    if let Some(p) = absolute(&path, own) {
                        out.push(p);
                    }
                }
            }
        }
    }
    out
}

/// The path that starts `text`: identifiers, `::`, and one balanced `{…}` group.
fn take_path(text: &str) -> String {
    let mut depth = 0;
    let mut end = text.len();
    for (k, c) in text.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth > 0 => {
                depth -= 1;
                if depth == 0 {
                    end = k + 1;
                    break;
                }
            }
            c if depth == 0 && !(c.is_alphanumeric() || c == '_' || c == ':') => {
                end = k;
                break;
            }
            _ => {}
        }
    }
    text[..end].split_whitespace().collect()
}

/// `a::{b, c::{d, e}}` → `a::b`, `a::c::d`, `a::c::e` (`self` names the prefix itself).
fn expand_braces(path: &str) -> Vec<String> {
    let Some(open) = path.find('{') else {
        return vec![path.trim_end_matches(':').to_string()];
    };
    let prefix = &path[..open];
    let inner = &path[open + 1..path.rfind('}').unwrap_or(path.len())];
    let mut parts = Vec::new();
    let (mut depth, mut from) = (0, 0);
    for (k, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[from..k]);
                from = k + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[from..]);
    parts
        .into_iter()
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .flat_map(|p| {
            let p = p.split(" as ").next().unwrap();
            let joined = if p == "self" {
                prefix.trim_end_matches(':').to_string()
            } else {
                format!("{prefix}{p}")
            };
            expand_braces(&joined)
        })
        .collect()
}

/// `crate::a::b` → `[a, b]`; `super::x` against `own`; anything else is not the crate's.
fn absolute(path: &str, own: &[String]) -> Option<Vec<String>> {
    let mut parts: Vec<&str> = path.split("::").filter(|p| !p.is_empty()).collect();
    let mut base: Vec<String> = match *parts.first()? {
        "crate" => Vec::new(),
        "super" => own.to_vec(),
        _ => return None,
    };
    parts.remove(0);
    if path.starts_with("super::") {
        base.pop();
        while parts.first() == Some(&"super") {
            parts.remove(0);
            base.pop();
        }
    }
    base.extend(parts.iter().map(|p| p.to_string()));
    Some(base)
}

/// The module (among `modules`) that a path names: its longest prefix that is a module.
fn module_named(path: &[String], modules: &BTreeSet<Vec<String>>) -> Option<Vec<String>> {
    (1..=path.len())
        .rev()
        .map(|n| path[..n].to_vec())
        .find(|p| modules.contains(p))
}

/// The import graph of `files` (module path → modules it names), leaving out a module's
/// names of its own ancestors: a child may use what its parent offers (the parent is the
/// folder's front door and re-exports the child), which is not a loop between two rooms.
fn import_graph(files: &[(Vec<String>, String)]) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(m, _)| m.clone()).collect();
    let mut graph = BTreeMap::new();
    for (own, text) in files {
        let code: Vec<String> = without_tests(text)
            .iter()
            .map(|l| code_part(l).to_string())
            .collect();
        let targets: BTreeSet<Vec<String>> = named_paths(&code.join("\n"), own)
            .iter()
            .filter_map(|p| module_named(p, &modules))
            .filter(|m| m != own && !own.starts_with(m))
            .collect();
        graph.insert(own.clone(), targets);
    }
    graph
}

/// The loops of `graph`: each strongly connected set of two or more modules (Tarjan).
fn import_loops(graph: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<Vec<Vec<String>>> {
    struct Walk<'g> {
        graph: &'g BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        index: BTreeMap<&'g Vec<String>, (usize, usize)>,
        stack: Vec<&'g Vec<String>>,
        loops: Vec<Vec<Vec<String>>>,
    }
    fn visit<'g>(w: &mut Walk<'g>, v: &'g Vec<String>) {
        let n = w.index.len();
        w.index.insert(v, (n, n));
        w.stack.push(v);
        for t in w.graph.get(v).into_iter().flatten() {
            let Some((t, _)) = w.graph.get_key_value(t) else {
                continue;
            };
            if !w.index.contains_key(t) {
                visit(w, t);
                let low = w.index[v].1.min(w.index[t].1);
                w.index.get_mut(v).unwrap().1 = low;
            } else if w.stack.contains(&t) {
                let low = w.index[v].1.min(w.index[t].0);
                w.index.get_mut(v).unwrap().1 = low;
            }
        }
        if w.index[v].0 == w.index[v].1 {
            let at = w.stack.iter().position(|m| *m == v).unwrap();
            let component: Vec<Vec<String>> = w.stack.drain(at..).cloned().collect();
            if component.len() > 1 {
                w.loops.push(component);
            }
        }
    }
    let mut walk = Walk {
        graph,
        index: BTreeMap::new(),
        stack: Vec::new(),
        loops: Vec::new(),
    };
    for v in graph.keys() {
        if !walk.index.contains_key(v) {
            visit(&mut walk, v);
        }
    }
    walk.loops
}

#[test]
fn no_two_modules_import_each_other() {
    for dir in ["src", "bindings/src"] {
        let src = root().join(dir);
        let files: Vec<(Vec<String>, String)> = library_files(&[dir])
            .into_iter()
            .filter(|(f, _)| !f.ends_with("main.rs"))
            .map(|(f, text)| (module_of(&src, &f), text))
            .collect();
        let loops = import_loops(&import_graph(&files));
        let shown: Vec<String> = loops
            .iter()
            .map(|l| {
                l.iter()
                    .map(|m| m.join("::"))
                    .collect::<Vec<_>>()
                    .join(" <-> ")
            })
            .collect();
        assert!(
            shown.is_empty(),
            "{dir}: modules that import each other (move what both need into one of them, or \
             below both):\n{}",
            shown.join("\n")
        );
    }
}

#[test]
fn the_checks_themselves_see_what_they_look_for() {
    // A regression guard for the scanners: an upward path, a test module and a long function.
    assert_eq!(
        crate_paths("use crate::episode::run; // crate::train"),
        ["episode"]
    );
    assert_eq!(
        fn_name("pub(crate) fn search<T>(x: T) {"),
        Some("search".into())
    );
    assert_eq!(fn_name("let f = |x| x; // fn not_this"), None);
    let body = "    x += 1;\n".repeat(90);
    let text = format!("fn long() {{\n{body}}}\n#[cfg(test)]\nmod tests {{\n    fn hidden() {{\n{body}    }}\n}}\n");
    let found = functions(&text);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!((found[0].0.as_str(), found[0].2), ("long", 92));
    const _: () = assert!(MAX_FUNCTION_LINES < 92);

    // A long file is long outside its tests only.
    let long = format!(
        "{}#[cfg(test)]\nmod tests {{\n{}}}\n",
        "x;\n".repeat(601),
        "y;\n".repeat(900)
    );
    assert_eq!(lines_outside_tests(&long), 601);
    assert!(lines_outside_tests(&long) > MAX_FILE_LINES);
    assert_eq!(
        test_module_files("#[cfg(test)]\nmod tests;\nmod real;\n"),
        ["tests"]
    );

    // Paths as `use` writes them, resolved from the module that writes them.
    let own = vec!["campaign".to_string(), "results".to_string()];
    let named = named_paths(
        "use super::validate::{key, Table};\nuse crate::episode::{self, metrics::Summary}",
        &own,
    );
    let mut shown: Vec<String> = named.iter().map(|p| p.join("::")).collect();
    shown.sort();
    assert_eq!(
        shown,
        [
            "campaign::validate::Table",
            "campaign::validate::key",
            "episode",
            "episode::metrics::Summary"
        ]
    );

    // A loop between two rooms is found; a child naming its parent is not a loop.
    let m = |p: &str| p.split("::").map(str::to_string).collect::<Vec<_>>();
    let files = vec![
        (m("campaign"), "pub use results::Results;".to_string()),
        (
            m("campaign::results"),
            "use super::validate::check; use super::Grid;".to_string(),
        ),
        (
            m("campaign::validate"),
            "use crate::campaign::results::key;".to_string(),
        ),
        (m("campaign::grid"), "use super::Settings;".to_string()),
    ];
    let loops = import_loops(&import_graph(&files));
    assert_eq!(loops.len(), 1, "{loops:?}");
    assert_eq!(loops[0].len(), 2);
    assert!(
        loops[0].contains(&m("campaign::results")) && loops[0].contains(&m("campaign::validate"))
    );
}
