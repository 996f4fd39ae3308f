//! The report's tables, as CSV (for machines, full precision) and Markdown (for reading):
//! system delay and, beside it, the paper's arrived-only mean delay per λ (rows planners,
//! columns α), controllable collision rate per planner (rows λ, columns α), and one long
//! summary of every (planner, α, λ).
//!
//! A Markdown entry is the mean over seeds ± the half-width of its 95 % interval, or, from 2 up
//! to fewer than [`INTERVAL_MIN_SEEDS`] seeds, the mean and then each seed's value in seed order
//! (`6.35 (seeds 3.62, 9.08)`), where such an interval would mostly show how few seeds there
//! are. The CSV files keep the interval either way.

use super::stats::{t_975, Estimate, INTERVAL_MIN_SEEDS};
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

/// A delay table: its file-name prefix, Markdown heading and explanation, its estimate and the
/// per-seed values behind it.
struct DelayKind {
    file: &'static str,
    heading: &'static str,
    explanation: &'static str,
    of: fn(Option<&Group>) -> Option<&Estimate>,
    samples: fn(&Group) -> &[f64],
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
    samples: |g| &g.samples.system_delay,
};

/// The paper's delay: the vehicles that arrived only.
const ARRIVED_DELAY: DelayKind = DelayKind {
    file: "delay",
    heading: "Mean travel delay (s)",
    explanation: "The paper's delay: per episode the mean delay of the vehicles that arrived \
                  without collision, then the mean over seeds. Bold: lowest mean in the column.",
    of: delay_of,
    samples: |g| &g.samples.delay,
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

/// Whether an entry lists its seeds' values instead of an interval: 2 up to fewer than
/// [`INTERVAL_MIN_SEEDS`] values.
fn lists_seeds(e: &Estimate) -> bool {
    (2..INTERVAL_MIN_SEEDS).contains(&e.n)
}

/// "m ± c" with `decimals`, or "m (seeds a, b)" with the values of `samples` (the seeds' values
/// behind `e`, in seed order) when [`lists_seeds`]; "(n=k)" appended when fewer than `full`
/// seeds, "–" for nothing.
fn md_cell(
    e: Option<&Estimate>,
    samples: &[f64],
    decimals: usize,
    scale: f64,
    full: usize,
) -> String {
    let Some(e) = e else {
        return "–".into();
    };
    let mut s = format!("{:.decimals$}", e.mean * scale);
    if lists_seeds(e) {
        let values: Vec<String> = samples
            .iter()
            .map(|v| format!("{:.decimals$}", v * scale))
            .collect();
        s += &format!(" (seeds {})", values.join(", "));
    } else if let Some(c) = e.ci95 {
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

/// Every estimate the Markdown tables show: each group's system delay, delay and collision rate.
fn shown(s: &Summary) -> impl Iterator<Item = &Estimate> {
    s.groups.iter().flat_map(|g| {
        [&g.system_delay, &g.delay, &g.collision_rate]
            .into_iter()
            .flatten()
    })
}

/// Why an entry of few seeds lists them: what the interval would be, and how to read the list.
fn few_seeds_why() -> String {
    let few = 2..INTERVAL_MIN_SEEDS;
    let t: Vec<String> = few
        .clone()
        .map(|n| format!("{:.1}", t_975(n - 1)))
        .collect();
    let n: Vec<String> = few.map(|n| n.to_string()).collect();
    format!(
        "No 95 % interval below {INTERVAL_MIN_SEEDS} seeds: t(0.975, n − 1) is {} for {} seeds, \
         so it would say more about how few seeds there are than about the planners. A seed is \
         the same traffic for every planner, so the values in the same place compare planners on \
         equal terms (`bkpbs report --versus` tests the differences seed by seed).",
        t.join(", "),
        n.join(", "),
    )
}

/// The title and what the grid holds and how its entries read: the interval, or each seed's
/// value where a cell has too few seeds for one ([`lists_seeds`]; every cell, or some).
fn md_intro(s: &Summary) -> String {
    let mut md = String::from("# Campaign report\n\n");
    md += &format!(
        "{} planners × {} α × {} λ, {} seeds per cell ({} episodes). ",
        s.planners.len(),
        s.alphas.len(),
        s.lambdas.len(),
        s.seeds,
        s.groups.iter().map(|g| g.episodes).sum::<usize>(),
    );
    let interval = "mean over seeds ± half-width of the 95 % confidence interval, t(0.975, n − 1) \
                    · s / √n (Student t, s the sample standard deviation)";
    let marks = "\"(n=k)\" marks cells with fewer episodes, \"–\" cells without any.";
    let some = shown(s).any(lists_seeds);
    let all = shown(s).all(|e| e.n < INTERVAL_MIN_SEEDS);
    let why = few_seeds_why();
    md += &match (some, all) {
        (false, _) => format!("Each entry: {interval}; {marks}"),
        (true, true) => format!(
            "Each entry: mean over seeds, then each seed's value in seed order, \"m (seeds a, \
             b)\". {why} {marks}"
        ),
        (true, false) => format!(
            "Each entry: {interval}; {marks} A cell of fewer than {INTERVAL_MIN_SEEDS} seeds \
             shows its mean and then each seed's value in seed order instead, \"m (seeds a, \
             b)\". {why}"
        ),
    };
    md + "\n\n"
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
            let samples = s.get(p, a, l).map_or(&[][..], kind.samples);
            let cell = md_cell(e, samples, 2, 1.0, s.seeds);
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
            let g = s.get(p, a, l);
            let samples = g.map_or(&[][..], |g| &g.samples.collision_rate);
            md += &format!(" {} |", md_cell(rate_of(g), samples, 2, 100.0, s.seeds));
        }
        md += "\n";
    }
    md + "\n"
}

/// A planner label as a file-name part: `bk-pbs (paper)` becomes `bk-pbs_paper`.
pub fn file_stem(label: &str) -> String {
    label.replace(" (", "_").replace(')', "")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::summary::Samples;

    /// A group of planner `p` at α `alpha`, λ 3000, with these per-seed system delays (also its
    /// arrived-only delays) and collision rates.
    fn group(p: &str, alpha: f64, delays: &[f64], rates: &[f64]) -> Group {
        Group {
            planner: p.into(),
            alpha,
            lambda: 3000.0,
            episodes: delays.len(),
            system_delay: Estimate::of(delays),
            own_speed_delay: None,
            delay: Estimate::of(delays),
            collision_rate: Estimate::of(rates),
            throughput: None,
            mean_speed: None,
            stranded: None,
            never_inserted: None,
            samples: Samples {
                system_delay: delays.to_vec(),
                delay: delays.to_vec(),
                collision_rate: rates.to_vec(),
                ..Samples::default()
            },
        }
    }

    fn summary(groups: Vec<Group>) -> Summary {
        let mut planners: Vec<String> = groups.iter().map(|g| g.planner.clone()).collect();
        planners.dedup();
        let mut alphas: Vec<f64> = groups.iter().map(|g| g.alpha).collect();
        alphas.dedup();
        Summary {
            planners,
            alphas,
            lambdas: vec![3000.0],
            seeds: groups.iter().map(|g| g.episodes).max().unwrap_or(0),
            groups,
        }
    }

    /// The Markdown row of planner `p` in the first table of `md` (the system delay).
    fn row<'m>(md: &'m str, start: &str) -> &'m str {
        md.lines()
            .find(|l| l.starts_with(start))
            .unwrap_or_else(|| panic!("no row {start} in\n{md}"))
    }

    #[test]
    fn two_seeds_show_each_seeds_value_not_an_interval() {
        // Two seeds: t(0.975, 1) = 12.7 made these "6.25 ± 34.94" s and "12.50 ± 158.83" %.
        let s = summary(vec![
            group("sumo", 0.4, &[3.5, 9.0], &[0.0, 0.25]),
            group("bk-pbs", 0.4, &[2.0, 3.0], &[0.0, 0.0]),
        ]);
        let md = markdown(&s);
        assert!(!md.contains('±'), "{md}");
        assert_eq!(row(&md, "| sumo |"), "| sumo | 6.25 (seeds 3.50, 9.00) |");
        assert_eq!(
            row(&md, "| bk-pbs |"),
            "| bk-pbs | **2.50 (seeds 2.00, 3.00)** |"
        );
        assert_eq!(row(&md, "| 3000 |"), "| 3000 | 12.50 (seeds 0.00, 25.00) |");
        assert!(
            md.contains("Each entry: mean over seeds, then each seed's value in seed order")
                && md.contains("t(0.975, n − 1) is 12.7, 4.3, 3.2 for 2, 3, 4 seeds"),
            "{md}"
        );
    }

    #[test]
    fn five_seeds_keep_the_interval_and_the_intro_of_the_committed_reports() {
        let delays = [1.0, 2.0, 3.0, 4.0, 5.0];
        let md = markdown(&summary(vec![group("sumo", 0.4, &delays, &[0.0; 5])]));
        // mean 3, t(0.975, 4) · √2.5 / √5 = 2.776 · 0.7071 = 1.96
        assert_eq!(row(&md, "| sumo |"), "| sumo | **3.00 ± 1.96** |");
        assert!(md.starts_with(
            "# Campaign report\n\n1 planners × 1 α × 1 λ, 5 seeds per cell (5 episodes). Each \
             entry: mean over seeds ± half-width of the 95 % confidence interval, t(0.975, n − \
             1) · s / √n (Student t, s the sample standard deviation); \"(n=k)\" marks cells with \
             fewer episodes, \"–\" cells without any.\n\n## "
        ));
    }

    #[test]
    fn a_cell_short_of_seeds_lists_them_among_cells_with_intervals() {
        let md = markdown(&summary(vec![
            group("sumo", 0.4, &[1.0, 2.0, 3.0, 4.0, 5.0], &[0.0; 5]),
            group("sumo", 0.8, &[1.0, 2.0, 6.0], &[0.0; 3]),
        ]));
        assert_eq!(
            row(&md, "| sumo |"),
            "| sumo | **3.00 ± 1.96** | **3.00 (seeds 1.00, 2.00, 6.00) (n=3)** |"
        );
        assert!(
            md.contains("A cell of fewer than 5 seeds shows its mean and then each seed's value"),
            "{md}"
        );
    }

    #[test]
    fn one_seed_is_its_value_alone() {
        let md = markdown(&summary(vec![group("sumo", 0.4, &[2.5], &[0.1])]));
        assert_eq!(row(&md, "| sumo |"), "| sumo | **2.50** |");
        assert_eq!(row(&md, "| 3000 |"), "| 3000 | 10.00 |");
        assert!(!md.contains("seeds 2.50") && md.contains("Each entry: mean over seeds ±"));
    }
}
