//! Doc comments that cite a README section or DESIGN §: both move (the README is now a front
//! door and the guide's chapters hold the sections), so code should link a chapter in
//! `docs/src/` or say what it means in place.

use std::path::Path;

use super::{has_ext, walk};

/// Section titles the README had when it was the whole book; a doc comment quoting one is a
/// reference into a README that no longer has it.
const FORMER_README_SECTIONS: [&str; 21] = [
    "Usage",
    "The scenario",
    "The planner",
    "BK-PBS",
    "Merge deadlock",
    "Safety shield",
    "Predictor",
    "Evaluation",
    "Cost",
    "RL-PPO",
    "Gymnasium and PettingZoo",
    "Other networks",
    "Results: what the CSV files mean",
    "Collision forensics",
    "Trajectories and figures of one episode",
    "How metrics are computed",
    "Calibration of the default scenario",
    "HDV driver profiles",
    "Campaigns",
    "Architecture",
    "Design notes",
];

/// The doc comments (`///`, `//!`) of a Rust file as blocks of consecutive lines: the joined
/// text and, per line, its offset in that text and its line number.
fn doc_blocks(source: &str) -> Vec<(String, Vec<(usize, usize)>)> {
    let mut blocks: Vec<(String, Vec<(usize, usize)>)> = Vec::new();
    let mut open = false;
    for (n, line) in source.lines().enumerate() {
        let t = line.trim_start();
        let Some(body) = t.strip_prefix("///").or_else(|| t.strip_prefix("//!")) else {
            open = false;
            continue;
        };
        if !open {
            blocks.push((String::new(), Vec::new()));
            open = true;
        }
        let (text, lines) = blocks.last_mut().expect("just pushed");
        lines.push((text.len(), n + 1));
        text.push_str(body.trim());
        text.push(' ');
    }
    blocks
}

/// What in one doc-comment text cites DESIGN § or a README section, as byte offsets.
fn citations(text: &str) -> Vec<usize> {
    let mut at: Vec<usize> = ["DESIGN §", "DESIGN.md"]
        .iter()
        .flat_map(|pat| text.match_indices(pat).map(|(i, _)| i))
        .collect();
    // "README" and the quote that names its section, as (start, end of the gap) pairs.
    let readme: Vec<(usize, usize)> = text
        .match_indices("README")
        .filter_map(|(i, _)| {
            let after = &text[i + "README".len()..];
            let gap = after.find(['"', '“'])?;
            (gap <= 12 && !after[..gap].contains(['.', ')', '`'])).then_some((i, i + 6 + gap))
        })
        .collect();
    at.extend(readme.iter().map(|r| r.0));
    for title in FORMER_README_SECTIONS {
        let quoted = format!("\"{title}\"");
        let found = text.match_indices(&quoted).map(|(i, _)| i);
        at.extend(found.filter(|&i| !readme.iter().any(|r| r.0 <= i && i <= r.1)));
    }
    at.sort_unstable();
    at.dedup();
    at
}

/// The lines of a Rust source whose doc comments cite DESIGN § or a README section, each with
/// the start of what it cites.
pub fn cited_lines(source: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (text, lines) in doc_blocks(source) {
        for at in citations(&text) {
            let line = lines
                .iter()
                .rev()
                .find(|(offset, _)| *offset <= at)
                .map_or(0, |l| l.1);
            let excerpt: String = text[at..].chars().take(60).collect();
            out.push((line, excerpt.trim_end().to_string()));
        }
    }
    out
}

pub fn cited_sections(root: &Path) -> Vec<String> {
    let mut files = Vec::new();
    walk(&root.join("src"), &mut files);
    walk(&root.join("bindings/src"), &mut files);
    let mut out = Vec::new();
    for file in files.iter().filter(|p| has_ext(p, "rs")) {
        let source = std::fs::read_to_string(file).expect("reading a source file");
        let shown = file
            .strip_prefix(root)
            .unwrap_or(file)
            .display()
            .to_string();
        for (line, excerpt) in cited_lines(&source) {
            out.push(format!("{shown}:{line}: {excerpt}"));
        }
    }
    out
}
