//! An episode's trajectories as the time–space figures need them: per road-frame lane, each
//! vehicle's stretches of (t, s, speed), with its lane changes and collisions as marks.
//!
//! Read from `trajectories.csv` (or `.csv.gz`) and `collisions.csv` of an episode directory.

use std::collections::{BTreeMap, HashMap};
use std::io::Read;
use std::path::{Path, PathBuf};

/// Why an episode's trajectories could not be read.
#[derive(Debug, thiserror::Error)]
pub enum TracksError {
    /// The episode was run without `--trajectories`.
    #[error(
        "{dir} has no trajectories.csv: run the episode with `bkpbs episode --trajectories` \
         (the FCD format has no road frame to plot)"
    )]
    Missing {
        /// The episode directory.
        dir: PathBuf,
    },
    /// The trajectory file could not be read (or decompressed, or is not UTF-8).
    #[error("cannot read {path}: {cause}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        cause: std::io::Error,
    },
    /// A line of the trajectory file lacks a column or holds a non-number.
    #[error("malformed {path}, line {line}: {message}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line number (1 is the header).
        line: u64,
        /// What is wrong with it.
        message: String,
    },
    /// `collisions.csv` could not be read.
    #[error(transparent)]
    Collisions(#[from] super::explain::ExplainError),
}

/// One vehicle's stay on one lane: consecutive (t, s, speed) samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Stretch {
    /// The vehicle's id.
    pub id: String,
    /// Whether the vehicle is a CAV (drawn thick) rather than an HDV.
    pub cav: bool,
    /// (t in s, road-frame s in m, speed in m/s) of each sample, in time order.
    pub points: Vec<(f64, f64, f64)>,
}

/// Where something happened in the time–space plane of a lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mark {
    /// Road-frame lane (0 the ramp / auxiliary lane, 1.. the main lanes from the right).
    pub lane: i32,
    /// Simulation time (s).
    pub t: f64,
    /// Road-frame longitudinal position (m).
    pub s: f64,
}

/// The trajectories of an episode, by lane.
#[derive(Debug, Clone, Default)]
pub struct LaneTracks {
    /// Road-frame lane → the stretches driven on it, in order of first appearance.
    pub lanes: BTreeMap<i32, Vec<Stretch>>,
    /// A vehicle's lane change, marked on both lanes at the first sample on the new lane.
    pub lane_changes: Vec<Mark>,
    /// Collisions, at the collider's last sample.
    pub collisions: Vec<Mark>,
    /// Time step of the samples (s).
    pub dt: f64,
}

impl LaneTracks {
    /// The largest speed (for the colour scale).
    pub fn max_speed(&self) -> f64 {
        self.samples().map(|p| p.2).fold(0.0, f64::max)
    }

    /// Every sample of every lane.
    pub fn samples(&self) -> impl Iterator<Item = &(f64, f64, f64)> {
        self.lanes
            .values()
            .flatten()
            .flat_map(|st| st.points.iter())
    }
}

/// The trajectory file of `dir` (plain or compressed).
fn trajectory_file(dir: &Path) -> Result<PathBuf, TracksError> {
    ["trajectories.csv", "trajectories.csv.gz"]
        .iter()
        .map(|n| dir.join(n))
        .find(|p| p.is_file())
        .ok_or_else(|| TracksError::Missing {
            dir: dir.to_path_buf(),
        })
}

fn read_text(path: &Path) -> Result<String, TracksError> {
    let err = |cause| TracksError::Read {
        path: path.to_path_buf(),
        cause,
    };
    let bytes =
        crate::io::bounded::read_bytes(path, crate::io::bounded::FileKind::Data).map_err(err)?;
    let mut text = String::new();
    if path.extension().is_some_and(|e| e == "gz") {
        flate2::read::GzDecoder::new(&bytes[..])
            .read_to_string(&mut text)
            .map_err(err)?;
    } else {
        text = String::from_utf8(bytes)
            .map_err(|e| err(std::io::Error::new(std::io::ErrorKind::InvalidData, e)))?;
    }
    Ok(text)
}

/// One trajectory row, the fields the figures use.
struct Sample {
    t: f64,
    id: String,
    cav: bool,
    lane: i32,
    s: f64,
    speed: f64,
}

/// Reads the trajectories and collisions of an episode directory.
pub fn read(dir: &Path) -> Result<LaneTracks, TracksError> {
    let path = trajectory_file(dir)?;
    let samples = parse_samples(&path, &read_text(&path)?)?;
    let mut tracks = LaneTracks::default();
    let mut times: Vec<f64> = samples.iter().map(|s| s.t).collect();
    times.dedup();
    tracks.dt = times
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    // The open stretch of each vehicle: (lane, index in that lane's list).
    let mut open: HashMap<String, (i32, usize)> = HashMap::new();
    let mut last: HashMap<String, (f64, i32, f64)> = HashMap::new();
    for smp in samples {
        let stretches = tracks.lanes.entry(smp.lane).or_default();
        match open.get(&smp.id) {
            Some(&(lane, k)) if lane == smp.lane => {
                stretches[k].points.push((smp.t, smp.s, smp.speed));
            }
            previous => {
                if let Some(&(from, _)) = previous {
                    for lane in [from, smp.lane] {
                        tracks.lane_changes.push(Mark {
                            lane,
                            t: smp.t,
                            s: smp.s,
                        });
                    }
                }
                stretches.push(Stretch {
                    id: smp.id.clone(),
                    cav: smp.cav,
                    points: vec![(smp.t, smp.s, smp.speed)],
                });
                open.insert(smp.id.clone(), (smp.lane, stretches.len() - 1));
            }
        }
        last.insert(smp.id, (smp.t, smp.lane, smp.s));
    }
    tracks.collisions = read_collisions(dir, &last)?;
    Ok(tracks)
}

fn parse_samples(path: &Path, text: &str) -> Result<Vec<Sample>, TracksError> {
    let malformed = |line: u64, message: String| TracksError::Malformed {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let header = reader
        .headers()
        .map_err(|e| malformed(1, e.to_string()))?
        .clone();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| malformed(1, format!("no column {name}")))
    };
    let [t, id, kind, s, lane, speed] = ["time", "id", "type", "s", "lane", "speed"].map(column);
    let (t, id, kind, s, lane, speed) = (t?, id?, kind?, s?, lane?, speed?);
    let mut out = Vec::new();
    for (k, rec) in reader.records().enumerate() {
        let line = k as u64 + 2;
        let rec = rec.map_err(|e| malformed(line, e.to_string()))?;
        let field = |i: usize| rec.get(i).unwrap_or("");
        if field(s).is_empty() {
            continue; // off the merge section: no road-frame position to plot
        }
        let number = |i: usize| -> Result<f64, TracksError> {
            field(i)
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| malformed(line, format!("'{}' is not a number", field(i))))
        };
        out.push(Sample {
            t: number(t)?,
            id: field(id).to_string(),
            cav: field(kind) == "cav",
            lane: number(lane)? as i32,
            s: number(s)?,
            speed: number(speed)?,
        });
    }
    Ok(out)
}

/// The collisions of `collisions.csv` (if there is one), each at its collider's last sample.
fn read_collisions(
    dir: &Path,
    last: &HashMap<String, (f64, i32, f64)>,
) -> Result<Vec<Mark>, TracksError> {
    let path = dir.join("collisions.csv");
    if !path.is_file() {
        return Ok(Vec::new());
    }
    Ok(super::explain::read_collisions(&path)?
        .iter()
        .filter_map(|c| last.get(&c.collider))
        .map(|&(t, lane, s)| Mark { lane, t, s })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "time,id,type,origin,edge,sumo_lane,pos,x,y,angle,s,lane,lateral,heading,speed,accel,speed_sent,lane_change,source\n";

    fn row(t: f64, id: &str, lane: i32, s: f64) -> String {
        format!("{t:.2},{id},cav,ramp,acc,0,0,0,0,90,{s},{lane},0,0,20,0,,,\n")
    }

    #[test]
    fn a_lane_change_splits_the_stretch_and_is_marked_on_both_lanes() {
        let d = tempfile::tempdir().unwrap();
        let text = HEADER.to_string()
            + &row(0.0, "c", 0, 10.0)
            + &row(0.2, "c", 0, 14.0)
            + &row(0.4, "c", 1, 18.0)
            + &row(0.4, "h", 1, 50.0);
        std::fs::write(d.path().join("trajectories.csv"), text).unwrap();
        std::fs::write(
            d.path().join("collisions.csv"),
            "time_s,collider,collider_type,victim,victim_type,lane,position_m,controllable\n0.40,c,cav,h,hdv,acc_0,1,true\n",
        )
        .unwrap();
        let t = read(d.path()).unwrap();
        assert_eq!(t.lanes[&0].len(), 1);
        assert_eq!(t.lanes[&0][0].points.len(), 2);
        assert_eq!(t.lanes[&1].len(), 2);
        assert_eq!(t.lane_changes.len(), 2);
        assert_eq!(
            t.collisions,
            vec![Mark {
                lane: 1,
                t: 0.4,
                s: 18.0
            }]
        );
        assert!((t.dt - 0.2).abs() < 1e-9);
    }

    #[test]
    fn a_directory_without_trajectories_says_how_to_get_them() {
        let d = tempfile::tempdir().unwrap();
        let e = read(d.path()).unwrap_err().to_string();
        assert!(e.contains("--trajectories"), "{e}");
        std::fs::write(
            d.path().join("trajectories.csv"),
            HEADER.to_string() + "0.2,c,cav,ramp,acc,0,0,0,0,90,x,0,0,0,20,0,,,\n",
        )
        .unwrap();
        let e = read(d.path()).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("'x'"), "{e}");
    }
}
