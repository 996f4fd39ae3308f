//! Smoke tests of every figure of this module (the lane figures' are in
//! [`crate::report::timespace`], with the same check): each renders from small hand-built data into a valid PNG and
//! SVG, and rendering twice gives the same bytes (figures are compared byte for byte across
//! runs, so nothing may depend on time, addresses or hash order).

use super::*;

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

/// Renders twice with `render`, checks both files are well formed, and the second run
/// repeats the first byte for byte.
pub(in crate::report) fn assert_valid_and_deterministic(
    render: impl Fn() -> Result<Figure, PlotError>,
) {
    let first = render().expect("renders");
    assert!(first.png.len() > PNG_SIGNATURE.len());
    assert_eq!(first.png[..8], PNG_SIGNATURE, "PNG signature");
    assert!(
        first.svg.starts_with("<svg") || first.svg.starts_with("<?xml"),
        "SVG begins with {:?}",
        &first.svg[..first.svg.len().min(20)]
    );
    assert!(first.svg.trim_end().ends_with("</svg>"));
    let second = render().expect("renders again");
    assert!(
        first.png == second.png,
        "PNG differs between two renderings"
    );
    assert_eq!(first.svg, second.svg, "SVG differs between two renderings");
}

fn heatmap() -> Heatmap {
    Heatmap {
        panels: ["bk-pbs", "idm"]
            .iter()
            .map(|p| HeatPanel {
                title: p.to_string(),
                values: vec![vec![Some(0.0), Some(1.5)], vec![None, Some(3.25)]],
            })
            .collect(),
        row_labels: vec!["3000".into(), "2000".into()],
        col_labels: vec!["0.5".into(), "1".into()],
        row_axis: "λ (veh/h)".into(),
        col_axis: "α".into(),
        scale_label: "rate (%)".into(),
        decimals: 2,
        min_scale_max: 1.0,
    }
}

#[test]
fn heatmap_renders_valid_and_deterministic() {
    let h = heatmap();
    assert_valid_and_deterministic(|| h.render());
}

#[test]
fn heatmap_of_zeros_and_gaps_renders() {
    let mut h = heatmap();
    for p in &mut h.panels {
        p.values = vec![vec![Some(0.0), None], vec![None, Some(0.0)]];
    }
    assert_valid_and_deterministic(|| h.render());
}

#[test]
fn scatter_renders_valid_and_deterministic() {
    let s = Scatter {
        title: "delay vs. rate".into(),
        x_label: "rate (%)".into(),
        y_label: "delay (s)".into(),
        series: vec![
            ScatterSeries {
                name: "bk-pbs".into(),
                points: vec![(0.0, 10.0, 0), (0.5, 12.0, 1), (1.0, 15.0, 2)],
            },
            ScatterSeries {
                name: "idm".into(),
                points: vec![(2.0, 8.0, 3), (0.0, 9.0, 4)],
            },
        ],
        markers: ["λ = 1", "λ = 2", "λ = 3", "λ = 4"]
            .map(String::from)
            .to_vec(),
        min_x_max: 1.0,
    };
    assert_valid_and_deterministic(|| s.render());
}

#[test]
fn line_panels_render_valid_and_deterministic() {
    let panel = |marks: Vec<f64>, x_range| LinePanel {
        title: "delay".into(),
        x_label: "α".into(),
        y_label: "s".into(),
        curves: vec![
            Curve {
                points: vec![(0.0, 1.0), (0.5, 2.0), (1.0, 1.5)],
                colour: 0,
                thick: true,
            },
            Curve {
                points: vec![(0.0, 0.5), (1.0, 0.7)],
                colour: 1,
                thick: false,
            },
        ],
        bands: vec![Band {
            points: vec![(0.0, 0.5, 1.5), (0.5, 1.5, 2.5), (1.0, 1.0, 2.0)],
            colour: 0,
        }],
        dots: vec![Dots {
            points: vec![(0.0, 0.4), (1.0, 2.6)],
            colour: 1,
        }],
        marks,
        x_range,
    };
    let l = LinePanels {
        panels: vec![panel(Vec::new(), Some(-0.1..1.1)), panel(vec![0.25], None)],
        legend: vec![(0, "thick".into(), true), (1, "thin".into(), false)],
    };
    assert_valid_and_deterministic(|| l.render());
}

#[test]
fn viridis_ends_and_clamps() {
    assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
    assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
    assert_eq!(viridis(2.0), viridis(1.0));
    assert_eq!(viridis(f64::NAN), viridis(0.0));
}
