//! The report's tables, as CSV (for machines, full precision) and Markdown (for reading):
//! mean delay per λ (rows planners, columns α), controllable collision rate per planner (rows λ,
//! columns α), and one long summary of every (planner, α, λ).

use super::stats::Estimate;
use super::summary::{Group, Summary};

/// A CSV file of the report: its file name and content.
pub struct CsvFile {
    pub name: String,
    pub bytes: Vec<u8>,
}

fn csv_bytes(header: &[String], rows: &[Vec<String>]) -> Vec<u8> {
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

/// The per-α column triple of a wide table.
fn alpha_columns(alphas: &[f64], unit: &str) -> Vec<String> {
    alphas
        .iter()
        .flat_map(|a| {
            [
                format!("a{a}_mean{unit}"),
                format!("a{a}_ci95{unit}"),
                format!("a{a}_n"),
            ]
        })
        .collect()
}

fn delay_of(g: Option<&Group>) -> Option<&Estimate> {
    g.and_then(|g| g.delay.as_ref())
}

fn rate_of(g: Option<&Group>) -> Option<&Estimate> {
    g.and_then(|g| g.collision_rate.as_ref())
}

/// λ as it appears in file names and headings.
pub fn lambda_label(l: f64) -> String {
    format!("{l}")
}

/// All CSV tables: `delay_l<λ>.csv`, `collision_rate_<planner>.csv`, `summary.csv`.
pub fn csv_files(s: &Summary) -> Vec<CsvFile> {
    let mut files = Vec::new();
    for &l in &s.lambdas {
        let header: Vec<String> = std::iter::once("planner".to_string())
            .chain(alpha_columns(&s.alphas, "_s"))
            .collect();
        let rows: Vec<Vec<String>> = s
            .planners
            .iter()
            .map(|p| {
                std::iter::once(p.clone())
                    .chain(
                        s.alphas
                            .iter()
                            .flat_map(|&a| estimate_cells(delay_of(s.get(p, a, l)), 4, 1.0)),
                    )
                    .collect()
            })
            .collect();
        files.push(CsvFile {
            name: format!("delay_l{}.csv", lambda_label(l)),
            bytes: csv_bytes(&header, &rows),
        });
    }
    for p in &s.planners {
        let header: Vec<String> = std::iter::once("lambda".to_string())
            .chain(alpha_columns(&s.alphas, ""))
            .collect();
        let rows: Vec<Vec<String>> = s
            .lambdas
            .iter()
            .map(|&l| {
                std::iter::once(lambda_label(l))
                    .chain(
                        s.alphas
                            .iter()
                            .flat_map(|&a| estimate_cells(rate_of(s.get(p, a, l)), 6, 1.0)),
                    )
                    .collect()
            })
            .collect();
        files.push(CsvFile {
            name: format!("collision_rate_{p}.csv"),
            bytes: csv_bytes(&header, &rows),
        });
    }
    let header: Vec<String> = [
        "planner",
        "alpha",
        "lambda",
        "episodes",
        "delay_mean_s",
        "delay_ci95_s",
        "delay_n",
        "collision_rate_mean",
        "collision_rate_ci95",
        "collision_rate_n",
        "throughput_mean_veh_h",
        "throughput_ci95_veh_h",
        "throughput_n",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let rows: Vec<Vec<String>> = s
        .groups
        .iter()
        .map(|g| {
            let mut r = vec![
                g.planner.clone(),
                format!("{}", g.alpha),
                lambda_label(g.lambda),
                g.episodes.to_string(),
            ];
            r.extend(estimate_cells(g.delay.as_ref(), 4, 1.0));
            r.extend(estimate_cells(g.collision_rate.as_ref(), 6, 1.0));
            r.extend(estimate_cells(g.throughput.as_ref(), 2, 1.0));
            r
        })
        .collect();
    files.push(CsvFile {
        name: "summary.csv".into(),
        bytes: csv_bytes(&header, &rows),
    });
    files
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

/// The Markdown report: explanation, delay tables per λ (lowest mean per column in bold),
/// collision-rate grids per planner.
pub fn markdown(s: &Summary) -> String {
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
    for &l in &s.lambdas {
        md += &format!(
            "## Mean travel delay (s), λ = {} veh/h\n\n",
            lambda_label(l)
        );
        md += "Per episode the mean delay of the vehicles that arrived without collision, then \
               the mean over seeds. Bold: lowest mean in the column.\n\n";
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
        md += "\n";
    }
    for p in &s.planners {
        md += &format!("## Controllable collision rate (%), {p}\n\n");
        md += "Vehicles removed in collisions involving a CAV, per vehicle inserted.\n\n";
        md += &md_header("λ (veh/h)", &s.alphas);
        for &l in &s.lambdas {
            md += &format!("| {} |", lambda_label(l));
            for &a in &s.alphas {
                md += &format!(" {} |", md_cell(rate_of(s.get(p, a, l)), 2, 100.0, s.seeds));
            }
            md += "\n";
        }
        md += "\n";
    }
    md
}
