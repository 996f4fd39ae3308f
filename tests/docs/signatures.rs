//! The Python API as the documents write it, against the checked-in stubs `_bkpbs.pyi` (which
//! the Python tests keep in step with the native module): a full signature in the text (one
//! with `*` or `**kwargs`) must be the stub's, parameter names and defaults, and a call must use
//! the stub's parameter names.

use std::collections::BTreeMap;

/// A parameter as written: `name`, `name=default`, `*` or `**name`, without annotations or
/// spaces.
pub type Params = Vec<String>;

/// The text up to the bracket that closes the one `text` starts just after, and the rest.
fn until_closing(text: &str) -> Option<(&str, &str)> {
    let (mut depth, mut quote) = (0usize, None::<char>);
    for (i, c) in text.char_indices() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '(' | '[' | '{') => depth += 1,
            (None, ')' | ']' | '}') if depth == 0 => return Some((&text[..i], &text[i + 1..])),
            (None, ')' | ']' | '}') => depth -= 1,
            _ => {}
        }
    }
    None
}

/// `text` split at the commas outside brackets and quotes, each part trimmed, empty ones out.
fn top_level_parts(text: &str) -> Vec<String> {
    let (mut parts, mut part) = (Vec::new(), String::new());
    let (mut depth, mut quote) = (0i32, None::<char>);
    for c in text.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '(' | '[' | '{') => depth += 1,
            (None, ')' | ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                parts.push(std::mem::take(&mut part));
                continue;
            }
            _ => {}
        }
        part.push(c);
    }
    parts.push(part);
    parts
        .iter()
        .map(|p| p.split_whitespace().collect::<Vec<_>>().join(" "))
        .filter(|p| !p.is_empty())
        .collect()
}

/// A stub parameter (`lam: Optional[float] = None`) as written in the guide (`lam=None`).
fn stub_param(p: &str) -> String {
    let (head, default) = match p.split_once(" = ").or_else(|| p.split_once('=')) {
        Some((head, default)) => (head, Some(default.trim())),
        None => (p, None),
    };
    let name = head.split(':').next().unwrap_or(head).trim();
    match default {
        Some(d) => format!("{name}={d}"),
        None => name.to_string(),
    }
}

/// Every function and method of the stubs with its parameters (`self` left out); a class's
/// `__init__` under the class's name. A method name defined in several classes keeps each.
pub fn stub_signatures(pyi: &str) -> BTreeMap<String, Vec<Params>> {
    let mut out: BTreeMap<String, Vec<Params>> = BTreeMap::new();
    let mut class: Option<String> = None;
    let mut next = 0;
    for line in pyi.split_inclusive('\n') {
        let at = next;
        next += line.len();
        if let Some(rest) = line.strip_prefix("class ") {
            class = rest.split(['(', ':']).next().map(|c| c.trim().to_string());
            continue;
        }
        let indented = line.starts_with(' ');
        let Some(def) = line.trim_start().strip_prefix("def ") else {
            if !indented && !line.trim().is_empty() && !line.starts_with('#') {
                class = None;
            }
            continue;
        };
        let Some(open) = def.find('(') else { continue };
        let name = &def[..open];
        let start = at + (line.len() - line.trim_start().len()) + 4 + open + 1;
        let Some((params, _)) = until_closing(&pyi[start..]) else {
            continue;
        };
        let params: Params = top_level_parts(params)
            .iter()
            .map(|p| stub_param(p))
            .filter(|p| p != "self")
            .collect();
        let key = match (indented, name, &class) {
            (true, "__init__", Some(c)) => c.clone(),
            (true, n, _) if n.starts_with('_') => continue,
            _ => name.to_string(),
        };
        out.entry(key).or_default().push(params);
    }
    out
}

/// The code of a Markdown text (inline spans, and fenced blocks, whose fences split into empty
/// spans around them) that calls or declares one of `names` (`run_episode(…)`,
/// `bkpbs.Controller(…)`, `ctl.plan(…)`): its line, the name and the arguments as written.
pub fn documented_calls<'n>(
    text: &str,
    names: impl Iterator<Item = &'n String> + Clone,
) -> Vec<(usize, String, Params)> {
    let mut out = Vec::new();
    let mut offset = 0;
    let spans: Vec<&str> = text.split('`').collect();
    for (i, span) in spans.iter().enumerate() {
        let line = text[..offset].matches('\n').count() + 1;
        offset += span.len() + 1;
        if i % 2 == 0 {
            continue;
        }
        for name in names.clone() {
            let Some(at) = span.find(&format!("{name}(")) else {
                continue;
            };
            let before = span[..at].chars().last();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue;
            }
            let Some((args, _)) = until_closing(&span[at + name.len() + 1..]) else {
                continue;
            };
            let args = top_level_parts(args)
                .iter()
                .map(|a| a.replace(' ', ""))
                .collect();
            out.push((line, name.clone(), args));
        }
    }
    out
}

/// Whether a written call or signature `args` fits the stub's `params`: a full signature (it has
/// `*` or `**name`) must equal them; a call's bare-name positional arguments must be named as
/// the parameters they stand for, and its keywords must be parameters (or go to `**kwargs`).
pub fn fits(args: &Params, params: &Params) -> bool {
    if args.iter().any(|a| a == "*" || a.starts_with("**")) {
        return args == params;
    }
    let positional: Vec<&String> = params
        .iter()
        .take_while(|p| *p != "*" && !p.starts_with("**"))
        .collect();
    let name_of = |p: &str| p.split('=').next().unwrap_or(p).to_string();
    let names: Vec<String> = params.iter().map(|p| name_of(p)).collect();
    let takes_any = params.iter().any(|p| p.starts_with("**"));
    let mut position = 0;
    for a in args {
        let keyword = a
            .split_once('=')
            .filter(|(key, _)| key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'));
        match keyword {
            Some((key, _)) => {
                if !(names.iter().any(|n| n == key) || takes_any) {
                    return false;
                }
            }
            None => {
                let Some(p) = positional.get(position) else {
                    return false;
                };
                let bare = a.chars().all(|c| c.is_ascii_lowercase() || c == '_');
                if bare && name_of(p) != *a {
                    return false;
                }
                position += 1;
            }
        }
    }
    true
}
