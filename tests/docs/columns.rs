//! The column tables of the guide's metrics chapter: the section under a heading, and the
//! column names its table rows document, so that every column the code writes is checked
//! against them (and no documented column is one the code no longer writes).

use std::collections::BTreeSet;

/// The lines under the heading line `heading` (exactly as written, `###` and all) up to the
/// next heading of the same or a higher level, fenced code blocks skipped; `None` without it.
pub fn section<'t>(text: &'t str, heading: &str) -> Option<Vec<&'t str>> {
    let level = heading.chars().take_while(|&c| c == '#').count();
    let (mut out, mut fenced, mut inside) = (Vec::new(), false, false);
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let hashes = line.chars().take_while(|&c| c == '#').count();
        let is_heading = hashes > 0 && line[hashes..].starts_with(' ');
        if inside && is_heading && hashes <= level {
            break;
        }
        if inside {
            out.push(line);
        }
        inside = inside || line.trim_end() == heading;
    }
    inside.then_some(out)
}

/// The names in backticks in the first cell of each table row of `lines` (a row may document
/// several columns: `` `collider`, `collider_type` ``); the header row has none.
pub fn documented_columns(lines: &[&str]) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in lines {
        let Some(row) = line.trim().strip_prefix('|') else {
            continue;
        };
        let first = row.split('|').next().unwrap_or("");
        out.extend(
            first
                .split('`')
                .skip(1)
                .step_by(2)
                .filter(|name| !name.is_empty())
                .map(String::from),
        );
    }
    out
}

/// How the columns `written` by the code and those the section `heading` of `text` documents
/// differ, one line per difference (empty: they agree).
pub fn column_differences(text: &str, heading: &str, file: &str, written: &[&str]) -> Vec<String> {
    let Some(lines) = section(text, heading) else {
        return vec![format!("no section `{heading}` documents {file}")];
    };
    let documented = documented_columns(&lines);
    let written: BTreeSet<String> = written.iter().map(|c| c.to_string()).collect();
    let missing = written
        .difference(&documented)
        .map(|c| format!("{file}: column `{c}` is written but not documented under `{heading}`"));
    let stale = documented
        .difference(&written)
        .map(|c| format!("{file}: `{c}` is documented under `{heading}` but not written"));
    missing.chain(stale).collect()
}
