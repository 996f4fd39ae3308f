//! On-ramps that run alongside another merge's auxiliary lane: along the carriageway, the
//! ramp's edges lie beside an acceleration lane or weaving lane that is not its own (two
//! on-ramps close together; a cloverleaf's outer on-ramp beside its weaving lane). The road
//! frame places a ramp's lane beside the carriageway on frame lane 0, counted back from where
//! it joins, so the stretch of such a ramp beside the other lane would lie on that lane in the
//! frame: the road frame leaves it out (`road_frame.rs`), and the ramp's vehicles are planned
//! from where it no longer runs beside another's lane. Only a ramp whose own acceleration lane
//! begins while another's auxiliary lane still runs beside it is left to SUMO's drivers.

use super::{Layout, OnRamp};
use crate::sumo::network::Net;

/// A ramp `ramp` whose edges lie beside the auxiliary lane of on-ramp `other`.
struct Beside<'l> {
    ramp: &'l OnRamp,
    other: &'l OnRamp,
    /// Where the ramp's edges lie along the carriageway (m).
    span: (f64, f64),
}

impl Beside<'_> {
    /// What it is, in `bkpbs network`'s words.
    fn what(&self) -> String {
        let (r, (a, b)) = (self.other, self.span);
        let lane = if r.weaves_into.is_some() {
            "weaving lane"
        } else {
            "acceleration lane"
        };
        format!(
            "'{}' (s {a:.2} – {b:.2} m) runs alongside the {lane} of on-ramp '{}' on '{}' (s \
             {:.2} – {:.2} m)",
            ramp_name(self.ramp),
            ramp_name(r),
            r.joins,
            r.merge_start,
            r.merge_end
        )
    }
}

/// Every on-ramp of `layout` whose edges run beside another's auxiliary lane: its name and
/// what it runs beside, in words (the first such lane).
pub fn beside(net: &Net, layout: &Layout) -> Vec<(String, String)> {
    (layout.on_ramps.iter())
        .filter_map(|q| first_beside(net, layout, q))
        .map(|b| (ramp_name(b.ramp).to_string(), b.what()))
        .collect()
}

/// Why `layout` cannot be planned: an on-ramp whose acceleration lane begins beside another
/// merge's auxiliary lane (the two would share frame lane 0 there): the first such ramp and
/// what it runs beside; `None` if no ramp does.
pub fn why(net: &Net, layout: &Layout) -> Option<(String, String)> {
    (layout.on_ramps.iter())
        .filter_map(|q| first_beside(net, layout, q))
        .find(|b| b.ramp.merge_start < b.other.merge_end - 1e-6)
        .map(|b| {
            let why = b.what() + ", and its own acceleration lane begins beside it";
            (ramp_name(b.ramp).to_string(), why)
        })
}

/// The first other on-ramp of `layout` beside whose auxiliary lane `q`'s edges lie.
fn first_beside<'l>(net: &Net, layout: &'l Layout, q: &'l OnRamp) -> Option<Beside<'l>> {
    let (a, b) = span(net, q);
    let other = (layout.on_ramps.iter())
        .filter(|r| *r != q)
        .find(|r| a < r.merge_end - 1e-6 && b > r.merge_start + 1e-6)?;
    Some(Beside {
        ramp: q,
        other,
        span: (a, b),
    })
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
