//! Each entry of a scenario's merge regions (its main road, each on-ramp), paired over seeds
//! against the reference planners: a ramp a planner closes shows here, where a region's mean
//! over all its vehicles can hide it (two on-ramps once received 22 of 84 vehicles, at 245 s of
//! delay, while the region's mean moved far less).
//!
//! `paired_entries.csv`: per scenario, region, entry, α, reference and other planner, the mean
//! of the per-seed differences reference − other of the entry's mean system delay in the region
//! (`entries.csv`'s `mean_delay_s`), its 95 % t-interval and the paired t-test's p-value, and
//! each planner's vehicles that came in by the entry and arrived, per episode (the mean over the
//! paired seeds). Its Markdown table closes `tables.md`.

use std::collections::{BTreeMap, BTreeSet};

use super::scenario_common::{column, fmt_opt, paired_t, PairedT};

/// One entry's figures in one episode: the vehicles that came into the region by it, those of
/// them that arrived, their mean system delay in the region.
#[derive(Debug, Clone, Copy)]
struct EntrySample {
    vehicles: f64,
    arrived: f64,
    delay: Option<f64>,
}

/// (scenario, region, entry, α as text).
type EntryKey = (String, String, String, String);

/// Entry → planner → seed → sample.
type ByEntry = BTreeMap<EntryKey, BTreeMap<String, BTreeMap<u64, EntrySample>>>;

/// The (scenario, region) pairs of `entries.csv`'s `rows` that have an on-ramp entry: a region
/// of lane drops alone has its main carriageway's only.
pub fn regions_with_ramps(rows: &[csv::StringRecord], h: &[String]) -> BTreeSet<(String, String)> {
    let get = |r: &csv::StringRecord, name: &str| r.get(column(h, name)).unwrap_or("").to_string();
    rows.iter()
        .filter(|r| get(r, "origin") == "ramp")
        .map(|r| (get(r, "scenario"), get(r, "region")))
        .collect()
}

fn by_entry(rows: &[csv::StringRecord], h: &[String]) -> ByEntry {
    let get = |r: &csv::StringRecord, name: &str| r.get(column(h, name)).unwrap_or("").to_string();
    let num = |r: &csv::StringRecord, name: &str| get(r, name).parse::<f64>().ok();
    let mut out = ByEntry::new();
    for r in rows {
        let key = (
            get(r, "scenario"),
            get(r, "region"),
            get(r, "entry"),
            get(r, "alpha"),
        );
        let sample = EntrySample {
            vehicles: num(r, "vehicles").unwrap_or(0.0),
            arrived: num(r, "arrived").unwrap_or(0.0),
            delay: num(r, "mean_delay_s"),
        };
        let seed = get(r, "seed").parse().unwrap_or(0);
        let planners = out.entry(key).or_default();
        planners
            .entry(get(r, "planner"))
            .or_default()
            .insert(seed, sample);
    }
    out
}

/// The mean of `f` over the samples of `seeds`.
fn mean_over(
    samples: &BTreeMap<u64, EntrySample>,
    seeds: &[u64],
    f: fn(&EntrySample) -> f64,
) -> f64 {
    let sum: f64 = seeds.iter().map(|s| f(&samples[s])).sum();
    sum / seeds.len().max(1) as f64
}

/// `paired_entries.csv` and its Markdown table, from `entries.csv`'s rows (header `h`).
pub fn paired_entries(
    rows: &[csv::StringRecord],
    h: &[String],
    versus: &[String],
) -> (String, String) {
    let mut csv = String::from(
        "scenario,region,entry,alpha,reference,planner,pairs,mean_difference_s,ci95_low_s,ci95_high_s,p_paired_t,reference_entered,planner_entered,reference_arrived,planner_arrived\n",
    );
    let mut md = String::from(
        "### System delay per entry: reference − planner, paired over seeds\n\n\
         Per episode, the vehicles that came into the region by each entry and those of them that arrived, reference vs planner (the mean over the pairs).\n\n\
         | scenario | region | entry | α | reference − planner | pairs | mean (s) | 95 % interval (s) | p (paired t) | entered | arrived |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for (key, planners) in by_entry(rows, h) {
        for reference in versus {
            let Some(r) = planners.get(reference) else {
                continue;
            };
            for (planner, o) in planners.iter().filter(|(p, _)| *p != reference) {
                if let Some(pair) = Pair::of(r, o) {
                    csv += &pair.csv_row(&key, (reference, planner));
                    md += &pair.md_row(&key, (reference, planner));
                }
            }
        }
    }
    (csv, md + "\n")
}

/// One entry's reference and other planner over the seeds both ran: the paired delays, and
/// each one's vehicles in and arrived (means per episode).
struct Pair {
    t: PairedT,
    entered: (f64, f64),
    arrived: (f64, f64),
}

impl Pair {
    fn of(r: &BTreeMap<u64, EntrySample>, o: &BTreeMap<u64, EntrySample>) -> Option<Pair> {
        let seeds: Vec<u64> = r.keys().filter(|s| o.contains_key(s)).copied().collect();
        let d: Vec<f64> = (seeds.iter())
            .filter_map(|s| Some(r[s].delay? - o[s].delay?))
            .collect();
        let both = |f: fn(&EntrySample) -> f64| (mean_over(r, &seeds, f), mean_over(o, &seeds, f));
        Some(Pair {
            t: paired_t(&d)?,
            entered: both(|x| x.vehicles),
            arrived: both(|x| x.arrived),
        })
    }

    fn csv_row(
        &self,
        (scenario, region, entry, alpha): &EntryKey,
        (reference, planner): (&str, &str),
    ) -> String {
        let (lo, hi) = self.t.interval();
        format!(
            "{scenario},{region},{entry},{alpha},{reference},{planner},{},{:.4},{},{},{},{:.2},{:.2},{:.2},{:.2}\n",
            self.t.n,
            self.t.mean,
            fmt_opt(lo, 4),
            fmt_opt(hi, 4),
            fmt_opt(self.t.p, 4),
            self.entered.0,
            self.entered.1,
            self.arrived.0,
            self.arrived.1
        )
    }

    fn md_row(
        &self,
        (scenario, region, entry, alpha): &EntryKey,
        (reference, planner): (&str, &str),
    ) -> String {
        format!(
            "| {scenario} | {region} | {entry} | {alpha} | {reference} − {planner} | {} | {:+.2} | {} | {} | {:.1} vs {:.1} | {:.1} vs {:.1} |\n",
            self.t.n,
            self.t.mean,
            self.t.interval_md(),
            fmt_opt(self.t.p, 3),
            self.entered.0,
            self.entered.1,
            self.arrived.0,
            self.arrived.1
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(
        planner: &str,
        seed: &str,
        entry: &str,
        vehicles: &str,
        delay: &str,
    ) -> csv::StringRecord {
        let arrived = (vehicles.parse::<u32>().unwrap() - 1).to_string();
        csv::StringRecord::from(vec![
            "s.sumocfg",
            planner,
            "0.6",
            seed,
            "acc",
            entry,
            vehicles,
            &arrived,
            delay,
        ])
    }

    #[test]
    fn a_ramp_is_paired_on_seed_with_its_counts_beside() {
        let h: Vec<String> = [
            "scenario",
            "planner",
            "alpha",
            "seed",
            "region",
            "entry",
            "vehicles",
            "arrived",
            "mean_delay_s",
        ]
        .map(String::from)
        .to_vec();
        let rows = [
            row("sumo", "1", "on", "40", "7.0"),
            row("sumo", "2", "on", "42", "9.0"),
            row("bk-pbs", "2", "on", "41", "8.0"),
            row("bk-pbs", "1", "on", "22", "245.0"),
            row("bk-pbs", "3", "on", "30", "1.0"),
        ];
        let (csv, md) = paired_entries(&rows, &h, &["sumo".to_string()]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 2, "{csv}");
        // Seeds 1 and 2 pair (3 has no reference): differences 7 − 245 and 9 − 8.
        let cells: Vec<&str> = lines[1].split(',').collect();
        assert_eq!(
            &cells[..7],
            ["s.sumocfg", "acc", "on", "0.6", "sumo", "bk-pbs", "2"]
        );
        assert_eq!(cells[7], "-118.5000");
        assert_eq!(&cells[11..], ["41.00", "31.50", "40.00", "30.50"]);
        assert!(
            md.contains("| s.sumocfg | acc | on | 0.6 | sumo − bk-pbs | 2 | -118.50 |"),
            "{md}"
        );
    }
}
