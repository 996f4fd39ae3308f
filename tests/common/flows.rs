//! Scenarios of flows on networks the tests build, and each flow's vehicles counted from an
//! episode's `vehicles.csv`: what the layout tests compare with SUMO alone.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::csv_rows;

/// A flow: its id, its route's edges, the lane it departs on (SUMO's `departLane`), and
/// vehicles per hour.
pub type Flow<'a> = (&'a str, &'a str, &'a str, u32);

/// A scenario on `net` (in `dir`) whose `flows` run from 0 to `flows_end` s, the simulation to
/// `end` s, at 0.2 s steps; its path.
pub fn scenario(dir: &Path, net: &Path, flows: &[Flow], (flows_end, end): (u32, u32)) -> PathBuf {
    let mut routes = String::from("<routes>\n<vType id=\"car\" length=\"5\" maxSpeed=\"30\"/>\n");
    for (id, edges, lane, rate) in flows {
        routes += &format!("<route id=\"r_{id}\" edges=\"{edges}\"/>\n");
        routes += &format!(
            "<flow id=\"{id}\" type=\"car\" route=\"r_{id}\" begin=\"0\" end=\"{flows_end}\" \
             vehsPerHour=\"{rate}\" departSpeed=\"max\" departLane=\"{lane}\"/>\n"
        );
    }
    super::write_scenario(dir, "s", net, &(routes + "</routes>\n"), end)
}

/// Per flow: vehicles inserted, arrived, and their mean delay (SUMO's timeLoss plus the wait
/// to enter, s).
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct FlowCount {
    pub inserted: usize,
    pub arrived: usize,
    pub delay: f64,
}

/// Each flow's count in the episode written to `out` (vehicle ids are `FLOW.N`).
pub fn per_flow(out: &Path) -> BTreeMap<String, FlowCount> {
    let mut flows: BTreeMap<String, FlowCount> = BTreeMap::new();
    for v in csv_rows(&std::fs::read(out.join("vehicles.csv")).unwrap()) {
        let flow = v["id"].split('.').next().unwrap().to_string();
        let f = flows.entry(flow).or_default();
        let num = |k: &str| v[k].parse::<f64>().unwrap_or(0.0);
        f.inserted += 1;
        f.arrived += usize::from(v["outcome"] == "arrived");
        f.delay += num("time_loss_s") + num("depart_delay_s");
    }
    for f in flows.values_mut() {
        f.delay /= f.inserted.max(1) as f64;
    }
    flows
}

/// Whether `x` lies within 3 % of `y`.
pub fn within_3_percent(x: usize, y: usize) -> bool {
    (x as f64 - y as f64).abs() <= 0.03 * y as f64
}
