//! The report's tables, as CSV (for machines, full precision) and Markdown (for reading):
//! system delay and, beside it, the paper's arrived-only mean delay per λ (rows planners,
//! columns α), controllable collision rate per planner (rows λ, columns α), and one long
//! summary of every (planner, α, λ).

use super::stats::Estimate;
use super::summary::{Group, Summary};

/// A CSV file of the report: its file name and content.
pub struct CsvFile {
    /// File name inside the report directory (e.g. `summary.csv`).
    pub name: String,
    /// The file's content.
    pub bytes: Vec<u8>,
}

/// CSV bytes of `header` and `rows`.
pub(super) fn csv_bytes(header: &[String], rows: &[Vec<String>]) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header).expect("writing to memory");
    for r in rows {
        w.write_record(r).expect("writing to memory");
    }
    w.into_inner().expect("writing to memory")
}

/// Mean, CI half-width and n of an estimate as three CSV cells (empty where undefined).
fn estimate_cells(e: Option<&Estimate>, decimals: usize, scale: f64) -> [String; 3] {
    match e {
        Some(e) => [
            format!("{:.decimals$}", e.mean * scale),
            e.ci95
                .map(|c| format!("{:.decimals$}", c * scale))
                .unwrap_or_default(),
            e.n.to_string(),
        ],
        None => [String::new(), String::new(), "0".into()],
    }
}

fn delay_of(g: Option<&Group>) -> Option<&Estimate> {
    g.and_then(|g| g.delay.as_ref())
}

fn system_delay_of(g: Option<&Group>) -> Option<&Estimate> {
    g.and_then(|g| g.system_delay.as_ref())
}

/// A delay table: its file-name prefix, Markdown heading and explanation, and its estimate.
struct DelayKind {
    file: &'static str,
    heading: &'static str,
    explanation: &'static str,
    of: fn(Option<&Group>) -> Option<&Estimate>,
}

/// The system delay, which leads: every vehicle the demand scheduled, arrived or not.
const SYSTEM_DELAY: DelayKind = DelayKind {
    file: "system_delay",
    heading: "System delay (s)",
    explanation: "Per episode the mean over every vehicle the demand scheduled (crashed ones \
                  excluded) of the time from its scheduled departure to its arrival or the \
                  episode's end, less the free-flow time of the distance it covered: vehicles \
                  stuck in a jam or never inserted count. Then the mean over seeds. Bold: \
                  lowest mean in the column.",
    of: system_delay_of,
};

/// The paper's delay: the vehicles that arrived only.
const ARRIVED_DELAY: DelayKind = DelayKind {
    file: "delay",
    heading: "Mean travel delay (s)",
    explanation: "The paper's delay: per episode the mean delay of the vehicles that arrived \
                  without collision, then the mean over seeds. Bold: lowest mean in the column.",
    of: delay_of,
};

fn rate_of(g: Option<&Group>) -> Option<&Estimate> {
    g.and_then(|g| g.collision_rate.as_ref())
}

/// λ as it appears in file names and headings.
pub fn lambda_label(l: f64) -> String {
    format!("{l}")
}

/// All CSV tables: `system_delay_l<λ>.csv`, `delay_l<λ>.csv`, `collision_rate_<planner>.csv`,
/// `summary.csv`.
pub fn csv_files(s: &Summary) -> Vec<CsvFile> {
    let delays = [SYSTEM_DELAY, ARRIVED_DELAY]
        .into_iter()
        .flat_map(|kind| s.lambdas.iter().map(move |&l| delay_table(s, l, &kind)));
    let rates = s.planners.iter().map(|p| collision_rate_table(s, p));
    delays
        .chain(rates)
        .chain(std::iter::once(summary_table(s)))
        .collect()
}

/// The header of a wide table: `first`, then a mean, CI and n column per α.
fn wide_header(first: &str, alphas: &[f64], unit: &str) -> Vec<String> {
    let triples = alphas.iter().flat_map(|a| {
        [
            format!("a{a}_mean{unit}"),
            format!("a{a}_ci95{unit}"),
            format!("a{a}_n"),
        ]
    });
    std::iter::once(first.to_string()).chain(triples).collect()
}

/// A row of a wide table: `first`, then the cells of `estimate(α)` for every α.
fn wide_row<'s>(
    first: String,
    alphas: &[f64],
    estimate: impl Fn(f64) -> Option<&'s Estimate>,
    decimals: usize,
) -> Vec<String> {
    std::iter::once(first)
        .chain(
            alphas
                .iter()
                .flat_map(|&a| estimate_cells(estimate(a), decimals, 1.0)),
        )
        .collect()
}

/// A delay at λ `l`: rows planners, columns α.
fn delay_table(s: &Summary, l: f64, kind: &DelayKind) -> CsvFile {
    let header = wide_header("planner", &s.alphas, "_s");
    let rows: Vec<Vec<String>> = s
        .planners
        .iter()
        .map(|p| wide_row(p.clone(), &s.alphas, |a| (kind.of)(s.get(p, a, l)), 4))
        .collect();
    CsvFile {
        name: format!("{}_l{}.csv", kind.file, lambda_label(l)),
        bytes: csv_bytes(&header, &rows),
    }
}

/// Controllable collision rate of planner `p`: rows λ, columns α.
fn collision_rate_table(s: &Summary, p: &str) -> CsvFile {
    let header = wide_header("lambda", &s.alphas, "");
    let rows: Vec<Vec<String>> = s
        .lambdas
        .iter()
        .map(|&l| wide_row(lambda_label(l), &s.alphas, |a| rate_of(s.get(p, a, l)), 6))
        .collect();
    CsvFile {
        name: format!("collision_rate_{}.csv", file_stem(p)),
        bytes: csv_bytes(&header, &rows),
    }
}

const SUMMARY_HEADER: [&str; 28] = [
    "planner",
    "alpha",
    "lambda",
    "episodes",
    "system_delay_mean_s",
    "system_delay_ci95_s",
    "system_delay_n",
    "own_speed_delay_mean_s",
    "own_speed_delay_ci95_s",
    "own_speed_delay_n",
    "delay_mean_s",
    "delay_ci95_s",
    "delay_n",
    "collision_rate_mean",
    "collision_rate_ci95",
    "collision_rate_n",
    "throughput_mean_veh_h",
    "throughput_ci95_veh_h",
    "throughput_n",
    "mean_speed_mps",
    "mean_speed_ci95_mps",
    "mean_speed_n",
    "stranded_mean",
    "stranded_ci95",
    "stranded_n",
    "never_inserted_mean",
    "never_inserted_ci95",
    "never_inserted_n",
];

/// One long table, a row per (planner, α, λ) with every estimate.
fn summary_table(s: &Summary) -> CsvFile {
    let header: Vec<String> = SUMMARY_HEADER.iter().map(|s| s.to_string()).collect();
    let rows: Vec<Vec<String>> = s.groups.iter().map(summary_row).collect();
    CsvFile {
        name: "summary.csv".into(),
        bytes: csv_bytes(&header, &rows),
    }
}

fn summary_row(g: &Group) -> Vec<String> {
    let mut r = vec![
        g.planner.clone(),
        format!("{}", g.alpha),
        lambda_label(g.lambda),
        g.episodes.to_string(),
    ];
    r.extend(estimate_cells(g.system_delay.as_ref(), 4, 1.0));
    r.extend(estimate_cells(g.own_speed_delay.as_ref(), 4, 1.0));
    r.extend(estimate_cells(g.delay.as_ref(), 4, 1.0));
    r.extend(estimate_cells(g.collision_rate.as_ref(), 6, 1.0));
    r.extend(estimate_cells(g.throughput.as_ref(), 2, 1.0));
    r.extend(estimate_cells(g.mean_speed.as_ref(), 3, 1.0));
    r.extend(estimate_cells(g.stranded.as_ref(), 2, 1.0));
    r.extend(estimate_cells(g.never_inserted.as_ref(), 2, 1.0));
    r
}

/// "m ± c" with `decimals`, "(n=k)" appended when fewer than `full` seeds, "–" for nothing.
fn md_cell(e: Option<&Estimate>, decimals: usize, scale: f64, full: usize) -> String {
    let Some(e) = e else {
        return "–".into();
    };
    let mut s = format!("{:.decimals$}", e.mean * scale);
    if let Some(c) = e.ci95 {
        s += &format!(" ± {:.decimals$}", c * scale);
    }
    if e.n < full {
        s += &format!(" (n={})", e.n);
    }
    s
}

fn md_header(first: &str, alphas: &[f64]) -> String {
    let mut s = format!("| {first} |");
    for a in alphas {
        s += &format!(" α = {a} |");
    }
    s += "\n| --- |";
    s += &" ---: |".repeat(alphas.len());
    s + "\n"
}

/// The Markdown report: explanation, per λ the system delay then the paper's arrived-only
/// delay (lowest mean per column in bold), collision-rate grids per planner.
pub fn markdown(s: &Summary) -> String {
    let mut md = md_intro(s);
    for &l in &s.lambdas {
        md += &md_delay_section(s, l, &SYSTEM_DELAY);
        md += &md_delay_section(s, l, &ARRIVED_DELAY);
    }
    for p in &s.planners {
        md += &md_collision_section(s, p);
    }
    md
}

/// The title and what the grid holds and how its entries read.
fn md_intro(s: &Summary) -> String {
    let mut md = String::from("# Campaign report\n\n");
    md += &format!(
        "{} planners × {} α × {} λ, {} seeds per cell ({} episodes). Each entry: mean over \
         seeds ± half-width of the 95 % confidence interval, t(0.975, n − 1) · s / √n (Student \
         t, s the sample standard deviation); \"(n=k)\" marks cells with fewer episodes, \"–\" \
         cells without any.\n\n",
        s.planners.len(),
        s.alphas.len(),
        s.lambdas.len(),
        s.seeds,
        s.groups.iter().map(|g| g.episodes).sum::<usize>(),
    );
    md
}

/// A delay at λ `l`: rows planners, columns α, the lowest mean per column in bold.
fn md_delay_section(s: &Summary, l: f64, kind: &DelayKind) -> String {
    let delay_of = kind.of;
    let mut md = format!("## {}, λ = {} veh/h\n\n", kind.heading, lambda_label(l));
    md += kind.explanation;
    md += "\n\n";
    md += &md_header("planner", &s.alphas);
    // Lowest mean per column, compared as printed so that ties are all bold.
    let best: Vec<Option<String>> = s
        .alphas
        .iter()
        .map(|&a| {
            s.planners
                .iter()
                .filter_map(|p| delay_of(s.get(p, a, l)).map(|e| e.mean))
                .min_by(f64::total_cmp)
                .map(|m| format!("{m:.2}"))
        })
        .collect();
    for p in &s.planners {
        md += &format!("| {p} |");
        for (i, &a) in s.alphas.iter().enumerate() {
            let e = delay_of(s.get(p, a, l));
            let cell = md_cell(e, 2, 1.0, s.seeds);
            let bold = e.is_some_and(|e| Some(format!("{:.2}", e.mean)) == best[i]);
            md += &if bold {
                format!(" **{cell}** |")
            } else {
                format!(" {cell} |")
            };
        }
        md += "\n";
    }
    md + "\n"
}

/// The controllable collision rate of planner `p` in percent: rows λ, columns α.
fn md_collision_section(s: &Summary, p: &str) -> String {
    let mut md = format!("## Controllable collision rate (%), {p}\n\n");
    md += "Vehicles removed in collisions involving a CAV, per vehicle inserted.\n\n";
    md += &md_header("λ (veh/h)", &s.alphas);
    for &l in &s.lambdas {
        md += &format!("| {} |", lambda_label(l));
        for &a in &s.alphas {
            md += &format!(" {} |", md_cell(rate_of(s.get(p, a, l)), 2, 100.0, s.seeds));
        }
        md += "\n";
    }
    md + "\n"
}

/// A planner label as a file-name part: `bk-pbs (paper)` becomes `bk-pbs_paper`.
pub fn file_stem(label: &str) -> String {
    label.replace(" (", "_").replace(')', "")
}
