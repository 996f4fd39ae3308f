//! The report of a campaign over scenarios of the user's own: per merge region, each planner's
//! system delay in the region and SUMO's `timeLoss` over the seeds, and each planner against
//! reference planners, seed by seed.
//!
//! Files in `<dir>/report/`:
//! - `regions.csv`: per scenario, region, α and planner, the mean over the seeds of the
//!   region's mean system delay with its 95 % t-interval, of its vehicles' mean `timeLoss`, of
//!   the vehicles still driving at the end; the controllable crashes summed; the vehicles that
//!   entered it from an on-ramp (mean over the seeds) and the episodes in which none did.
//! - `paired_regions.csv`: per scenario, region, α, reference and other planner, the mean of
//!   the per-seed differences reference − other of the region's mean system delay, its 95 %
//!   t-interval and the two-sided paired t-test's p-value.
//! - `paired_entries.csv`: the same per entry of each region (its main road and each on-ramp),
//!   with each planner's vehicles and arrivals beside ([`super::scenario_entries`]).
//! - `paired_collisions.csv`: per scenario, α, reference and other planner, the episodes with
//!   a controllable crash of each, and Fisher's exact test of the 2×2 table.
//! - `inserted.csv`: per scenario, α and planner, the vehicles SUMO inserted and those it never
//!   inserted, each the mean over the seeds ([`super::scenario_inserted`]).
//! - `tables.md`: the vehicles inserted and never inserted, the regions whose merge saw no
//!   ramp traffic in some episode (their delays are of traffic past a merge nobody used), then
//!   the paired tables, in Markdown.
//!
//! The paired t-test, not Wilcoxon's: a scenario's episodes are long and few (three seeds give
//! Wilcoxon a smallest p of 0.25), and the per-seed differences of a mean over hundreds of
//! vehicles are close to normal.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use super::scenario_common::{column, fmt_opt, paired_t, records};
use super::scenario_entries::{paired_entries, regions_with_ramps};
use super::scenario_inserted::inserted_tables;
use super::signif::fisher_exact;
use super::stats::Estimate;
use super::{Report, ReportError, REPORT_DIR};
use crate::campaign::results::Results;
use crate::episode::summary::{Summary, Traffic};

/// A reference planner that ran in none of the campaign's episodes.
#[derive(Debug, thiserror::Error)]
#[error("--versus: planner '{name}' is not in the campaign (it ran: {known})")]
pub struct UnknownReference {
    /// The name given.
    pub name: String,
    /// The planners that ran, comma-separated.
    pub known: String,
}

/// One region row's figures, as read from `regions.csv`.
#[derive(Debug, Clone)]
struct RegionSample {
    seed: u64,
    delay: Option<f64>,
    time_loss: Option<f64>,
    present: f64,
    controllable: f64,
    from_ramp: f64,
}

/// (scenario, region, α as text) → planner → samples, in seed order.
type ByRegion = BTreeMap<(String, String, String), BTreeMap<String, Vec<RegionSample>>>;

fn by_region(rows: &[csv::StringRecord], h: &[String]) -> ByRegion {
    let get = |r: &csv::StringRecord, name: &str| r.get(column(h, name)).unwrap_or("").to_string();
    let num = |r: &csv::StringRecord, name: &str| get(r, name).parse::<f64>().ok();
    let mut out = ByRegion::new();
    for r in rows {
        let key = (get(r, "scenario"), get(r, "region"), get(r, "alpha"));
        out.entry(key)
            .or_default()
            .entry(get(r, "planner"))
            .or_default()
            .push(RegionSample {
                seed: get(r, "seed").parse().unwrap_or(0),
                delay: num(r, "mean_delay_s"),
                time_loss: num(r, "mean_time_loss_s"),
                present: num(r, "present").unwrap_or(0.0),
                controllable: num(r, "controllable_crashed").unwrap_or(0.0),
                from_ramp: num(r, "from_ramp").unwrap_or(0.0),
            });
    }
    out
}

/// The planners in their first-seen order (the grid's).
fn planners_of(episodes: &[csv::StringRecord]) -> Vec<String> {
    let i = column(&Summary::header(Traffic::Scenario), "planner");
    let mut out: Vec<String> = Vec::new();
    for r in episodes {
        let p = r.get(i).unwrap_or("").to_string();
        if !out.contains(&p) {
            out.push(p);
        }
    }
    out
}

/// Writes the report of the campaign over scenarios whose collected files are `res` (by arm,
/// [`super::arms::by_arm`]) into `<out>/report/`, comparing every planner with the `versus` planners (default: `bk-pbs` when
/// it ran).
///
/// # Errors
/// A reference did not run, or a file cannot be written.
pub fn report(res: &Results, out: &Path, versus: &[String]) -> Result<Report, ReportError> {
    let (episodes, regions) = (records(&res.episodes), records(&res.regions));
    let planners = planners_of(&episodes);
    let versus: Vec<String> = match versus {
        [] => planners
            .iter()
            .filter(|p| *p == "bk-pbs")
            .cloned()
            .collect(),
        given => given.to_vec(),
    };
    if let Some(name) = versus.iter().find(|v| !planners.contains(v)) {
        return Err(ReportError::Reference(UnknownReference {
            name: name.clone(),
            known: planners.join(", "),
        }));
    }
    let regions = by_region(&regions, &res.regions.header);
    let (paired, paired_md) = paired_csv(&regions, &versus);
    let (inserted, inserted_md) = inserted_tables(&episodes, &planners);
    let entries = records(&res.entries);
    let (by_entry, by_entry_md) = paired_entries(&entries, &res.entries.header, &versus);
    let ramps = regions_with_ramps(&entries, &res.entries.header);
    let markdown = inserted_md + &unused_merges_md(&regions, &ramps) + &paired_md + &by_entry_md;
    let files = [
        ("regions.csv", summary_csv(&regions)),
        ("paired_regions.csv", paired),
        ("paired_entries.csv", by_entry),
        ("paired_collisions.csv", collisions_csv(&episodes, &versus)),
        ("inserted.csv", inserted),
    ];
    let report_dir = out.join(REPORT_DIR);
    let mut written = Vec::new();
    for (name, bytes) in files {
        let p = report_dir.join(name);
        crate::io::write_atomic(&p, bytes.as_bytes())?;
        written.push(p);
    }
    let p = report_dir.join("tables.md");
    crate::io::write_atomic(&p, markdown.as_bytes())?;
    written.push(p);
    Ok(Report {
        markdown,
        files: written,
        out: out.to_path_buf(),
    })
}

/// The regions whose merge no ramp vehicle entered in some episode, as a Markdown section: the
/// A10KW game's two merges once got 2 and 0 ramp vehicles in 30 minutes, and their delays were
/// read as merge results. Only regions with an on-ramp (`ramps`, by scenario and region) can be
/// so: a region of lane drops alone has none to leave unused.
fn unused_merges_md(regions: &ByRegion, ramps: &BTreeSet<(String, String)>) -> String {
    let mut rows = String::new();
    for ((scenario, region, alpha), planners) in regions {
        if !ramps.contains(&(scenario.clone(), region.clone())) {
            continue;
        }
        for (planner, samples) in planners {
            let none = samples.iter().filter(|x| x.from_ramp == 0.0).count();
            if none > 0 {
                rows += &format!(
                    "| {scenario} | {region} | {alpha} | {planner} | {none} of {} |\n",
                    samples.len()
                );
            }
        }
    }
    let head = "### Merges without ramp traffic\n\n";
    if rows.is_empty() {
        return format!(
            "{head}Every region with an on-ramp received ramp vehicles in every episode.\n\n"
        );
    }
    format!(
        "{head}In these episodes no vehicle entered the region from an on-ramp: its delays there \
         are of traffic past a merge nobody used, not merge results.\n\n\
         | scenario | region | α | planner | episodes without a ramp vehicle |\n\
         | --- | --- | --- | --- | --- |\n{rows}\n"
    )
}

fn summary_csv(regions: &ByRegion) -> String {
    let mut s = String::from(
        "scenario,region,alpha,planner,seeds,mean_delay_s,delay_ci95_s,mean_time_loss_s,mean_present,controllable_crashed,mean_from_ramp,episodes_without_ramp_traffic\n",
    );
    for ((scenario, region, alpha), planners) in regions {
        for (planner, samples) in planners {
            let delays: Vec<f64> = samples.iter().filter_map(|x| x.delay).collect();
            let losses: Vec<f64> = samples.iter().filter_map(|x| x.time_loss).collect();
            let delay = Estimate::of(&delays);
            let present: Vec<f64> = samples.iter().map(|x| x.present).collect();
            let from_ramp: Vec<f64> = samples.iter().map(|x| x.from_ramp).collect();
            s += &format!(
                "{scenario},{region},{alpha},{planner},{},{},{},{},{},{},{},{}\n",
                samples.len(),
                fmt_opt(delay.map(|e| e.mean), 4),
                fmt_opt(delay.and_then(|e| e.ci95), 4),
                fmt_opt(Estimate::of(&losses).map(|e| e.mean), 4),
                fmt_opt(Estimate::of(&present).map(|e| e.mean), 2),
                samples.iter().map(|x| x.controllable).sum::<f64>(),
                fmt_opt(Estimate::of(&from_ramp).map(|e| e.mean), 2),
                from_ramp.iter().filter(|&&n| n == 0.0).count()
            );
        }
    }
    s
}

/// The per-seed differences reference − other of the region delay, paired on seed.
fn differences(reference: &[RegionSample], other: &[RegionSample]) -> Vec<f64> {
    reference
        .iter()
        .filter_map(|r| {
            let o = other.iter().find(|o| o.seed == r.seed)?;
            Some(r.delay? - o.delay?)
        })
        .collect()
}

/// `paired_regions.csv` and its Markdown table.
fn paired_csv(regions: &ByRegion, versus: &[String]) -> (String, String) {
    let mut csv = String::from(
        "scenario,region,alpha,reference,planner,pairs,mean_difference_s,ci95_low_s,ci95_high_s,p_paired_t\n",
    );
    let mut md = String::from(
        "### System delay in each region: reference − planner, paired over seeds\n\n\
         | scenario | region | α | reference − planner | pairs | mean (s) | 95 % interval (s) | p (paired t) |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for ((scenario, region, alpha), planners) in regions {
        for reference in versus {
            let Some(r) = planners.get(reference) else {
                continue;
            };
            for (planner, o) in planners.iter().filter(|(p, _)| *p != reference) {
                let Some(t) = paired_t(&differences(r, o)) else {
                    continue;
                };
                let (lo, hi) = t.interval();
                csv += &format!(
                    "{scenario},{region},{alpha},{reference},{planner},{},{:.4},{},{},{}\n",
                    t.n,
                    t.mean,
                    fmt_opt(lo, 4),
                    fmt_opt(hi, 4),
                    fmt_opt(t.p, 4)
                );
                md += &format!(
                    "| {scenario} | {region} | {alpha} | {reference} − {planner} | {} | {:+.2} | {} | {} |\n",
                    t.n,
                    t.mean,
                    t.interval_md(),
                    fmt_opt(t.p, 3)
                );
            }
        }
    }
    (csv, md)
}

/// `paired_collisions.csv`: episodes with a controllable crash, per scenario and α.
fn collisions_csv(episodes: &[csv::StringRecord], versus: &[String]) -> String {
    let h = Summary::header(Traffic::Scenario);
    let get = |r: &csv::StringRecord, name: &str| r.get(column(&h, name)).unwrap_or("").to_string();
    // (scenario, α) → planner → (episodes, with a controllable crash)
    let mut counts: BTreeMap<(String, String), BTreeMap<String, (u64, u64)>> = BTreeMap::new();
    for r in episodes {
        let crashed = get(r, "controllable_crashed").parse::<u64>().unwrap_or(0) > 0;
        let c = counts
            .entry((get(r, "scenario"), get(r, "alpha")))
            .or_default()
            .entry(get(r, "planner"))
            .or_default();
        c.0 += 1;
        c.1 += u64::from(crashed);
    }
    let mut s = String::from(
        "scenario,alpha,reference,planner,reference_episodes,reference_with_crash,episodes,with_crash,p_fisher\n",
    );
    for ((scenario, alpha), planners) in &counts {
        for reference in versus {
            let Some(&(rn, rc)) = planners.get(reference) else {
                continue;
            };
            for (planner, &(n, c)) in planners.iter().filter(|(p, _)| *p != reference) {
                let p = fisher_exact(rc, rn - rc, c, n - c);
                s +=
                    &format!("{scenario},{alpha},{reference},{planner},{rn},{rc},{n},{c},{p:.4}\n");
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(seed: u64, from_ramp: f64) -> RegionSample {
        RegionSample {
            seed,
            delay: Some(1.0),
            time_loss: Some(2.0),
            present: 0.0,
            controllable: 0.0,
            from_ramp,
        }
    }

    #[test]
    fn a_merge_nobody_used_is_named_with_its_episodes() {
        let mut regions = ByRegion::new();
        let key = (
            "A10KW.sumocfg".to_string(),
            "4054057".to_string(),
            "0.3".to_string(),
        );
        let planners = regions.entry(key).or_default();
        planners.insert(
            "sumo".into(),
            vec![sample(1, 0.0), sample(2, 0.0), sample(3, 2.0)],
        );
        planners.insert("bk-pbs".into(), vec![sample(1, 5.0)]);
        let ramps = BTreeSet::from([("A10KW.sumocfg".to_string(), "4054057".to_string())]);
        let md = unused_merges_md(&regions, &ramps);
        assert!(
            md.contains("| A10KW.sumocfg | 4054057 | 0.3 | sumo | 2 of 3 |"),
            "{md}"
        );
        assert!(!md.contains("bk-pbs"), "{md}");
        let csv = summary_csv(&regions);
        assert!(
            csv.contains(",sumo,3,1.0000,0.0000,2.0000,0.00,0,0.67,2\n"),
            "{csv}"
        );
        // A region of lane drops alone has no ramp to leave unused.
        let no_ramp = unused_merges_md(&regions, &BTreeSet::new());
        assert!(
            no_ramp.contains("Every region with an on-ramp received ramp vehicles"),
            "{no_ramp}"
        );
        regions
            .values_mut()
            .for_each(|p| p.remove("sumo").map(drop).unwrap_or(()));
        let md = unused_merges_md(&regions, &ramps);
        assert!(
            md.contains("Every region with an on-ramp received ramp vehicles"),
            "{md}"
        );
    }

    #[test]
    fn the_paired_t_test_matches_a_worked_example() {
        // t.test(c(-5.2, -4.1, -6.0)): t = -9.2600, df = 2, 95 % interval [-7.4697, -2.7303];
        // with 2 degrees of freedom p = 1 - |t| / sqrt(t² + 2) = 0.011462.
        let t = paired_t(&[-5.2, -4.1, -6.0]).unwrap();
        assert!((t.mean + 5.1).abs() < 1e-12);
        assert!((t.half.unwrap() - 2.369_716).abs() < 1e-5, "{t:?}");
        let p = 1.0 - 9.259_981_f64 / (9.259_981_f64.powi(2) + 2.0).sqrt();
        assert!((t.p.unwrap() - p).abs() < 1e-6, "{t:?}");
        assert!(paired_t(&[1.0]).unwrap().p.is_none());
    }
}
