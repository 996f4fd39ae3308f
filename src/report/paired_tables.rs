//! The paired comparisons ([`super::paired`]) as tables: `paired.csv` (one row per planner,
//! reference, cell and metric), `paired_collisions.csv` (one row per planner, reference and
//! cell) at full precision, and a Markdown section for reading.

use super::paired::{Block, MetricDiff, Paired};
use super::tables::{csv_bytes, lambda_label, CsvFile};

/// What the pooled rows put in the cell columns.
const ALL: &str = "all";

/// A CSV file of `header` and `rows`.
fn csv_file(name: &str, header: &[&str], rows: &[Vec<String>]) -> CsvFile {
    let header: Vec<String> = header.iter().map(|h| h.to_string()).collect();
    CsvFile {
        name: name.into(),
        bytes: csv_bytes(&header, rows),
    }
}

/// planner, reference, α, λ, HDV profile of a block (`all` when pooled).
fn lead(b: &Block) -> Vec<String> {
    let cell = match &b.cell {
        Some(c) => [
            c.alpha.to_string(),
            c.lambda.to_string(),
            c.hdv_profile.clone(),
        ],
        None => [ALL.into(), ALL.into(), ALL.into()],
    };
    [b.planner.clone(), b.reference.clone()]
        .into_iter()
        .chain(cell)
        .collect()
}

const PAIRED_HEADER: [&str; 17] = [
    "planner",
    "reference",
    "alpha",
    "lambda",
    "hdv_profile",
    "metric",
    "pairs",
    "mean_planner",
    "mean_reference",
    "mean_diff",
    "ci95_low",
    "ci95_high",
    "zeros",
    "wilcoxon_v",
    "wilcoxon_p",
    "test",
    "unmatched",
];

/// The cells of one metric's difference after `metric` (empty where undefined).
fn diff_cells(d: Option<&MetricDiff>) -> Vec<String> {
    let Some(d) = d else {
        let mut cells = vec![String::new(); 10];
        cells[0] = "0".into();
        cells[9] = "none".into();
        return cells;
    };
    let e = d.diff;
    let (low, high) = match e.ci95 {
        Some(h) => ((e.mean - h).to_string(), (e.mean + h).to_string()),
        None => Default::default(),
    };
    let t = d.test;
    vec![
        d.pairs.to_string(),
        d.mean_planner.to_string(),
        d.mean_reference.to_string(),
        e.mean.to_string(),
        low,
        high,
        t.map_or(d.pairs, |t| t.zeros).to_string(),
        t.map(|t| t.v.to_string()).unwrap_or_default(),
        t.map(|t| t.p.to_string()).unwrap_or_default(),
        t.map_or("none", |t| t.method.name()).to_string(),
    ]
}

/// `paired.csv`: per block and metric, the difference and its test.
fn paired_csv(p: &Paired) -> CsvFile {
    let mut rows = Vec::new();
    for b in &p.blocks {
        for (name, d) in p.metrics.iter().zip(&b.metrics) {
            let mut row = lead(b);
            row.push(name.to_string());
            row.extend(diff_cells(d.as_ref()));
            row.push(b.unmatched.to_string());
            rows.push(row);
        }
    }
    csv_file("paired.csv", &PAIRED_HEADER, &rows)
}

/// `paired_collisions.csv`: per block, the collision episodes of each side and Fisher's p.
fn collisions_csv(p: &Paired) -> CsvFile {
    let header = [
        "planner",
        "reference",
        "alpha",
        "lambda",
        "hdv_profile",
        "pairs",
        "planner_collision_episodes",
        "reference_collision_episodes",
        "fisher_p",
        "unmatched",
    ];
    let rows: Vec<Vec<String>> = p
        .blocks
        .iter()
        .map(|b| {
            let c = &b.collisions;
            let mut row = lead(b);
            row.extend([b.pairs, c.planner, c.reference].map(|n| n.to_string()));
            row.extend([c.p.to_string(), b.unmatched.to_string()]);
            row
        })
        .collect();
    csv_file("paired_collisions.csv", &header, &rows)
}

/// Both CSV files of the paired comparisons.
pub fn csv_files(p: &Paired) -> Vec<CsvFile> {
    vec![paired_csv(p), collisions_csv(p)]
}

/// A p-value for reading: three decimals, `<0.001` below.
fn p_text(p: f64) -> String {
    if p < 0.001 {
        "<0.001".into()
    } else {
        format!("{p:.3}")
    }
}

/// One metric's difference for reading: `Δ [low, high]`, its p, and `(n k)` when fewer pairs
/// than the block's had values.
fn diff_text(d: Option<&MetricDiff>, pairs: usize) -> [String; 2] {
    let Some(d) = d else {
        return ["—".into(), "none".into()];
    };
    let e = d.diff;
    let mut text = match e.ci95 {
        Some(h) => format!("{:+.2} [{:+.2}, {:+.2}]", e.mean, e.mean - h, e.mean + h),
        None => format!("{:+.2}", e.mean),
    };
    if d.pairs < pairs {
        text += &format!(" (n {})", d.pairs);
    }
    [text, d.test.map_or("none".into(), |t| p_text(t.p))]
}

/// The Markdown row of a block.
fn markdown_row(b: &Block) -> String {
    let cell = match &b.cell {
        Some(c) => [
            format!("{}", c.alpha),
            lambda_label(c.lambda),
            c.hdv_profile.clone(),
        ],
        None => [ALL; 3].map(|s| format!("**{s}**")),
    };
    let mut cols: Vec<String> = cell.into_iter().collect();
    cols.push(b.pairs.to_string());
    for d in &b.metrics {
        cols.extend(diff_text(d.as_ref(), b.pairs));
    }
    let c = &b.collisions;
    cols.push(format!("{} vs {}", c.planner, c.reference));
    cols.push(p_text(c.p));
    format!("| {} |\n", cols.join(" | "))
}

/// The Markdown section: one table per planner and reference, rows cells then pooled.
pub fn markdown(p: &Paired) -> String {
    let mut out = String::from(
        "\n## Paired comparisons (planner − reference, same cell and seed)\n\n\
         Δ: mean per-seed difference with Student's 95 % interval; p: Wilcoxon signed-rank, \
         two-sided (zero differences dropped; exact below 50 pairs without ties, else normal \
         with tie and continuity correction; `none`: every difference zero); collision \
         episodes (controllable_crashed > 0) planner vs reference with Fisher's exact p.\n",
    );
    let mut header = ["α", "λ", "HDV", "pairs"].join(" | ");
    for m in &p.metrics {
        header += &format!(" | Δ {m} | p");
    }
    header += " | collision episodes | p";
    let columns = header.matches(" | ").count() + 1;
    let rule = format!("|{}\n", "---|".repeat(columns));
    let mut last: Option<(&str, &str)> = None;
    for b in &p.blocks {
        if last != Some((&b.planner, &b.reference)) {
            out += &format!(
                "\n### {} − {}\n\n| {header} |\n{rule}",
                b.planner, b.reference
            );
            last = Some((&b.planner, &b.reference));
        }
        out += &markdown_row(b);
        if b.cell.is_none() && b.unmatched > 0 {
            out += &format!(
                "\n{} episode(s) without a partner of the same cell and seed dropped.\n",
                b.unmatched
            );
        }
    }
    out
}
