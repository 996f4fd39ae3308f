//! CSV files of an episode, written atomically (temporary file, then rename), so a crash or a
//! kill never leaves a half-written result and an earlier result stays until replaced whole.

use std::path::{Path, PathBuf};

use super::trajectories;
use crate::episode::cells;
use crate::episode::metrics::{CollisionEvent, Timing};
use crate::episode::rows::{CollisionRow, TimingRow, VehicleRow};
use crate::episode::summary::{Summary, Traffic};
use crate::episode::trace::TRACE_FILE;
use crate::episode::EpisodeResult;
use crate::io::SetFile;
pub use crate::io::{write_atomic, WriteError};

/// `timing.csv` of an episode's `timing` as bytes.
pub fn timing_csv(timing: &Timing) -> Vec<u8> {
    cells::csv_text(&TimingRow::default(), &[TimingRow::of(timing)])
}

/// `collisions.csv` of `events` as bytes.
pub fn collisions_csv(events: &[CollisionEvent]) -> Vec<u8> {
    let rows: Vec<CollisionRow> = events.iter().map(CollisionRow::of).collect();
    cells::csv_text(&CollisionRow::default(), &rows)
}

impl EpisodeResult {
    /// `episode.csv` as bytes.
    pub fn episode_csv(&self) -> Vec<u8> {
        Summary::csv(Traffic::Demand, std::slice::from_ref(&self.summary))
    }

    /// `vehicles.csv` as bytes.
    pub fn vehicles_csv(&self) -> Vec<u8> {
        let rows: Vec<VehicleRow> = self.vehicles.iter().map(VehicleRow::of).collect();
        VehicleRow::csv(Traffic::Demand, &rows)
    }

    /// `collisions.csv` as bytes.
    pub fn collisions_csv(&self) -> Vec<u8> {
        collisions_csv(&self.collisions)
    }

    /// `timing.csv` as bytes.
    pub fn timing_csv(&self) -> Vec<u8> {
        timing_csv(&self.timing)
    }

    /// Writes the four CSV files (and SUMO's log and the trajectories, if any) into `dir` as
    /// one set, `episode.csv` last: its presence marks a complete episode directory. An earlier
    /// episode's files are replaced together (an old `sumo.log` or trajectory file the new run
    /// lacks is removed); returns the paths written.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, WriteError> {
        let (vehicles, collisions, timing, episode) = (
            self.vehicles_csv(),
            self.collisions_csv(),
            self.timing_csv(),
            self.episode_csv(),
        );
        let log = (!self.sumo_log.is_empty()).then_some(self.sumo_log.as_bytes());
        let trace = self.trace.as_deref().map(str::as_bytes);
        let mut files: Vec<SetFile> = vec![("sumo.log", log), (TRACE_FILE, trace)];
        for name in trajectories::FILE_NAMES {
            let mine = self.trajectories.as_ref().filter(|t| t.name == name);
            files.push((name, mine.map(|t| &t.bytes[..])));
        }
        files.extend([
            ("vehicles.csv", Some(&vehicles[..])),
            ("collisions.csv", Some(&collisions[..])),
            ("timing.csv", Some(&timing[..])),
            ("episode.csv", Some(&episode[..])),
        ]);
        crate::io::replace_together(dir, &files)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_whole_and_leaves_no_temp() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("sub/x.csv");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let names: Vec<_> = std::fs::read_dir(p.parent().unwrap()).unwrap().collect();
        assert_eq!(names.len(), 1);
    }

    #[test]
    fn unwritable_target_names_the_path() {
        let d = tempfile::tempdir().unwrap();
        let blocker = d.path().join("file");
        std::fs::write(&blocker, b"").unwrap();
        let e = write_atomic(&blocker.join("x.csv"), b"x").unwrap_err();
        assert!(e.to_string().contains("file/x.csv"), "{e}");
    }

    /// The episode.csv bytes of a summary, header and all, as they were before the summary
    /// became a serde struct: the columns, their order and each float's decimals.
    #[test]
    fn episode_csv_keeps_its_columns_and_decimals() {
        let s = Summary {
            planner: "bk-pbs".into(),
            alpha: 0.6,
            lambda: Some(3000.0),
            seed: 7,
            hdv_profile: Some("sumo-safe".into()),
            sumo_version: "1.28.0".into(),
            steps: 400,
            system: Some(crate::episode::summary::SystemDelay {
                system_delay_s: Some(2.0 / 3.0),
                system_delay_veh_h: 0.0012345678,
                own_speed_delay_s: Some(0.25),
            }),
            scheduled: Some(9),
            inserted: 8,
            never_inserted: 1,
            inserted_cav: 5,
            arrived: 6,
            crashed: 1,
            present: 1,
            controllable_crashed: 1,
            controllable_collision_rate: Some(1.0 / 8.0 + 1e-9),
            hdv_collisions: 0,
            travel: Some(crate::episode::summary::TravelFigures {
                hdv_crashed: 0,
                mean_delay_s: Some(1.0 / 3.0),
                mean_delay_cav_s: None,
                mean_delay_hdv_s: Some(-0.00004),
                throughput_veh_h: 270.0 + 1.0 / 7.0,
                throughput_window_s: 66.8,
                mean_speed_mps: 29.123456,
                stranded: 2,
            }),
            plan_stats: crate::controller::PlanStats {
                searches: 1,
                nodes_expanded: 2,
                phase2_plans: 3,
                fallbacks: 4,
                pbs_nodes: 5,
                pbs_depth: 6,
                predictions: 7,
                pbs_fallbacks: 8,
                time_budget_hits: 9,
                shield_overrides: 10,
            },
            ..Summary::default()
        };
        let text = String::from_utf8(Summary::csv(Traffic::Demand, &[s])).unwrap();
        assert_eq!(
            text,
            "planner,alpha,lambda,seed,hdv_profile,sumo_version,steps,system_delay_s,system_delay_veh_h,\
             own_speed_delay_s,scheduled,inserted,never_inserted,\
             inserted_cav,arrived,crashed,present,controllable_crashed,\
             controllable_collision_rate,hdv_collisions,hdv_crashed,mean_delay_s,\
             mean_delay_cav_s,mean_delay_hdv_s,throughput_veh_h,throughput_window_s,\
             mean_speed_mps,stranded,\
             plan_searches,plan_nodes_expanded,plan_phase2,plan_fallbacks,pbs_nodes,\
             pbs_depth_sum,predictions,pbs_fallbacks,time_budget_hits,shield_overrides\n\
             bk-pbs,0.6,3000,7,sumo-safe,1.28.0,400,0.6667,0.001235,0.2500,9,8,1,5,6,1,1,1,0.125000,\
             0,0,0.3333,,-0.0000,270.14,66.8000,29.1235,2,1,2,3,4,5,6,7,8,9,10\n"
        );
    }
}
