//! The `bkpbs …` commands of the documents' shell blocks, read as the shell and usage notation
//! mean them, and run with `--help` appended: clap rejects an unknown flag or a bad value before
//! it sees the trailing `--help`, and exits 0 on a command it accepts.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;

/// Languages of fenced blocks that hold shell commands.
const SHELL_BLOCKS: [&str; 6] = ["", "sh", "bash", "shell", "console", "sh-session"];

/// Where a documented command is, and how it is written there.
#[derive(Debug)]
pub struct Documented {
    pub place: String,
    pub written: String,
}

/// The command lines of a document's shell blocks, `\` continuations joined, with the line
/// each starts on.
pub fn shell_lines(text: &str) -> Vec<(usize, String)> {
    let (mut out, mut lang, mut inside) = (Vec::new(), String::new(), false);
    let mut pending: Option<(usize, String)> = None;
    for (n, line) in text.lines().enumerate() {
        if let Some(rest) = line.trim_start().strip_prefix("```") {
            (inside, lang) = (!inside, rest.trim().to_string());
            continue;
        }
        if !inside || !SHELL_BLOCKS.contains(&lang.as_str()) {
            continue;
        }
        let (start, mut joined) = pending.take().unwrap_or((n + 1, String::new()));
        joined.push_str(line.trim());
        match joined.strip_suffix('\\') {
            Some(head) => pending = Some((start, head.trim_end().to_string() + " ")),
            None => out.push((start, joined)),
        }
    }
    out
}

/// Shell words of a line: whitespace-separated, quotes grouping, a `#` word starting a comment,
/// and `$ ` prompts dropped.
pub fn words(line: &str) -> Vec<String> {
    let line = line.strip_prefix("$ ").unwrap_or(line);
    let (mut out, mut word, mut quote) = (Vec::new(), None::<String>, None::<char>);
    for c in line.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), c) => word.get_or_insert_with(String::new).push(c),
            (None, '"' | '\'') => (quote, word) = (Some(c), Some(word.unwrap_or_default())),
            (None, '#') if word.is_none() => break,
            (None, c) if c.is_whitespace() => out.extend(word.take()),
            (None, c) => word.get_or_insert_with(String::new).push(c),
        }
    }
    out.extend(word);
    out
}

/// Words that separate commands in a pipeline or list.
const SEPARATORS: [&str; 5] = ["&&", "||", ";", "|", "&"];

/// The arguments of each `bkpbs` invocation on a line: after the program word (`bkpbs` or a
/// path ending in `/bkpbs`; anything before it, such as `NAME=value` or `xvfb-run -a`, is
/// another program's), up to the end of its command, redirections left out.
pub fn invocations(line: &str) -> Vec<Vec<String>> {
    let words = words(line);
    words
        .split(|w| SEPARATORS.contains(&w.as_str()))
        .filter_map(|cmd| {
            let at = cmd
                .iter()
                .position(|w| w == "bkpbs" || w.ends_with("/bkpbs"))?;
            Some(without_redirections(&cmd[at + 1..]))
        })
        .collect()
}

/// The arguments without shell redirections (`> f`, `>f`, `2>&1`, `< f`); `<name>` is a
/// usage placeholder, not a redirection.
fn without_redirections(args: &[String]) -> Vec<String> {
    let mut out = Vec::new();
    let mut skip_next = false;
    for a in args {
        let bare = a.trim_start_matches(|c: char| c.is_ascii_digit() || c == '&');
        let placeholder = a.len() > 2 && a.starts_with('<') && a.ends_with('>');
        if skip_next {
            skip_next = false;
        } else if !placeholder && (bare.starts_with('>') || bare.starts_with('<')) {
            skip_next = bare.trim_start_matches(['>', '<', '&']).is_empty();
        } else {
            out.push(a.clone());
        }
    }
    out
}

/// Usage notation reduced to a concrete command line: `[--x]` is given, `a|b` is `a`, a number
/// placeholder (a single capital such as `N`, `S`, `W`, or `SECONDS`, `MS`) is `1`, `k/n` is
/// `1/2`, a word placeholder (`FILE`, `DIR`, `NAME`) stays as it is (any path or name parses),
/// and what only says "and so on" (`<…>`, `…`, `DIR...`) is left out, with the flag it is the
/// value of. What is left must parse.
pub fn concrete(args: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for a in args {
        let a = a.trim_matches(['[', ']']);
        let a = a.split('|').next().unwrap_or(a);
        if a.is_empty() {
            continue;
        }
        match placeholder_value(a) {
            Some(value) => out.push(value),
            None => {
                if out
                    .last()
                    .is_some_and(|f| f.starts_with("--") && !f.contains('='))
                {
                    out.pop();
                }
            }
        }
    }
    out
}

/// What a usage word is given as (`None`: left out).
fn placeholder_value(a: &str) -> Option<String> {
    let number = (a.len() == 1 && a.starts_with(|c: char| c.is_ascii_uppercase()))
        || ["SECONDS", "MS"].contains(&a);
    if a.contains(['<', '>', '…']) || a.contains("...") {
        None
    } else if number {
        Some("1".into())
    } else if a == "k/n" {
        Some("1/2".into())
    } else {
        Some(a.to_string())
    }
}

/// Every documented invocation, deduplicated by the arguments the binary gets.
pub fn documented_commands(docs: &BTreeMap<PathBuf, String>) -> BTreeMap<Vec<String>, Documented> {
    let mut out = BTreeMap::new();
    for (file, text) in docs {
        for (line, command) in shell_lines(text) {
            for args in invocations(&command) {
                let place = format!("{}:{line}", file.display());
                out.entry(concrete(&args)).or_insert(Documented {
                    place,
                    written: command.clone(),
                });
            }
        }
    }
    out
}

/// The binary's answer to a documented command with `--help` appended, if it is not exit 0.
pub fn rejected((args, doc): &(Vec<String>, Documented)) -> Option<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_bkpbs"))
        .args(args)
        .arg("--help")
        .output()
        .expect("running bkpbs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    (!out.status.success()).then(|| {
        let first = stderr.lines().next().unwrap_or("");
        format!(
            "{}: `{}` → bkpbs {} --help: {first}",
            doc.place,
            doc.written,
            args.join(" ")
        )
    })
}

/// The `bkpbs …` (or `…/bkpbs …`) inline code spans of a text — Markdown prose, or the
/// comments, doc comments and messages of source files — with their line: the subcommand and
/// the `--flags` named (values, placeholders and notation left out). Fenced shell blocks are
/// [`shell_lines`]'s.
pub fn inline_mentions(text: &str) -> Vec<(usize, String, Vec<String>)> {
    let mut out = Vec::new();
    let mut offset = 0;
    for (i, span) in text.split('`').enumerate() {
        let line = text[..offset].matches('\n').count() + 1;
        offset += span.len() + 1;
        let mut words = span.split_whitespace();
        let program = words.next().unwrap_or("");
        if i % 2 == 0 || !(program == "bkpbs" || program.ends_with("/bkpbs")) {
            continue;
        }
        let Some(sub) = words.next() else { continue };
        if !sub.chars().all(|c| c.is_ascii_lowercase() || c == '-') {
            continue;
        }
        let flags = words
            .map(|w| w.trim_start_matches('['))
            .filter(|w| w.starts_with("--"))
            .map(|w| {
                let end = w[2..]
                    .find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
                    .map_or(w.len(), |e| e + 2);
                w[..end].to_string()
            })
            .collect();
        out.push((line, sub.to_string(), flags));
    }
    out
}

/// The flags `bkpbs SUB --help` lists, or `None` when the binary has no such subcommand.
pub fn flags_of(sub: &str) -> Option<std::collections::BTreeSet<String>> {
    let out = Command::new(env!("CARGO_BIN_EXE_bkpbs"))
        .args([sub, "--help"])
        .output()
        .expect("running bkpbs");
    if !out.status.success() {
        return None;
    }
    let help = String::from_utf8_lossy(&out.stdout);
    Some(
        help.split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
            .filter(|w| w.starts_with("--") && w.len() > 2)
            .map(String::from)
            .collect(),
    )
}
