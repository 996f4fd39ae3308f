//! One definition per idea, for the two records every part of bkpbs shares: the episode's
//! summary (`episode::summary::Summary`, the `episode.csv` row of every traffic) and the grid's
//! cell (`campaign::grid::Cell`, one episode of every campaign). A second struct of the same
//! fields anywhere in `src/` (as the scenario path once had its own `ScenarioSummary` and
//! `ScenarioCell` beside them) fails here, naming it: add a field or an optional part to the one
//! definition instead.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A struct with named fields: where it is, its name, its fields' names.
#[derive(Debug, Clone)]
struct Struct {
    file: String,
    name: String,
    fields: Vec<String>,
}

/// The structs with named fields of `text` before its first `#[cfg(test)]` item (test
/// fixtures may shape what they like), as rustfmt lays them out: `struct Name {` at the start
/// of a line, one `name: Type` per line, `}` alone at the start of a line.
fn structs_of(file: &str, text: &str) -> Vec<Struct> {
    let mut out = Vec::new();
    let mut current: Option<Struct> = None;
    for line in text.lines() {
        if line.starts_with("#[cfg(test)]") {
            break;
        }
        if let Some(s) = &mut current {
            if line == "}" {
                out.push(current.take().unwrap());
            } else if let Some(field) = field_name(line) {
                s.fields.push(field);
            }
            continue;
        }
        if let Some(name) = struct_name(line) {
            current = Some(Struct {
                file: file.to_string(),
                name,
                fields: Vec::new(),
            });
        }
    }
    out
}

/// The name of the struct a line opens (`pub struct Name {`, `struct Name<T> {`).
fn struct_name(line: &str) -> Option<String> {
    let rest = line.strip_prefix("pub ").unwrap_or(line);
    let rest = rest.strip_prefix("pub(crate) ").unwrap_or(rest);
    let rest = rest.strip_prefix("struct ")?;
    if !line.trim_end().ends_with('{') {
        return None;
    }
    let name: String = rest
        .chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect();
    (!name.is_empty()).then_some(name)
}

/// The field a line of a struct body declares (`    pub name: Type,`).
fn field_name(line: &str) -> Option<String> {
    let rest = line.strip_prefix("    ")?;
    if rest.starts_with(' ') || rest.starts_with("//") || rest.starts_with('#') {
        return None;
    }
    let rest = rest.strip_prefix("pub ").unwrap_or(rest);
    let rest = rest.strip_prefix("pub(crate) ").unwrap_or(rest);
    let (name, _) = rest.split_once(": ")?;
    name.chars()
        .all(|c| c.is_alphanumeric() || c == '_')
        .then(|| name.to_string())
}

/// Every struct of `src/`.
fn src_structs() -> Vec<Struct> {
    let mut out = Vec::new();
    let mut stack = vec![root().join("src")];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).unwrap();
                out.extend(structs_of(&relative(&path), &text));
            }
        }
    }
    out
}

fn relative(path: &Path) -> String {
    path.strip_prefix(root())
        .unwrap_or(path)
        .to_string_lossy()
        .into_owned()
}

/// One shared record: the file that defines it, the names (column vocabulary) of its fields,
/// what makes another struct a second definition of it, and the structs that look alike but
/// are something else, each with the reason.
struct OneDefinition {
    what: &'static str,
    file: &'static str,
    /// Every field name of the structs of `file`: the record and its parts.
    vocabulary: BTreeSet<String>,
    /// A second definition shares at least this many fields with the vocabulary…
    min_shared: usize,
    /// …and has these fields.
    required: &'static [&'static str],
    not_copies: &'static [(&'static str, &'static str)],
}

impl OneDefinition {
    /// Whether `s` is a second definition: at least `min_shared` of its fields, and three in
    /// four of them, are the record's, the `required` ones among them.
    fn is_copy(&self, s: &Struct) -> bool {
        if s.file == self.file || s.fields.is_empty() {
            return false;
        }
        let shared = s
            .fields
            .iter()
            .filter(|f| self.vocabulary.contains(*f))
            .count();
        let has = |f: &&str| s.fields.iter().any(|g| g == f);
        shared >= self.min_shared
            && 4 * shared >= 3 * s.fields.len()
            && self.required.iter().all(has)
    }

    /// The second definitions among `structs`, as `file: name`.
    fn copies(&self, structs: &[Struct]) -> Vec<String> {
        structs
            .iter()
            .filter(|s| self.is_copy(s))
            .map(|s| format!("{}: {}", s.file, s.name))
            .filter(|found| !self.not_copies.iter().any(|(n, _)| found.ends_with(n)))
            .collect()
    }
}

fn vocabulary(structs: &[Struct], file: &str, only: Option<&str>) -> BTreeSet<String> {
    structs
        .iter()
        .filter(|s| s.file == file && only.is_none_or(|n| s.name == n))
        .flat_map(|s| s.fields.iter().cloned())
        .collect()
}

/// The two shared records, read from `structs`.
fn definitions(structs: &[Struct]) -> [OneDefinition; 2] {
    let summary_file = "src/episode/summary.rs";
    let cell_file = "src/campaign/grid.rs";
    [
        OneDefinition {
            what: "the episode summary (episode::summary::Summary)",
            file: summary_file,
            vocabulary: vocabulary(structs, summary_file, None),
            min_shared: 10,
            required: &[],
            not_copies: &[],
        },
        OneDefinition {
            what: "the grid's cell (campaign::grid::Cell)",
            file: cell_file,
            vocabulary: vocabulary(structs, cell_file, Some("Cell")),
            min_shared: 3,
            required: &["planner", "seed"],
            not_copies: &[
                (
                    "src/train/collect.rs: EpisodeSpec",
                    "an episode of a training collection's cycling plan, not of a campaign grid \
                     (the train layer lies below campaign)",
                ),
                (
                    "src/episode/sumocfg/region_rows.rs: RegionKey",
                    "the lead columns a scenario episode writes into its own regions.csv and \
                     entries.csv rows (the episode layer lies below campaign); it goes when the \
                     collection adds every file's lead columns from the cell",
                ),
            ],
        },
    ]
}

#[test]
fn the_summary_and_the_grid_cell_are_each_defined_once() {
    let structs = src_structs();
    for d in definitions(&structs) {
        assert!(
            d.vocabulary.len() >= 7,
            "{} not found in {}: {:?}",
            d.what,
            d.file,
            d.vocabulary
        );
        let copies = d.copies(&structs);
        assert!(
            copies.is_empty(),
            "a second definition of {} (add a field or an optional part to the one in {} \
             instead):\n{}",
            d.what,
            d.file,
            copies.join("\n")
        );
    }
}

/// The check finds what it is for: the scenario path's summary and cell as they were before
/// the one definitions, and a renamed copy of each, planted in a file of `src/`.
#[test]
fn a_planted_second_definition_is_found() {
    let structs = src_structs();
    let planted = r#"
pub struct ScenarioSummary {
    pub scenario: String,
    pub planner: String,
    pub alpha: f64,
    pub cav_types: String,
    pub seed: u64,
    pub sumo_version: String,
    pub steps: u32,
    pub regions: String,
    pub inserted: usize,
    pub never_inserted: usize,
    pub inserted_cav: usize,
    pub cav_share: f64,
    pub in_region: usize,
    pub arrived: usize,
    pub crashed: usize,
    pub present: usize,
    pub controllable_crashed: usize,
    pub hdv_collisions: usize,
    pub mean_time_loss_s: Option<f64>,
    pub plan_stats: PlanStats,
}

pub struct ScenarioCell {
    pub planner: String,
    pub sumocfg: PathBuf,
    pub alpha: f64,
    pub seed: u64,
}
"#;
    let mut with_planted = structs.clone();
    with_planted.extend(structs_of("src/campaign/scenarios/grid.rs", planted));
    for s in structs.iter().filter(|s| {
        (s.file == "src/episode/summary.rs" && s.name == "Summary")
            || (s.file == "src/campaign/grid.rs" && s.name == "Cell")
    }) {
        with_planted.push(Struct {
            file: "src/report/copy.rs".into(),
            name: format!("{}Copy", s.name),
            fields: s.fields.clone(),
        });
    }
    let [summary, cell] = definitions(&structs);
    assert_eq!(
        summary.copies(&with_planted),
        [
            "src/campaign/scenarios/grid.rs: ScenarioSummary",
            "src/report/copy.rs: SummaryCopy"
        ]
    );
    assert_eq!(
        cell.copies(&with_planted),
        [
            "src/campaign/scenarios/grid.rs: ScenarioCell",
            "src/report/copy.rs: CellCopy"
        ]
    );
}
