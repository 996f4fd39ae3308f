//! Per arm of a campaign over scenarios (scenario, α, planner), the vehicles SUMO inserted and
//! those it never inserted, each the mean over the seeds of `episode.csv`'s `inserted` and
//! `never_inserted`: a planner that holds traffic back at the network's entrances shows it
//! here, which no delay of the vehicles that entered can (on a congested cloverleaf bk-pbs
//! inserted 683 vehicles and SUMO alone 735 from the same routes).

use std::collections::BTreeMap;

use super::stats::Estimate;
use crate::episode::summary::{Summary, Traffic};

/// One arm's counts, per seed.
#[derive(Debug, Clone, Default, PartialEq)]
struct Counts {
    inserted: Vec<f64>,
    never_inserted: Vec<f64>,
}

/// (scenario, α as text, planner) → its episodes' counts; planners in the order of `planners`.
type ByArm = BTreeMap<(String, String, usize), (String, Counts)>;

fn by_arm(episodes: &[csv::StringRecord], planners: &[String]) -> ByArm {
    let h = Summary::header(Traffic::Scenario);
    let at = |name: &str| h.iter().position(|c| c == name).expect("a summary column");
    let get = |r: &csv::StringRecord, name: &str| r.get(at(name)).unwrap_or("").to_string();
    let num = |r: &csv::StringRecord, name: &str| get(r, name).parse::<f64>().unwrap_or(0.0);
    let mut out = ByArm::new();
    for r in episodes {
        let planner = get(r, "planner");
        let order = planners
            .iter()
            .position(|p| *p == planner)
            .unwrap_or(usize::MAX);
        let (_, c) = out
            .entry((get(r, "scenario"), get(r, "alpha"), order))
            .or_insert_with(|| (planner, Counts::default()));
        c.inserted.push(num(r, "inserted"));
        c.never_inserted.push(num(r, "never_inserted"));
    }
    out
}

fn mean(xs: &[f64]) -> String {
    Estimate::of(xs).map_or(String::new(), |e| format!("{:.2}", e.mean))
}

/// `inserted.csv` and its Markdown section, from the campaign's `episodes` rows, the planners
/// in their grid order (`planners`).
pub fn inserted_tables(episodes: &[csv::StringRecord], planners: &[String]) -> (String, String) {
    let mut csv = String::from("scenario,alpha,planner,seeds,mean_inserted,mean_never_inserted\n");
    let mut md = String::from(
        "### Vehicles inserted and never inserted\n\n\
         Per episode, the mean over the seeds: the vehicles SUMO inserted, and those whose \
         departure time came but which it never inserted (`never_inserted`).\n\n\
         | scenario | α | planner | seeds | inserted | never inserted |\n\
         | --- | --- | --- | ---: | ---: | ---: |\n",
    );
    for ((scenario, alpha, _), (planner, c)) in by_arm(episodes, planners) {
        let (n, ins, never) = (c.inserted.len(), mean(&c.inserted), mean(&c.never_inserted));
        csv += &format!("{scenario},{alpha},{planner},{n},{ins},{never}\n");
        md += &format!("| {scenario} | {alpha} | {planner} | {n} | {ins} | {never} |\n");
    }
    (csv, md + "\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An `episode.csv` row of `planner` on `ramp.sumocfg` at α 0.3 with these counts.
    fn row(planner: &str, inserted: usize, never_inserted: usize) -> csv::StringRecord {
        let s = Summary {
            scenario: Some("ramp.sumocfg".into()),
            planner: planner.into(),
            alpha: 0.3,
            inserted,
            never_inserted,
            ..Summary::template(Traffic::Scenario)
        };
        let bytes = Summary::csv(Traffic::Scenario, &[s]);
        let mut r = csv::Reader::from_reader(&bytes[..]);
        r.records().next().unwrap().unwrap()
    }

    #[test]
    fn each_arm_shows_its_mean_inserted_and_never_inserted_in_grid_order() {
        let episodes = [
            row("sumo", 735, 0),
            row("bk-pbs", 683, 52),
            row("bk-pbs", 690, 46),
        ];
        let planners = ["bk-pbs".to_string(), "sumo".into()];
        let (csv, md) = inserted_tables(&episodes, &planners);
        assert_eq!(
            csv,
            "scenario,alpha,planner,seeds,mean_inserted,mean_never_inserted\n\
             ramp.sumocfg,0.3,bk-pbs,2,686.50,49.00\n\
             ramp.sumocfg,0.3,sumo,1,735.00,0.00\n"
        );
        assert!(
            md.contains("| ramp.sumocfg | 0.3 | bk-pbs | 2 | 686.50 | 49.00 |\n| ramp.sumocfg"),
            "{md}"
        );
    }
}
