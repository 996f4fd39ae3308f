//! On-ramps that run alongside another merge's auxiliary lane: along the carriageway, the
//! ramp's edges lie beside an acceleration lane or weaving lane that is not its own (two
//! on-ramps close together; a cloverleaf's outer on-ramp beside its weaving lane). The road
//! frame gives each on-ramp's lane beside the carriageway frame lane 0, so a vehicle on such a
//! ramp would
//! be planned against the other merge's zone, and stopped where that lane ends: such a region
//! is left to SUMO's drivers until the frame knows one auxiliary lane from another.

use super::{Layout, OnRamp};
use crate::sumo::network::Net;

/// Why `layout` cannot be planned for an on-ramp alongside another merge's auxiliary lane:
/// the first such ramp, its span and the lane it runs beside; `None` if no ramp does.
pub fn why(net: &Net, layout: &Layout) -> Option<(String, String)> {
    for q in &layout.on_ramps {
        let (a, b) = span(net, q);
        for r in layout.on_ramps.iter().filter(|r| *r != q) {
            if a < r.merge_end - 1e-6 && b > r.merge_start + 1e-6 {
                let lane = if r.weaves_into.is_some() {
                    "weaving lane"
                } else {
                    "acceleration lane"
                };
                let why = format!(
                    "'{}' (s {a:.2} – {b:.2} m) runs alongside the {lane} of on-ramp '{}' on \
                     '{}' (s {:.2} – {:.2} m)",
                    ramp_name(q),
                    ramp_name(r),
                    r.joins,
                    r.merge_start,
                    r.merge_end
                );
                return Some((ramp_name(q).to_string(), why));
            }
        }
    }
    None
}

/// The ramp's name: its last edge, the one that joins the carriageway.
pub fn ramp_name(r: &OnRamp) -> &str {
    r.edges.last().expect("a ramp has an edge")
}

/// Where the ramp's edges lie along the carriageway: counted back from where its lane joins,
/// as the road frame places them.
fn span(net: &Net, r: &OnRamp) -> (f64, f64) {
    let length: f64 = r.edges.iter().map(|e| net.edge(e).lanes[0].length).sum();
    (r.merge_start - length, r.merge_start)
}
