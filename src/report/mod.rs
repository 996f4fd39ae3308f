//! Reports of campaigns: tables (CSV and Markdown) and figures from the collected results of one
//! or more campaign directories.
//!
//! Several directories are shards of one campaign (or campaigns to compare): their results are
//! merged first (see [`Results::merge`]) and the merged `episodes.csv`, `vehicles.csv`,
//! `timings.csv` and `failures.csv` are written to the output directory. Tables and figures go
//! to `<out>/report/`.
//!
//! Figures of one episode: [`episode_plots`] (`bkpbs plot`), from its trajectories
//! ([`lane_tracks`]) drawn by [`timespace`], and the collision close-ups of [`explain`].

pub mod calibration;
pub mod entries;
pub mod episode_plots;
pub mod explain;
pub mod lane_tracks;
pub mod learning_curve;
pub mod plot;
pub mod raster;
pub mod stats;
pub mod summary;
pub mod tables;
pub mod timespace;

use std::path::{Path, PathBuf};

use crate::campaign::results::{Results, ResultsError};
use crate::campaign::{Settings, SETTINGS_FILE};
use crate::episode::output::{self, WriteError};
use crate::report::plot::{
    Band, Curve, HeatPanel, Heatmap, LinePanel, LinePanels, PlotError, Scatter, ScatterSeries,
};
use crate::report::stats::Estimate;
use crate::report::summary::Group;
pub use summary::{Summary, SummaryError};

/// Directory of the tables and figures inside the output directory.
pub const REPORT_DIR: &str = "report";

/// Why a report could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The list of campaign directories was empty.
    #[error("report: no campaign directory given")]
    NoDirs,
    /// A directory has no `episodes.csv`.
    #[error("{dir} is not a campaign directory (no episodes.csv; run `bkpbs campaign --out {dir}` first)")]
    NotACampaign {
        /// The directory given.
        dir: PathBuf,
    },
    /// A directory's `campaign.toml` could not be read as campaign settings.
    #[error("malformed {path}: {message}")]
    Settings {
        /// The settings file.
        path: PathBuf,
        /// What the parser reported.
        message: String,
    },
    /// Two directories were run with different settings, so their episodes are not samples of
    /// the same experiment (`--allow-mixed` merges them anyway).
    #[error(
        "{other} was run with other settings than {first} ({key} differs): its episodes would \
         mix into the same tables; pass --allow-mixed to merge them anyway"
    )]
    MixedSettings {
        /// The first directory with a `campaign.toml`, the one the others are compared with.
        first: PathBuf,
        /// The directory whose settings differ from it.
        other: PathBuf,
        /// The first scenario setting (dotted key) found to differ.
        key: String,
    },
    /// The results (CSV files) could not be read or merged.
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// `episodes.csv` lacks a column the tables need, or holds a non-number.
    #[error(transparent)]
    Summary(#[from] SummaryError),
    /// A table, figure or merged result file could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// What a report produced.
pub struct Report {
    /// The Markdown tables (also in `report/tables.md`).
    pub markdown: String,
    /// Every file written, in order.
    pub files: Vec<PathBuf>,
    /// The directory the report went into.
    pub out: PathBuf,
}

/// The planner order a campaign directory was run with (from its `campaign.toml`), or none.
/// Refuses directories whose campaigns ran with different settings (steps, any scenario or
/// model setting; the grid may differ): merged, their episodes would be averaged as one. A
/// directory without `campaign.toml` has nothing to compare.
fn same_settings(dirs: &[PathBuf]) -> Result<(), ReportError> {
    let mut first: Option<(&PathBuf, Settings)> = None;
    for dir in dirs {
        let path = dir.join(SETTINGS_FILE);
        if !path.is_file() {
            continue;
        }
        let settings = Settings::from_campaign_file(&path).map_err(|e| ReportError::Settings {
            path: path.clone(),
            message: e.to_string(),
        })?;
        match &first {
            None => first = Some((dir, settings)),
            Some((first_dir, earlier)) => {
                if let Some(key) = settings.scenario_difference(earlier) {
                    return Err(ReportError::MixedSettings {
                        first: (*first_dir).clone(),
                        other: dir.clone(),
                        key,
                    });
                }
            }
        }
    }
    Ok(())
}

/// The planner and HDV-profile order a campaign directory was run with (from its
/// `campaign.toml`), or none.
fn grid_order(dir: &Path) -> Result<(Vec<String>, Vec<String>), ReportError> {
    let path = dir.join(SETTINGS_FILE);
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(Default::default());
    };
    let bad = |message: String| ReportError::Settings {
        path: path.clone(),
        message,
    };
    let doc: toml::Table = toml::from_str(&text).map_err(|e| bad(e.message().to_string()))?;
    let names = |table: &str, key: &str| -> Vec<String> {
        match doc.get(table).and_then(|c| c.get(key)) {
            Some(toml::Value::Array(a)) => a
                .iter()
                .filter_map(|v| v.as_str().map(String::from))
                .collect(),
            Some(toml::Value::String(s)) => vec![s.clone()],
            _ => Vec::new(),
        }
    };
    let mut profiles = names("campaign", "hdv_profiles");
    if profiles.is_empty() {
        profiles = names("hdv", "profile");
    }
    Ok((names("campaign", "planners"), profiles))
}

/// Reads (and merges) the campaign directories, writes tables and figures into
/// `out` (default: the first directory), and returns the Markdown tables.
pub fn run(dirs: &[PathBuf], out: Option<&Path>, allow_mixed: bool) -> Result<Report, ReportError> {
    let first = dirs.first().ok_or(ReportError::NoDirs)?;
    if !allow_mixed {
        same_settings(dirs)?;
    }
    let out = out.unwrap_or(first).to_path_buf();
    let mut parts = Vec::new();
    for dir in dirs {
        if !dir.join("episodes.csv").is_file() {
            return Err(ReportError::NotACampaign { dir: dir.clone() });
        }
        let (planners, profiles) = grid_order(dir)?;
        parts.push((dir.clone(), Results::read(dir, &planners, &profiles)?));
    }
    let mut files = Vec::new();
    let results = if parts.len() == 1 {
        let (_, mut r) = parts.pop().expect("one part");
        r.sort();
        if !same_dir(&out, first) {
            files.extend(r.write(&out)?);
        }
        r
    } else {
        let merged = Results::merge(&parts)?;
        files.extend(merged.write(&out)?);
        merged
    };
    let summary = Summary::from_results(&results, &out.join("episodes.csv"))?;
    let dir = out.join(REPORT_DIR);
    let by_entry = entries::rows(&results);
    let markdown = tables::markdown(&summary) + &entries::markdown(&by_entry);
    for f in tables::csv_files(&summary) {
        let p = dir.join(&f.name);
        output::write_atomic(&p, &f.bytes)?;
        files.push(p);
    }
    let p = dir.join("delay_by_entry.csv");
    output::write_atomic(&p, &entries::csv(&by_entry))?;
    files.push(p);
    let p = dir.join("tables.md");
    output::write_atomic(&p, markdown.as_bytes())?;
    files.push(p);
    for (name, fig) in [
        ("collision_heatmap", heatmap(&summary).render()?),
        ("delay_vs_collision", scatter(&summary).render()?),
        ("metrics_vs_alpha", metrics_vs_alpha(&summary).render()?),
    ] {
        for (ext, bytes) in [("png", fig.png.as_slice()), ("svg", fig.svg.as_bytes())] {
            let p = dir.join(format!("{name}.{ext}"));
            output::write_atomic(&p, bytes)?;
            files.push(p);
        }
    }
    Ok(Report {
        markdown,
        files,
        out,
    })
}

fn same_dir(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// The paper's fig. 3: per planner, mean controllable collision rate (%) over λ × α.
pub fn heatmap(s: &Summary) -> Heatmap {
    Heatmap {
        panels: s
            .planners
            .iter()
            .map(|p| HeatPanel {
                title: p.clone(),
                values: s
                    .lambdas
                    .iter()
                    .map(|&l| {
                        s.alphas
                            .iter()
                            .map(|&a| {
                                s.get(p, a, l)
                                    .and_then(|g| g.collision_rate)
                                    .map(|e| e.mean * 100.0)
                            })
                            .collect()
                    })
                    .collect(),
            })
            .collect(),
        row_labels: s.lambdas.iter().map(|&l| tables::lambda_label(l)).collect(),
        col_labels: s.alphas.iter().map(|a| format!("{a}")).collect(),
        row_axis: "λ (veh/h)".into(),
        col_axis: "CAV penetration α".into(),
        scale_label: "controllable collision rate (%)".into(),
        decimals: 2,
        min_scale_max: 1.0,
    }
}

/// System delay against mean controllable collision rate, one point per (planner, α, λ),
/// coloured by planner, shaped by λ.
pub fn scatter(s: &Summary) -> Scatter {
    Scatter {
        title: "System delay vs. controllable collision rate (mean over seeds)".into(),
        x_label: "controllable collision rate (%)".into(),
        y_label: "system delay (s)".into(),
        series: s
            .planners
            .iter()
            .map(|p| ScatterSeries {
                name: p.clone(),
                points: s
                    .groups
                    .iter()
                    .filter(|g| &g.planner == p)
                    .filter_map(|g| {
                        let d = g.system_delay?;
                        let r = g.collision_rate?;
                        let m = s.lambdas.iter().position(|&l| l == g.lambda)?;
                        Some((r.mean * 100.0, d.mean, m))
                    })
                    .collect(),
            })
            .collect(),
        markers: s
            .lambdas
            .iter()
            .map(|&l| format!("λ = {}", tables::lambda_label(l)))
            .collect(),
        min_x_max: 1.0,
    }
}

/// The quantities drawn against α: name, unit, and how to read one from a group.
type Metric = (&'static str, &'static str, fn(&Group) -> Option<Estimate>);

const METRICS: [Metric; 4] = [
    ("system delay", "delay (s)", |g| g.system_delay),
    ("arrived-only delay (paper)", "delay (s)", |g| g.delay),
    ("throughput", "throughput (veh/h)", |g| g.throughput),
    ("mean speed", "speed (m/s)", |g| g.mean_speed),
];

/// The paper's tables as a figure: per metric (rows) and λ (columns), each planner's mean over
/// seeds against α, with its 95 % confidence interval as a band (none for a single seed).
pub fn metrics_vs_alpha(s: &Summary) -> LinePanels {
    let (lo, hi) = (
        s.alphas.first().copied().unwrap_or(0.0),
        s.alphas.last().copied().unwrap_or(1.0),
    );
    let pad = ((hi - lo) * 0.05).max(0.02);
    let alpha_range = lo - pad..hi + pad;
    let mut panels = Vec::new();
    for (name, unit, read) in METRICS {
        for &lambda in &s.lambdas {
            let mut curves = Vec::new();
            let mut bands = Vec::new();
            for (colour, planner) in s.planners.iter().enumerate() {
                let estimates: Vec<(f64, Estimate)> = s
                    .alphas
                    .iter()
                    .filter_map(|&a| Some((a, read(s.get(planner, a, lambda)?)?)))
                    .collect();
                curves.push(Curve {
                    points: estimates.iter().map(|(a, e)| (*a, e.mean)).collect(),
                    colour,
                    thick: true,
                });
                bands.push(Band {
                    points: estimates
                        .iter()
                        .map(|(a, e)| {
                            let half = e.ci95.unwrap_or(0.0);
                            (*a, e.mean - half, e.mean + half)
                        })
                        .collect(),
                    colour,
                });
            }
            panels.push(LinePanel {
                title: format!("{name}, λ = {} veh/h", tables::lambda_label(lambda)),
                x_label: "CAV penetration α".into(),
                y_label: unit.into(),
                curves,
                bands,
                marks: Vec::new(),
                x_range: Some(alpha_range.clone()),
            });
        }
    }
    LinePanels {
        panels,
        legend: s
            .planners
            .iter()
            .enumerate()
            .map(|(i, p)| (i, p.clone(), true))
            .collect(),
    }
}

/// The files of a report worth pointing a reader to (tables and figures).
pub fn highlights(r: &Report) -> Vec<&Path> {
    r.files
        .iter()
        .filter(|p| {
            p.extension()
                .is_some_and(|e| e == "md" || e == "png" || e == "svg")
        })
        .map(|p| p.as_path())
        .collect()
}
