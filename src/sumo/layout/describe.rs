//! What `bkpbs network` prints: each region found, one line per element, then the regions
//! left to SUMO's drivers, every forced lane change by kind with where it is planned or why
//! not, every junction that is no merge and every edge left out, grouped by why.

use std::collections::BTreeMap;

use super::{Discovery, Layout, OnRamp, Status};

impl Layout {
    /// The region, one line per element.
    pub fn describe(&self) -> String {
        let mut out = format!("main carriageway: {:.2} m\n", self.length());
        for m in &self.main {
            out += &format!(
                "  {:<16} s {:>8.2} – {:>8.2} m  {} lanes\n",
                m.id,
                m.s_start,
                m.s_start + m.length,
                m.lanes
            );
        }
        for (k, r) in self.on_ramps.iter().enumerate() {
            out += &on_ramp_line(k, r);
        }
        for d in &self.lane_drops {
            out += &format!(
                "lane drop: lane {} of {} ends at s {:.2} m\n",
                d.lane, d.ends_on, d.merge_end
            );
        }
        for (k, r) in self.off_ramps.iter().enumerate() {
            out += &format!(
                "off-ramp {}: {} → {}\n",
                k + 1,
                r.leaves,
                r.edges.join(" → ")
            );
        }
        out
    }
}

/// The line of on-ramp `k` (from 0) of a region.
fn on_ramp_line(k: usize, r: &OnRamp) -> String {
    let route = r.edges.join(" → ");
    if r.nose {
        return format!(
            "on-ramp {}: {route} → {} lane {}: joins at the nose, s {:.2} m\n",
            k + 1,
            r.joins,
            r.lane,
            r.merge_start
        );
    }
    let mut on = if r.ends_on == r.joins {
        String::new()
    } else {
        format!(" on '{}'", r.ends_on)
    };
    if let Some(exit) = &r.weaves_into {
        on += &format!("; weaving: its lane runs on into off-ramp '{exit}'");
    }
    for o in &r.outer {
        on += &format!(
            "; outer lane {}: ends at s {:.2} m on '{}'",
            o.lane, o.merge_end, o.ends_on
        );
    }
    format!(
        "on-ramp {}: {route} → {} lane {}: from s {:.2} m, ends at s {:.2} m{on}\n",
        k + 1,
        r.joins,
        r.lane,
        r.merge_start,
        r.merge_end
    )
}

impl Discovery {
    /// The regions left to SUMO's drivers, forced lane changes, junctions that are no merge
    /// and edges left out, grouped by why (the regions planned are described with their road
    /// frames, by the caller; `unplannable`: the regions, by index, whose road frame cannot be
    /// built: an episode refuses them).
    pub fn describe_left_out(&self, unplannable: &[usize]) -> String {
        let mut out = String::new();
        for l in &self.left_to_sumo {
            out += &(l.line() + "\n");
            out += &l.layout.describe();
        }
        for (c, status) in &self.changes {
            let status = match status {
                Status::Region(k) if unplannable.contains(k) => format!(
                    "in region {}, which cannot be planned on (an episode refuses it)",
                    k + 1
                ),
                Status::Region(k) => format!("planned in region {}", k + 1),
                Status::LeftToSumo(k) => format!(
                    "in the region at {}, left to SUMO's drivers",
                    self.left_to_sumo[*k]
                        .layout
                        .merge_edges()
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                Status::NotPlanned => "not planned yet, SUMO's drivers drive it".into(),
            };
            out += &format!("{} {}: {status}\n", c.kind.as_str(), c.what);
        }
        for n in &self.not_merges {
            out += &format!("not a merge: ramp '{}' {}\n", n.ramp, n.why);
        }
        let mut by_why: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
        for (edge, why) in &self.left_out {
            by_why.entry(why).or_default().push(edge);
        }
        for (why, edges) in by_why {
            out += &format!(
                "left out, {why} ({} edges): {}\n",
                edges.len(),
                edges.join(" ")
            );
        }
        out
    }
}

impl super::LeftToSumo {
    /// The line that says the region is left to SUMO's drivers, and why: also what an
    /// episode prints at its start.
    pub fn line(&self) -> String {
        let l = self;
        format!(
            "region at {} left to SUMO's drivers: on-ramp {}; the planners would stop its \
             traffic where that lane ends (its CAVs are driven by SUMO too)",
            l.layout.merge_edges().collect::<Vec<_>>().join(", "),
            l.why
        )
    }
}
