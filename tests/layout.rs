//! The source tree keeps its architecture: folders are layers and import only downwards, the
//! top level holds only the crate roots, and no function outside tests
//! grows past what can be read at once. These checks read the source files; they fail with the
//! offending file and line, so a newcomer sees which rule a change broke.

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
const MAX_FUNCTION_LINES: usize = 80;

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
}
