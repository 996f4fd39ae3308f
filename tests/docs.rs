//! The documentation stays true to the code it describes, without mdbook: every relative link
//! of the guide (README.md, bindings/README.md, docs/src/, the READMEs of results/, models/ and sumo_net/) names a file
//! that exists and a heading that is there, every `bkpbs …` command in its shell blocks is one
//! the binary accepts, and no doc comment in the code cites a README section or DESIGN §, which
//! move (the guide's chapters are the place to link instead). Each check fails with file and
//! line, so a reader knows what to fix. The pieces are in `tests/docs/`: Markdown (`markdown.rs`),
//! the link checker (`links.rs`), reading commands (`commands.rs`) and finding citations in doc
//! comments (`citations.rs`).

#[path = "docs/citations.rs"]
mod citations;
#[path = "docs/commands.rs"]
mod commands;
#[path = "docs/links.rs"]
mod links;
#[path = "docs/markdown.rs"]
mod markdown;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use citations::{cited_lines, cited_sections};
use commands::{concrete, documented_commands, invocations, rejected, shell_lines, words};
use links::{check_links, Tree};
use markdown::{anchors, slug};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every Markdown file the checks cover, relative to the repository root.
fn doc_files(root: &Path) -> Vec<PathBuf> {
    let mut files = vec![
        PathBuf::from("README.md"),
        PathBuf::from("bindings/README.md"),
    ];
    let mut found = Vec::new();
    walk(&root.join("docs/src"), &mut found);
    files.extend(found.iter().filter(|p| has_ext(p, "md")).cloned());
    for dir in ["results", "models", "sumo_net"] {
        found.clear();
        walk(&root.join(dir), &mut found);
        files.extend(
            found
                .drain(..)
                .filter(|p| p.file_name().is_some_and(|n| n == "README.md")),
        );
    }
    files
        .into_iter()
        .map(|p| p.strip_prefix(root).map(Path::to_path_buf).unwrap_or(p))
        .collect()
}

/// Every file under `dir`, depth first, in name order (nothing if `dir` is missing).
pub fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            walk(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// Whether the file name ends in `.ext`.
pub fn has_ext(p: &Path, ext: &str) -> bool {
    p.extension().is_some_and(|e| e == ext)
}

fn read_docs(root: &Path) -> BTreeMap<PathBuf, String> {
    doc_files(root)
        .into_iter()
        .map(|p| {
            let text = std::fs::read_to_string(root.join(&p))
                .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            (p, text)
        })
        .collect()
}

#[test]
fn every_relative_link_names_an_existing_file_and_heading() {
    let root = root();
    let docs = read_docs(&root);
    assert!(docs.len() > 10, "found only {} documents", docs.len());
    let problems = check_links(&Tree {
        docs: &docs,
        root: Some(&root),
    });
    assert!(
        problems.is_empty(),
        "broken links:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_link_checker_reports_a_planted_broken_link_and_anchor() {
    let mut docs = BTreeMap::new();
    let guide = "# Guide\n\n## Set-up: the `make` way\n\nSee [set-up](#set-up-the-make-way), \
                 [other](other.md#part-two), [gone](missing.md) and [typo](other.md#part-3).\n\
                 ```sh\n[not a link](nowhere.md)\n```\n`[code](nowhere.md)`\n";
    docs.insert(PathBuf::from("docs/guide.md"), guide.to_string());
    docs.insert(
        PathBuf::from("docs/other.md"),
        "# Other\n## Part two\n".to_string(),
    );
    let problems = check_links(&Tree {
        docs: &docs,
        root: None,
    });
    assert_eq!(problems.len(), 2, "{problems:#?}");
    assert!(
        problems[0].contains("(missing.md) no file docs/missing.md"),
        "{problems:#?}"
    );
    assert!(
        problems[1].contains("no heading with anchor #part-3"),
        "{problems:#?}"
    );
    assert!(
        problems.iter().all(|p| p.starts_with("docs/guide.md:5:")),
        "{problems:#?}"
    );
}

#[test]
fn slugs_follow_github_and_mdbook() {
    assert_eq!(
        slug(" Results: what the CSV files mean"),
        "results-what-the-csv-files-mean"
    );
    assert_eq!(slug(" `episode.csv`"), "episodecsv");
    assert_eq!(
        slug(" Your own TraCI loop, bkpbs's planner"),
        "your-own-traci-loop-bkpbss-planner"
    );
    assert_eq!(
        slug(" BK-M-A\\* and [the plan](x.md)"),
        "bk-m-a-and-the-plan"
    );
    let twice = anchors("# A\n## Notes\n```\n# not a heading\n```\n## Notes\n");
    assert_eq!(
        twice,
        BTreeSet::from(["a", "notes", "notes-1"].map(String::from))
    );
}

#[test]
fn reading_commands_follows_the_shell_and_usage_notation() {
    let line = "$ FOO=1 xvfb-run -a target/release/bkpbs plot DIR 2>&1 | tee log && bkpbs x > f";
    assert_eq!(invocations(line), vec![vec!["plot", "DIR"], vec!["x"]]);
    let args =
        invocations("bkpbs train --data F.bin [--conditioned|--unconditioned] --seed S").remove(0);
    let expected = ["train", "--data", "F.bin", "--conditioned", "--seed", "1"];
    assert_eq!(concrete(&args), expected);
    let args = invocations("bkpbs report DIR [DIR...] --shard k/n --at <when>").remove(0);
    assert_eq!(concrete(&args), ["report", "DIR", "--shard", "1/2"]);
    assert_eq!(
        words("bkpbs demand --out 'a b' # a comment"),
        ["bkpbs", "demand", "--out", "a b"]
    );
    let block = "```sh\nbkpbs a \\\n  --b 1\n```\n```python\nbkpbs c\n```\n";
    assert_eq!(shell_lines(block), vec![(2, "bkpbs a --b 1".to_string())]);
}

#[test]
fn every_documented_command_is_one_the_binary_accepts() {
    let docs = read_docs(&root());
    let commands: Vec<_> = documented_commands(&docs).into_iter().collect();
    assert!(
        commands.len() > 20,
        "found only {} commands",
        commands.len()
    );
    let failures: Vec<String> = std::thread::scope(|s| {
        let runs: Vec<_> = commands
            .chunks(commands.len().div_ceil(4))
            .map(|chunk| s.spawn(move || chunk.iter().filter_map(rejected).collect::<Vec<_>>()))
            .collect();
        runs.into_iter()
            .flat_map(|r| r.join().expect("a --help run panicked"))
            .collect()
    });
    assert!(
        failures.is_empty(),
        "documented commands the binary rejects:\n{}",
        failures.join("\n")
    );
}

#[test]
fn finding_citations_in_doc_comments() {
    let src = "/// See the README's \"How metrics are\n/// computed\".\nfn a() {}\n//! DESIGN §5\n\
               /// for `bkpbs config` and the README.\n/// (see \"Merge deadlock\")\n";
    let lines: Vec<usize> = cited_lines(src).into_iter().map(|(line, _)| line).collect();
    assert_eq!(lines, [1, 4, 6]);
}

#[test]
fn no_doc_comment_cites_a_readme_section_or_design() {
    let found = cited_sections(&root());
    assert!(
        found.is_empty(),
        "doc comments that cite DESIGN § or a README section (link the guide's chapter in docs/src/ \
         instead, or say it in place):\n{}",
        found.join("\n")
    );
}
