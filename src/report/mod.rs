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

pub mod arms;
pub mod calibration;
pub mod entries;
pub mod episode_plots;
pub mod explain;
pub mod lane_tracks;
pub mod learning_curve;
pub mod paired;
pub mod paired_tables;
pub mod plot;
pub mod raster;
pub mod scenario_common;
pub mod scenario_entries;
pub mod scenario_inserted;
pub mod scenarios;
pub mod signif;
pub mod stats;
pub mod summary;
pub mod tables;
pub mod timespace;
pub mod versions;

use std::path::{Path, PathBuf};

use crate::campaign::grid::file_name_of;
use crate::campaign::results::{Order, Results, ResultsError};
use crate::campaign::{Settings, SETTINGS_FILE};
use crate::episode::output::{self, WriteError};
use crate::report::paired::{Paired, PairedError};
use crate::report::plot::{
    Band, Curve, Dots, HeatPanel, Heatmap, LinePanel, LinePanels, PlotError, Scatter, ScatterSeries,
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
    /// Results of different SUMO versions, without `--allow-mixed`.
    #[error(
        "the results come from different SUMO versions ({versions}): results move between \
         versions, so they are not merged unless --allow-mixed (each row's planner then carries \
         its version, e.g. bk-pbs@{example})"
    )]
    MixedVersions {
        /// The versions found, comma-separated, each with a directory holding it.
        versions: String,
        /// One of them, for the example.
        example: String,
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
    /// The paired comparisons could not be made (an unknown reference, a damaged column).
    #[error(transparent)]
    Paired(#[from] PairedError),
    /// A reference planner of a campaign over scenarios did not run in it.
    #[error(transparent)]
    Reference(#[from] scenarios::UnknownReference),
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

/// Refuses directories whose campaigns ran with different settings (steps, any scenario or
/// model setting; the grid may differ): merged, their episodes would be averaged as one. A
/// directory without `campaign.toml` has nothing to compare.
fn same_settings(dirs: &[PathBuf]) -> Result<(), ReportError> {
    let mut first: Option<(&PathBuf, RunSettings)> = None;
    for dir in dirs {
        let path = dir.join(SETTINGS_FILE);
        if !path.is_file() {
            continue;
        }
        let settings = RunSettings::read(&path)?;
        match &first {
            None => first = Some((dir, settings)),
            Some((first_dir, earlier)) => {
                if let Some(key) = settings.difference(earlier) {
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

/// What a directory's episodes ran with, to compare with another's: on the paper's demand its
/// resolved settings; over scenarios its `campaign.toml` without the grid's axes (resolving it
/// would read the scenarios, which need not be on the machine that reports).
enum RunSettings {
    Demand(Box<Settings>),
    Scenarios(toml::Value),
}

impl RunSettings {
    fn read(path: &Path) -> Result<RunSettings, ReportError> {
        let bad = |message: String| ReportError::Settings {
            path: path.to_path_buf(),
            message,
        };
        let text = crate::io::bounded::read_text(path, crate::io::bounded::FileKind::Config)
            .map_err(|e| bad(e.to_string()))?;
        let mut doc: toml::Table =
            toml::from_str(&text).map_err(|e| bad(e.message().to_string()))?;
        let Some(toml::Value::Table(c)) = doc.get_mut("campaign") else {
            return Settings::from_campaign_file(path)
                .map(|s| RunSettings::Demand(Box::new(s)))
                .map_err(|e| bad(e.to_string()));
        };
        if !c.contains_key("scenarios") {
            return Settings::from_campaign_file(path)
                .map(|s| RunSettings::Demand(Box::new(s)))
                .map_err(|e| bad(e.to_string()));
        }
        for key in ["scenarios", "planners", "alphas", "seeds", "seed_base"] {
            c.remove(key);
        }
        Ok(RunSettings::Scenarios(toml::Value::Table(doc)))
    }

    /// The first setting (dotted key) in which the two differ, if any.
    fn difference(&self, other: &RunSettings) -> Option<String> {
        match (self, other) {
            (RunSettings::Demand(a), RunSettings::Demand(b)) => a.scenario_difference(b),
            (RunSettings::Scenarios(a), RunSettings::Scenarios(b)) => {
                crate::campaign::comparison::first_difference(a, b, "")
            }
            _ => Some("campaign.scenarios".into()),
        }
    }
}

/// The grid order a campaign directory was run with (from its `campaign.toml`), or none.
fn grid_order(dir: &Path) -> Result<Order, ReportError> {
    let path = dir.join(SETTINGS_FILE);
    let Ok(text) = crate::io::bounded::read_text(&path, crate::io::bounded::FileKind::Config)
    else {
        return Ok(Order::default());
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
    let scenarios = names("campaign", "scenarios");
    Ok(Order {
        planners: names("campaign", "planners"),
        profiles,
        scenarios: scenarios
            .iter()
            .map(|s| file_name_of(Path::new(s)))
            .collect(),
    })
}

/// Reads (and merges) the campaign directories, writes tables and figures into
/// `out` (default: the first directory), and returns the Markdown tables.
pub fn run(dirs: &[PathBuf], out: Option<&Path>, allow_mixed: bool) -> Result<Report, ReportError> {
    run_versus(dirs, out, allow_mixed, &[])
}

/// [`run`], and with references in `versus` (`bkpbs report --versus`) the paired comparisons
/// of every planner against each of them ([`paired`]): `paired.csv`, `paired_collisions.csv`
/// and a section of the Markdown.
pub fn run_versus(
    dirs: &[PathBuf],
    out: Option<&Path>,
    allow_mixed: bool,
    versus: &[String],
) -> Result<Report, ReportError> {
    let first = dirs.first().ok_or(ReportError::NoDirs)?;
    if !allow_mixed {
        same_settings(dirs)?;
    }
    let out = out.unwrap_or(first).to_path_buf();
    let (results, mut files) = gather(dirs, &out, allow_mixed)?;
    let results = arms::by_arm(results);
    if results.axes.scenario {
        let mut report = scenarios::report(&results, &out, versus)?;
        files.append(&mut report.files);
        report.files = files;
        return Ok(report);
    }
    let episodes = out.join("episodes.csv");
    let summary = Summary::from_results(&results, &episodes)?;
    let by_entry = entries::rows(&results);
    let mut markdown = tables::markdown(&summary) + &entries::markdown(&by_entry);
    let mut csvs = tables::csv_files(&summary);
    csvs.push(tables::CsvFile {
        name: "delay_by_entry.csv".into(),
        bytes: entries::csv(&by_entry),
    });
    if !versus.is_empty() {
        let p = Paired::of(&results, versus, &episodes)?;
        markdown += &paired_tables::markdown(&p);
        csvs.extend(paired_tables::csv_files(&p));
    }
    let dir = out.join(REPORT_DIR);
    for f in csvs {
        let p = dir.join(&f.name);
        output::write_atomic(&p, &f.bytes)?;
        files.push(p);
    }
    let p = dir.join("tables.md");
    output::write_atomic(&p, markdown.as_bytes())?;
    files.push(p);
    files.extend(write_figures(&summary, &dir)?);
    Ok(Report {
        markdown,
        files,
        out,
    })
}

/// Reads the directories and, when they are several or `out` is another directory, writes the
/// merged (sorted) results there; returns them and the files written.
fn gather(
    dirs: &[PathBuf],
    out: &Path,
    allow_mixed: bool,
) -> Result<(Results, Vec<PathBuf>), ReportError> {
    let mut parts = Vec::new();
    for dir in dirs {
        if !dir.join("episodes.csv").is_file() {
            return Err(ReportError::NotACampaign { dir: dir.clone() });
        }
        parts.push((dir.clone(), Results::read(dir, &grid_order(dir)?)?));
    }
    versions::label_if_mixed(&mut parts, allow_mixed)?;
    let mut files = Vec::new();
    let results = if parts.len() == 1 {
        let (first, mut r) = parts.pop().expect("one part");
        r.sort();
        if !same_dir(out, &first) {
            files.extend(r.write(out)?);
        }
        r
    } else {
        let merged = Results::merge(&parts)?;
        files.extend(merged.write(out)?);
        merged
    };
    Ok((results, files))
}

/// The report's figures, as PNG and SVG in `dir`.
fn write_figures(summary: &Summary, dir: &Path) -> Result<Vec<PathBuf>, ReportError> {
    let mut files = Vec::new();
    for (name, fig) in [
        ("collision_heatmap", heatmap(summary).render()?),
        ("delay_vs_collision", scatter(summary).render()?),
        ("metrics_vs_alpha", metrics_vs_alpha(summary).render()?),
    ] {
        for (ext, bytes) in [("png", fig.png.as_slice()), ("svg", fig.svg.as_bytes())] {
            let p = dir.join(format!("{name}.{ext}"));
            output::write_atomic(&p, bytes)?;
            files.push(p);
        }
    }
    Ok(files)
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

/// A quantity drawn against α.
struct Metric {
    /// Panel title.
    name: &'static str,
    /// y-axis title with the unit.
    unit: &'static str,
    /// The group's estimate.
    estimate: fn(&Group) -> Option<Estimate>,
    /// The group's per-seed values.
    samples: fn(&Group) -> &[f64],
    /// What the quantity can physically be: a band is clipped to it (t(0.975, 1) = 12.7 would
    /// otherwise draw negative speeds).
    bounds: (f64, f64),
}

const METRICS: [Metric; 4] = [
    Metric {
        name: "system delay",
        unit: "delay (s)",
        estimate: |g| g.system_delay,
        samples: |g| &g.samples.system_delay,
        bounds: (0.0, f64::INFINITY),
    },
    Metric {
        name: "arrived-only delay (paper)",
        unit: "delay (s)",
        estimate: |g| g.delay,
        samples: |g| &g.samples.delay,
        bounds: (0.0, f64::INFINITY),
    },
    Metric {
        name: "throughput",
        unit: "throughput (veh/h)",
        estimate: |g| g.throughput,
        samples: |g| &g.samples.throughput,
        bounds: (0.0, f64::INFINITY),
    },
    Metric {
        name: "mean speed",
        unit: "speed (m/s)",
        estimate: |g| g.mean_speed,
        samples: |g| &g.samples.mean_speed,
        bounds: (0.0, f64::INFINITY),
    },
];

/// Below this many seeds a figure draws each seed's value instead of a 95 % band: with t(0.975,
/// n − 1) at 12.7, 4.3, 3.2 for 2, 3, 4 seeds the band says more about n than about the data.
/// The tables' threshold too ([`stats::INTERVAL_MIN_SEEDS`]).
pub const BAND_MIN_SEEDS: usize = stats::INTERVAL_MIN_SEEDS;

/// The paper's tables as a figure: per metric (rows) and λ (columns), each planner's mean over
/// seeds against α, with its 95 % confidence interval as a band (clipped to what the metric can
/// be) from [`BAND_MIN_SEEDS`] seeds on, and each seed's value as a dot below that.
pub fn metrics_vs_alpha(s: &Summary) -> LinePanels {
    let (lo, hi) = (
        s.alphas.first().copied().unwrap_or(0.0),
        s.alphas.last().copied().unwrap_or(1.0),
    );
    let pad = ((hi - lo) * 0.05).max(0.02);
    let alpha_range = lo - pad..hi + pad;
    let mut panels = Vec::new();
    for metric in &METRICS {
        for &lambda in &s.lambdas {
            let mut panel = LinePanel {
                title: format!(
                    "{}, λ = {} veh/h",
                    metric.name,
                    tables::lambda_label(lambda)
                ),
                x_label: "CAV penetration α".into(),
                y_label: metric.unit.into(),
                curves: Vec::new(),
                bands: Vec::new(),
                dots: Vec::new(),
                marks: Vec::new(),
                x_range: Some(alpha_range.clone()),
            };
            for colour in 0..s.planners.len() {
                add_planner(&mut panel, s, metric, lambda, colour);
            }
            panels.push(panel);
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

/// One planner's (the `colour`-th) mean curve in a panel of [`metrics_vs_alpha`], with its band
/// when every α has [`BAND_MIN_SEEDS`] seeds, else its seeds as dots (shifted a little per
/// planner so that planners' equal values stay apart).
fn add_planner(panel: &mut LinePanel, s: &Summary, metric: &Metric, lambda: f64, colour: usize) {
    let groups: Vec<(f64, &Group, Estimate)> = s
        .alphas
        .iter()
        .filter_map(|&a| {
            let g = s.get(&s.planners[colour], a, lambda)?;
            Some((a, g, (metric.estimate)(g)?))
        })
        .collect();
    panel.curves.push(Curve {
        points: groups.iter().map(|(a, _, e)| (*a, e.mean)).collect(),
        colour,
        thick: true,
    });
    let (floor, ceiling) = metric.bounds;
    if groups.iter().all(|(_, _, e)| e.n >= BAND_MIN_SEEDS) {
        let points = groups.iter().map(|(a, _, e)| {
            let half = e.ci95.unwrap_or(0.0);
            let (low, high) = (e.mean - half, e.mean + half);
            (*a, low.clamp(floor, ceiling), high.clamp(floor, ceiling))
        });
        panel.bands.push(Band {
            points: points.collect(),
            colour,
        });
        return;
    }
    let width = panel.x_range.as_ref().map_or(1.0, |r| r.end - r.start);
    let shift = (colour as f64 - (s.planners.len() as f64 - 1.0) / 2.0) * 0.008 * width;
    panel.dots.push(Dots {
        points: groups
            .iter()
            .flat_map(|(a, g, _)| (metric.samples)(g).iter().map(move |v| (a + shift, *v)))
            .collect(),
        colour,
    });
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

#[cfg(test)]
mod tests {
    use super::summary::Samples;
    use super::*;

    /// A summary of one planner at α 0.4 and 0.8 whose speeds per seed are `speeds`.
    fn summary(speeds: &[f64]) -> Summary {
        let group = |alpha| Group {
            planner: "p".into(),
            alpha,
            lambda: 3000.0,
            episodes: speeds.len(),
            system_delay: None,
            own_speed_delay: None,
            stranded: None,
            never_inserted: None,
            delay: None,
            collision_rate: None,
            throughput: None,
            mean_speed: Estimate::of(speeds),
            samples: Samples {
                mean_speed: speeds.to_vec(),
                ..Samples::default()
            },
        };
        Summary {
            planners: vec!["p".into()],
            alphas: vec![0.4, 0.8],
            lambdas: vec![3000.0],
            groups: vec![group(0.4), group(0.8)],
            seeds: speeds.len(),
        }
    }

    fn speed_panel(f: &LinePanels) -> &LinePanel {
        f.panels
            .iter()
            .find(|p| p.title.starts_with("mean speed"))
            .unwrap()
    }

    #[test]
    fn few_seeds_are_drawn_as_dots_and_many_as_a_band_within_bounds() {
        // Two seeds: t(0.975, 1) = 12.7 would span ±184 m/s; each seed is drawn instead.
        let f = metrics_vs_alpha(&summary(&[1.0, 30.0]));
        let p = speed_panel(&f);
        assert!(p.bands.is_empty());
        assert_eq!(p.dots.len(), 1);
        let ys: Vec<f64> = p.dots[0].points.iter().map(|d| d.1).collect();
        assert_eq!(ys, [1.0, 30.0, 1.0, 30.0]);
        assert_eq!(p.curves[0].points, [(0.4, 15.5), (0.8, 15.5)]);
        // Five seeds: a band, clipped at zero speed (mean 2, half-width 2.776·√20/√5 = 5.55).
        let f = metrics_vs_alpha(&summary(&[0.0, 0.0, 0.0, 0.0, 10.0]));
        let p = speed_panel(&f);
        assert!(p.dots.is_empty());
        let (_, low, high) = p.bands[0].points[0];
        assert_eq!(low, 0.0);
        assert!((high - (2.0 + 2.776_445 * 2.0)).abs() < 1e-5, "{high}");
    }
}
