//! The documentation stays true to the code it describes, without mdbook: every relative link
//! of the guide (README.md, bindings/README.md, docs/src/, the READMEs of results/, models/ and sumo_net/) names a file
//! that exists and a heading that is there, every `bkpbs …` command in its shell blocks is one
//! the binary accepts, and no doc comment in the code cites a README section or DESIGN §, which
//! move (the guide's chapters are the place to link instead). Each check fails with file and
//! line, so a reader knows what to fix. The pieces are in `tests/docs/`: Markdown (`markdown.rs`),
//! the link checker (`links.rs`), reading commands (`commands.rs`) and finding citations in doc
//! comments (`citations.rs`).
//!
//! Facts the guide states that the code decides are checked against the code where that is
//! cheap: every column of every per-episode CSV file has its row in the metrics chapter and no
//! other (`columns.rs`), every `bkpbs SUB --flag` written inline in a document or a source
//! comment names a subcommand and flags the binary has, the Python signatures the guide writes
//! are the stubs' (`signatures.rs`), the documented minimum Rust is `Cargo.toml`'s
//! `rust-version`, and the README lists every committed result.

#[path = "docs/citations.rs"]
mod citations;
#[path = "docs/columns.rs"]
mod columns;
#[path = "docs/commands.rs"]
mod commands;
#[path = "docs/links.rs"]
mod links;
#[path = "docs/markdown.rs"]
mod markdown;
#[path = "docs/signatures.rs"]
mod signatures;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use citations::{cited_lines, cited_sections};
use columns::{column_differences, documented_columns, section};
use commands::{
    concrete, documented_commands, flags_of, inline_mentions, invocations, rejected, shell_lines,
    words,
};
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

/// The header of a scenario file's CSV, as the code writes it (no rows).
fn scenario_header<T: serde::Serialize + Default>() -> Vec<String> {
    let bytes = bkpbs::episode::sumocfg::csv_of::<T>(&[]);
    let text = String::from_utf8(bytes).expect("a CSV header is text");
    text.trim_end().split(',').map(String::from).collect()
}

#[test]
fn every_column_of_every_episode_file_is_documented_in_the_metrics_chapter() {
    use bkpbs::episode::rows::{CollisionRow, TimingRow, VehicleRow};
    use bkpbs::episode::summary::{Summary, Traffic};
    use bkpbs::episode::sumocfg::{RegionEntryRow, RegionRow};
    let metrics = std::fs::read_to_string(root().join("docs/src/metrics.md")).unwrap();
    let scenario = [
        ("Its `episode.csv`", Summary::header(Traffic::Scenario)),
        (
            "Its `vehicles.csv`",
            VehicleRow::columns(Traffic::Scenario)
                .iter()
                .map(|c| c.to_string())
                .collect(),
        ),
        ("`regions.csv`", scenario_header::<RegionRow>()),
        ("`entries.csv`", scenario_header::<RegionEntryRow>()),
    ];
    let scenario: Vec<(&str, Vec<&str>, String)> = scenario
        .iter()
        .map(|(h, cols)| {
            let file = format!(
                "a scenario's {}",
                h.trim_start_matches("Its ").replace('`', "")
            );
            (*h, cols.iter().map(String::as_str).collect(), file)
        })
        .collect();
    let mut files: Vec<(String, Vec<&str>, String)> = vec![
        (
            "### `episode.csv`".into(),
            Summary::columns(Traffic::Demand).to_vec(),
            "episode.csv".into(),
        ),
        (
            "### `vehicles.csv`".into(),
            VehicleRow::columns(Traffic::Demand).to_vec(),
            "vehicles.csv".into(),
        ),
        (
            "### `collisions.csv`".into(),
            CollisionRow::columns().to_vec(),
            "collisions.csv".into(),
        ),
        (
            "### `timing.csv`".into(),
            TimingRow::columns().to_vec(),
            "timing.csv".into(),
        ),
    ];
    files.extend(
        scenario
            .into_iter()
            .map(|(h, cols, file)| (format!("#### {h}"), cols, file)),
    );
    let problems: Vec<String> = files
        .iter()
        .flat_map(|(heading, written, file)| column_differences(&metrics, heading, file, written))
        .collect();
    assert!(
        problems.is_empty(),
        "docs/src/metrics.md and the CSV files the code writes disagree:\n{}",
        problems.join("\n")
    );
}

#[test]
fn column_tables_are_read_from_their_own_section() {
    let md = "## A\n### `a.csv`\n| column | unit |\n| --- | --- |\n| `x` | s |\n\
              | `y`, `z` | – | see `w` |\n```\n### `b.csv`\n```\n#### Sub\n| `u` | |\n\
              ### `b.csv`\n| `v` | |\n";
    let a = section(md, "### `a.csv`").unwrap();
    assert_eq!(
        documented_columns(&a),
        BTreeSet::from(["u", "x", "y", "z"].map(String::from))
    );
    let problems = column_differences(md, "### `b.csv`", "b.csv", &["v", "new"]);
    assert_eq!(problems.len(), 1, "{problems:?}");
    assert!(problems[0].contains("column `new` is written but not documented"));
    let stale = column_differences(md, "### `a.csv`", "a.csv", &["x", "y", "z"]);
    assert_eq!(stale.len(), 1, "{stale:?}");
    assert!(stale[0].contains("`u` is documented"), "{stale:?}");
    assert!(!column_differences(md, "### `c.csv`", "c.csv", &[]).is_empty());
}

/// The text between `start` and the next `end` after it, in `text`.
fn between<'t>(text: &'t str, start: &str, end: &str) -> Option<&'t str> {
    let from = text.find(start)? + start.len();
    Some(&text[from..from + text[from..].find(end)?])
}

#[test]
fn the_documented_minimum_rust_is_cargo_tomls_rust_version() {
    let root = root();
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap();
    let manifest: toml::Table = toml::from_str(&read("Cargo.toml")).unwrap();
    let wanted = manifest["package"]["rust-version"]
        .as_str()
        .expect("Cargo.toml's [package] names its rust-version")
        .to_string();
    let stated = [
        ("README.md", "Rust toolchain (", "+)"),
        ("docs/src/getting-started.md", "Rust toolchain (", "+)"),
        ("scripts/ensure-deps.sh", "Rust toolchain (", " or newer)"),
    ];
    for (file, start, end) in stated {
        let text = read(file);
        let version = between(&text, start, end);
        assert_eq!(
            version,
            Some(wanted.as_str()),
            "{file} names another minimum Rust than Cargo.toml's rust-version {wanted}"
        );
    }
}

#[test]
fn the_readme_lists_every_committed_result() {
    let root = root();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let mut dirs: Vec<String> = std::fs::read_dir(root.join("results"))
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().join("README.md").is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    dirs.sort();
    assert!(dirs.len() > 5, "found only {dirs:?}");
    let missing: Vec<&String> = dirs
        .iter()
        .filter(|d| !readme.contains(&format!("(results/{d}/README.md)")))
        .collect();
    assert!(
        missing.is_empty(),
        "README.md's list of results lacks results/{missing:?}"
    );
}

/// Every source file whose comments, docstrings and messages may name a `bkpbs` command to a
/// reader (the library, the binary, the Python package, the examples; not the tests, whose
/// helpers say `bkpbs args`), read as text with Python's ``double`` backticks made single,
/// relative to the root.
fn sources(root: &Path) -> Vec<(PathBuf, String)> {
    let mut found = Vec::new();
    for dir in ["src", "bindings/src", "bindings/python", "examples"] {
        walk(&root.join(dir), &mut found);
    }
    found
        .into_iter()
        .filter(|p| ["rs", "py", "pyi"].iter().any(|e| has_ext(p, e)))
        .map(|p| {
            let text = std::fs::read_to_string(&p).unwrap().replace("``", "`");
            (p.strip_prefix(root).unwrap().to_path_buf(), text)
        })
        .collect()
}

#[test]
fn every_inline_bkpbs_command_names_a_real_subcommand_and_flags() {
    let root = root();
    let mut texts: Vec<(PathBuf, String)> = read_docs(&root).into_iter().collect();
    texts.extend(sources(&root));
    let mentions: Vec<(String, String, Vec<String>)> = texts
        .iter()
        .flat_map(|(path, text)| {
            inline_mentions(text)
                .into_iter()
                .map(move |(line, sub, flags)| (format!("{}:{line}", path.display()), sub, flags))
        })
        .collect();
    assert!(
        mentions.len() > 100,
        "found only {} mentions",
        mentions.len()
    );
    let subs: BTreeSet<&str> = mentions.iter().map(|(_, s, _)| s.as_str()).collect();
    let known: BTreeMap<&str, Option<BTreeSet<String>>> =
        subs.into_iter().map(|s| (s, flags_of(s))).collect();
    let mut problems = Vec::new();
    for (place, sub, flags) in &mentions {
        match &known[sub.as_str()] {
            None => problems.push(format!("{place}: `bkpbs {sub}`: no such subcommand")),
            Some(have) => problems.extend(
                flags
                    .iter()
                    .filter(|f| !have.contains(*f))
                    .map(|f| format!("{place}: `bkpbs {sub} {f}`: no such flag")),
            ),
        }
    }
    assert!(
        problems.is_empty(),
        "inline commands the binary does not have:\n{}",
        problems.join("\n")
    );
}

#[test]
fn inline_mentions_keep_the_subcommand_and_its_flags() {
    let text = "Run `bkpbs report DIR --versus a,b` or\n`target/release/bkpbs campaign \
                [--seeds 5] --out=x`; not `bkpbs …` nor `cargo x`.\n";
    let found = inline_mentions(text);
    assert_eq!(found.len(), 2, "{found:?}");
    assert_eq!(found[0], (1, "report".into(), vec!["--versus".to_string()]));
    assert_eq!(found[1].0, 2);
    assert_eq!(found[1].2, ["--seeds", "--out"]);
}

#[test]
fn the_python_signatures_the_guide_writes_are_the_stubs() {
    let root = root();
    let pyi = std::fs::read_to_string(root.join("bindings/python/bkpbs/_bkpbs.pyi")).unwrap();
    let stubs = signatures::stub_signatures(&pyi);
    for name in ["run_episode", "Controller", "load_predictor", "predict"] {
        assert!(stubs.contains_key(name), "no stub for {name}: {stubs:?}");
    }
    let mut problems = Vec::new();
    let mut seen = 0;
    for (path, text) in read_docs(&root) {
        for (line, name, args) in signatures::documented_calls(&text, stubs.keys()) {
            seen += 1;
            if !stubs[&name]
                .iter()
                .any(|params| signatures::fits(&args, params))
            {
                problems.push(format!(
                    "{}:{line}: `{name}({})` does not fit the stub's {name}({})",
                    path.display(),
                    args.join(", "),
                    stubs[&name]
                        .iter()
                        .map(|p| p.join(", "))
                        .collect::<Vec<_>>()
                        .join(" | ")
                ));
            }
        }
    }
    assert!(seen > 10, "found only {seen} documented calls");
    assert!(
        problems.is_empty(),
        "Python calls and signatures the documents write that bindings/python/bkpbs/_bkpbs.pyi \
         does not have:\n{}",
        problems.join("\n")
    );
}

#[test]
fn signatures_are_compared_as_written() {
    let pyi = "\"\"\"Doc\"\"\"\nclass C:\n    def __init__(self, a: int = 1, **kw: Any) -> None: ...\n\
               \n    def m(self, x: Dict[str, int], y=None) -> int: ...\n\
               def f(\n    p: str,\n    q: Optional[float] = None,\n    *,\n    out: Union[str, \"P\"] = None,\n) -> dict: ...\n";
    let stubs = signatures::stub_signatures(pyi);
    let params = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert_eq!(stubs["C"], [params(&["a=1", "**kw"])]);
    assert_eq!(stubs["m"], [params(&["x", "y=None"])]);
    assert_eq!(stubs["f"], [params(&["p", "q=None", "*", "out=None"])]);
    let calls = signatures::documented_calls(
        "`f(p, q, *, out=None)` and `c.m(x, y=2)`, `bkpbs.f(\"s\", out=d)`, `ff(z)`\n\
         ```python\nC(b=1)\n```\n",
        stubs.keys(),
    );
    let fit: Vec<bool> = calls
        .iter()
        .map(|(_, n, a)| stubs[n].iter().any(|p| signatures::fits(a, p)))
        .collect();
    // The full signature lacks q's default; the call and the fenced C(b=…) (to **kw) fit.
    assert_eq!(fit, [false, true, true, true], "{calls:?}");
    assert!(!signatures::fits(&params(&["y"]), &stubs["m"][0]));
    assert!(!signatures::fits(&params(&["x", "z=1"]), &stubs["m"][0]));
}
