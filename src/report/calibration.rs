//! The generalisation matrix of the longitudinal calibration as files: a CSV and a Markdown
//! table per error, and a heat map (rows: the profile the IDM was fitted on, and constant
//! speed; columns: the profile it is evaluated on).

use super::plot::{Figure, HeatPanel, Heatmap, PlotError};
use crate::train::longitudinal::{Errors, Matrix};

/// An error shown: its name, unit, and how to read it.
type Shown = (&'static str, &'static str, fn(&Errors) -> f64);

/// The two errors shown.
const SHOWN: [Shown; 2] = [
    ("rmse_speed_3s", "m/s", |e| e.rmse_speed_3s),
    ("rmse_gap_3s", "m", |e| e.rmse_gap_3s),
];

/// Row labels: each fitted-on profile, then constant speed.
fn row_labels(m: &Matrix) -> Vec<String> {
    let mut rows: Vec<String> = m
        .profiles
        .iter()
        .map(|p| format!("IDM fitted on {p}"))
        .collect();
    rows.push("constant speed".into());
    rows
}

/// The values of one error: a row per fitted-on profile, then constant speed.
fn values(m: &Matrix, read: fn(&Errors) -> f64) -> Vec<Vec<f64>> {
    let mut rows: Vec<Vec<f64>> = m
        .fitted
        .iter()
        .map(|r| r.iter().map(read).collect())
        .collect();
    rows.push(m.constant.iter().map(read).collect());
    rows
}

/// `longitudinal_matrix.csv`: one row per (model, evaluated-on profile) with both errors.
pub fn csv(m: &Matrix) -> String {
    let mut out = String::from("model,evaluated_on,rmse_speed_1s,rmse_speed_3s,rmse_gap_3s\n");
    let models = m.fitted.iter().chain(std::iter::once(&m.constant));
    for (label, row) in row_labels(m).iter().zip(models) {
        for (profile, e) in m.profiles.iter().zip(row) {
            out += &format!(
                "{label},{profile},{:.4},{:.4},{:.4}\n",
                e.rmse_speed_1s, e.rmse_speed_3s, e.rmse_gap_3s
            );
        }
    }
    out
}

/// The Markdown tables, one per shown error.
pub fn markdown(m: &Matrix) -> String {
    let mut out = String::from("# Longitudinal generalisation matrix\n\nRows: the model (an IDM fitted on a profile, or constant speed); columns: the profile whose held-out episodes it predicts. Open-loop errors over 3 s; lower is better, bold: the lowest of a column.\n");
    for (name, unit, read) in SHOWN {
        out += &format!(
            "\n## {name} ({unit})\n\n| model | {} |\n",
            m.profiles.join(" | ")
        );
        out += &format!("| --- |{}\n", " ---: |".repeat(m.profiles.len()));
        let v = values(m, read);
        let best: Vec<f64> = (0..m.profiles.len())
            .map(|c| v.iter().map(|r| r[c]).fold(f64::INFINITY, f64::min))
            .collect();
        for (label, row) in row_labels(m).iter().zip(&v) {
            let cells: Vec<String> = row
                .iter()
                .zip(&best)
                .map(|(x, b)| match x == b {
                    true => format!("**{x:.3}**"),
                    false => format!("{x:.3}"),
                })
                .collect();
            out += &format!("| {label} | {} |\n", cells.join(" | "));
        }
    }
    out
}

/// A profile's name short enough for the heat map's axes.
fn short(profile: &str) -> String {
    match profile {
        "sumo-safe" => "safe".into(),
        "heterogeneous" => "hetero".into(),
        p => p.chars().take(7).collect(),
    }
}

/// The heat map: a panel per shown error.
pub fn figure(m: &Matrix) -> Result<Figure, PlotError> {
    Heatmap {
        panels: SHOWN
            .iter()
            .map(|(name, unit, read)| HeatPanel {
                title: format!("{name} ({unit})"),
                values: values(m, *read)
                    .into_iter()
                    .map(|r| r.into_iter().map(Some).collect())
                    .collect(),
            })
            .collect(),
        row_labels: m
            .profiles
            .iter()
            .map(|p| short(p))
            .chain(std::iter::once("const.".to_string()))
            .collect(),
        col_labels: m.profiles.iter().map(|p| short(p)).collect(),
        row_axis: "IDM fitted on (const.: constant speed)".into(),
        col_axis: "evaluated on".into(),
        scale_label: "open-loop error at 3 s".into(),
        decimals: 2,
        min_scale_max: 1.0,
    }
    .render()
}
