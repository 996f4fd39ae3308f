//! Trajectories: one row per vehicle and step, what traffic researchers look at before they
//! trust a table (time–space diagrams, `bkpbs plot`).
//!
//! Two formats. `trajectories.csv`: time, identity, SUMO's edge, lane and position, x, y and
//! angle as SUMO reports them, the road-frame state (s of the centre, lane, lateral offset,
//! heading), speed, acceleration and, for commanded CAVs, the maneuver sent and its
//! [`Source`]. `trajectories.fcd.xml`: SUMO's own floating-car-data format (as `sumo
//! --fcd-output` writes it, same times and precision) for SUMO's tools.
//!
//! Rows are formatted as the episode runs, so memory holds text rather than records; past
//! [`GZIP_ABOVE_BYTES`] the text is gzip-compressed on the fly and the file gets `.gz`. The
//! switch depends only on the content, so the same seed still gives the same bytes.

use std::fmt::Write as _;
use std::io::Write as _;
use std::sync::Arc;

use flate2::write::GzEncoder;
use flate2::Compression;

use crate::config::TrajectoryFormat;
use crate::controller::{LaneChange, Source};
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin, VehicleState};
use crate::sumo::RawVehicleState;

/// Uncompressed size past which trajectories are gzip-compressed (16 MiB: a 400-step episode
/// of the paper's scenario stays plain, a long corridor run does not).
pub const GZIP_ABOVE_BYTES: usize = 16 << 20;

/// Header of `trajectories.csv`.
pub const CSV_COLUMNS: [&str; 19] = [
    "time",
    "id",
    "type",
    "origin",
    "edge",
    "sumo_lane",
    "pos",
    "x",
    "y",
    "angle",
    "s",
    "lane",
    "lateral",
    "heading",
    "speed",
    "accel",
    "speed_sent",
    "lane_change",
    "source",
];

/// One vehicle at one step, as SUMO reported it and as the road frame sees it.
#[derive(Debug, Clone)]
pub struct TrajectoryRow {
    /// SUMO vehicle id.
    pub id: std::sync::Arc<str>,
    /// CAV or HDV (the `type` column).
    pub kind: Kind,
    /// Main road or on-ramp.
    pub origin: Origin,
    /// SUMO's edge id; `None` off the known edges.
    pub edge: Option<Arc<str>>,
    /// SUMO's lane index on `edge` (0 the rightmost).
    pub sumo_lane: i32,
    /// Position of the front bumper along SUMO's lane (m).
    pub pos: f64,
    /// Front-bumper x position in SUMO's network coordinates (m).
    pub x: f64,
    /// Front-bumper y position in SUMO's network coordinates (m).
    pub y: f64,
    /// SUMO's heading angle (degrees, 0 = north, clockwise).
    pub angle: f64,
    /// Road-frame state of the centre; `None` off the merge section.
    pub frame: Option<FrameState>,
    /// Speed (m/s), SUMO's.
    pub speed: f64,
    /// Acceleration over the last step (m/s²), SUMO's.
    pub accel: f64,
    /// The maneuver sent to SUMO after this step (commanded CAVs only).
    pub sent: Option<Sent>,
}

/// The road-frame part of a row.
#[derive(Debug, Clone, Copy)]
pub struct FrameState {
    /// Longitudinal position of the centre along the road (m).
    pub s: f64,
    /// Road-frame lane (0 = ramp / acceleration lane).
    pub lane: i32,
    /// Offset from the lane centre (m, positive to the left): non-zero mid lane change.
    pub lateral: f64,
    /// Heading relative to the road direction (rad, positive to the left).
    pub heading: f64,
}

/// What was sent to a CAV for the next step, and where it came from.
#[derive(Debug, Clone, Copy)]
pub struct Sent {
    /// Speed commanded for the end of the next step (m/s, bounded to [0, v_max]).
    pub speed: f64,
    /// The lane change started, if any.
    pub lane_change: Option<LaneChange>,
    /// Where the maneuver came from.
    pub source: Source,
}

impl TrajectoryRow {
    /// The row of SUMO's reading `raw` of vehicle `id` (edge codes counted in `road`), with
    /// its state in the road frame (`None` off the section); no maneuver yet (one is sent after
    /// planning).
    pub fn of_reading(
        road: &Road,
        (id, kind, origin): (Arc<str>, Kind, Origin),
        raw: &RawVehicleState,
        state: Option<&VehicleState>,
    ) -> TrajectoryRow {
        TrajectoryRow {
            id,
            kind,
            origin,
            edge: usize::try_from(raw.edge_code)
                .ok()
                .and_then(|c| road.edges.get(c))
                .map(|e| e.name.clone()),
            sumo_lane: raw.lane_index,
            pos: raw.lane_position,
            x: raw.x,
            y: raw.y,
            angle: raw.angle,
            frame: state.map(|v| FrameState {
                s: v.s,
                lane: v.lane,
                lateral: v.lateral,
                heading: v.heading,
            }),
            speed: raw.speed,
            accel: raw.acceleration,
            sent: None,
        }
    }
}

/// Text that is compressed once it grows large.
enum Sink {
    Plain(Vec<u8>),
    Gzip(GzEncoder<Vec<u8>>),
}

impl Sink {
    fn write(&mut self, text: &str) {
        match self {
            Sink::Plain(buf) => {
                buf.extend_from_slice(text.as_bytes());
                if buf.len() > GZIP_ABOVE_BYTES {
                    let mut gz = GzEncoder::new(Vec::new(), Compression::default());
                    gz.write_all(buf).expect("writing to memory");
                    *self = Sink::Gzip(gz);
                }
            }
            Sink::Gzip(gz) => gz.write_all(text.as_bytes()).expect("writing to memory"),
        }
    }

    /// The bytes, and whether they are gzip-compressed.
    fn finish(self) -> (Vec<u8>, bool) {
        match self {
            Sink::Plain(buf) => (buf, false),
            Sink::Gzip(gz) => (gz.finish().expect("writing to memory"), true),
        }
    }
}

/// The trajectories of one episode, built step by step: the rows of the current step wait
/// until the controller has planned (to carry the maneuver sent), then become text.
pub struct TrajectoryLog {
    format: TrajectoryFormat,
    sink: Sink,
    time: f64,
    step_rows: Vec<TrajectoryRow>,
    line: String,
}

/// A finished trajectory file: its name in the episode directory and its bytes.
#[derive(Debug, Clone)]
pub struct TrajectoryFile {
    /// File name in the episode directory (one of [`FILE_NAMES`]).
    pub name: &'static str,
    /// The file's content (gzip-compressed when the name ends in `.gz`).
    pub bytes: Vec<u8>,
}

/// Every name a trajectory file may have, so that a new episode's set replaces an old one's.
pub const FILE_NAMES: [&str; 4] = [
    "trajectories.csv",
    "trajectories.csv.gz",
    "trajectories.fcd.xml",
    "trajectories.fcd.xml.gz",
];

impl TrajectoryLog {
    /// A log in `format`; `None` for [`TrajectoryFormat::None`].
    pub fn new(format: TrajectoryFormat) -> Option<TrajectoryLog> {
        let mut sink = Sink::Plain(Vec::new());
        match format {
            TrajectoryFormat::None => return None,
            TrajectoryFormat::Csv => sink.write(&(CSV_COLUMNS.join(",") + "\n")),
            TrajectoryFormat::Fcd => sink.write(FCD_HEADER),
        }
        Some(TrajectoryLog {
            format,
            sink,
            time: f64::NAN,
            step_rows: Vec::new(),
            line: String::new(),
        })
    }

    /// Starts the rows of the step whose state is labelled `time` (SUMO's clock).
    pub fn begin_step(&mut self, time: f64) {
        self.flush_step();
        self.time = time;
    }

    /// Adds a vehicle's row to the current step; returns its index for [`Self::set_sent`].
    pub fn push(&mut self, row: TrajectoryRow) -> usize {
        self.step_rows.push(row);
        self.step_rows.len() - 1
    }

    /// Records the maneuver sent to the vehicle of row `index` of the current step.
    pub fn set_sent(&mut self, index: usize, sent: Sent) {
        self.step_rows[index].sent = Some(sent);
    }

    /// The whole file.
    pub fn finish(mut self) -> TrajectoryFile {
        self.flush_step();
        if self.format == TrajectoryFormat::Fcd {
            self.sink.write("</fcd-export>\n");
        }
        let (bytes, gz) = self.sink.finish();
        let name = match (self.format, gz) {
            (TrajectoryFormat::Fcd, false) => FILE_NAMES[2],
            (TrajectoryFormat::Fcd, true) => FILE_NAMES[3],
            (_, false) => FILE_NAMES[0],
            (_, true) => FILE_NAMES[1],
        };
        TrajectoryFile { name, bytes }
    }

    fn flush_step(&mut self) {
        if self.time.is_nan() {
            return;
        }
        self.line.clear();
        match self.format {
            TrajectoryFormat::Fcd => fcd_step(&mut self.line, self.time, &self.step_rows),
            _ => {
                for r in &self.step_rows {
                    csv_row(&mut self.line, self.time, r);
                }
            }
        }
        self.sink.write(&self.line);
        self.step_rows.clear();
        self.time = f64::NAN;
    }
}

/// One CSV line; empty fields for what a row does not have.
fn csv_row(out: &mut String, time: f64, r: &TrajectoryRow) {
    let _ = write!(
        out,
        "{time:.2},{},{},{},{},{},{:.2},{:.2},{:.2},{:.2},",
        r.id,
        r.kind.as_str(),
        r.origin.as_str(),
        r.edge.as_deref().unwrap_or(""),
        r.sumo_lane,
        r.pos,
        r.x,
        r.y,
        r.angle
    );
    match r.frame {
        Some(f) => {
            let _ = write!(
                out,
                "{:.2},{},{:.2},{:.4},",
                f.s, f.lane, f.lateral, f.heading
            );
        }
        None => out.push_str(",,,,"),
    }
    let _ = write!(out, "{:.2},{:.2},", r.speed, r.accel);
    match r.sent {
        Some(m) => {
            let change = match m.lane_change {
                Some(LaneChange::Left) => "left",
                Some(LaneChange::Right) => "right",
                None => "",
            };
            let _ = writeln!(out, "{:.2},{change},{}", m.speed, m.source.as_str());
        }
        None => out.push_str(",,\n"),
    }
}

const FCD_HEADER: &str = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- Trajectories written by bkpbs in SUMO's FCD format. -->\n<fcd-export xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xsi:noNamespaceSchemaLocation=\"http://sumo.dlr.de/xsd/fcd_file.xsd\">\n";

/// One `<timestep>` as SUMO writes it: vehicles with front-bumper x, y, angle, type, speed,
/// lane position and lane id (slope 0: the networks are flat).
fn fcd_step(out: &mut String, time: f64, rows: &[TrajectoryRow]) {
    if rows.is_empty() {
        let _ = writeln!(out, "    <timestep time=\"{time:.2}\"/>");
        return;
    }
    let _ = writeln!(out, "    <timestep time=\"{time:.2}\">");
    for r in rows {
        let _ = writeln!(
            out,
            "        <vehicle id=\"{}\" x=\"{:.2}\" y=\"{:.2}\" angle=\"{:.2}\" type=\"{}\" speed=\"{:.2}\" pos=\"{:.2}\" lane=\"{}_{}\" slope=\"0.00\"/>",
            r.id,
            r.x,
            r.y,
            r.angle,
            r.kind.as_str(),
            r.speed,
            r.pos,
            r.edge.as_deref().unwrap_or(""),
            r.sumo_lane
        );
    }
    out.push_str("    </timestep>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(id: &str) -> TrajectoryRow {
        TrajectoryRow {
            id: id.into(),
            kind: Kind::Cav,
            origin: Origin::Ramp,
            edge: Some(Arc::from("acc")),
            sumo_lane: 0,
            pos: 12.3456,
            x: 100.0,
            y: -4.5,
            angle: 90.0,
            frame: Some(FrameState {
                s: 9.85,
                lane: 0,
                lateral: 0.0,
                heading: 0.0,
            }),
            speed: 20.0,
            accel: -0.5,
            sent: None,
        }
    }

    #[test]
    fn csv_rows_carry_the_maneuver_sent_when_there_is_one() {
        let mut log = TrajectoryLog::new(TrajectoryFormat::Csv).unwrap();
        log.begin_step(0.0);
        let i = log.push(row("c1"));
        log.push(row("c2"));
        log.set_sent(
            i,
            Sent {
                speed: 21.0,
                lane_change: Some(LaneChange::Left),
                source: Source::PbsSolution,
            },
        );
        let f = log.finish();
        assert_eq!(f.name, "trajectories.csv");
        let text = String::from_utf8(f.bytes).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0].split(',').count(), CSV_COLUMNS.len());
        assert_eq!(
            lines[1],
            "0.00,c1,cav,ramp,acc,0,12.35,100.00,-4.50,90.00,9.85,0,0.00,0.0000,20.00,-0.50,21.00,left,pbs-solution"
        );
        assert!(lines[2].ends_with(",20.00,-0.50,,,"));
        assert_eq!(lines.len(), 3);
    }

    #[test]
    fn large_logs_are_compressed_the_same_way_every_time() {
        let make = || {
            let mut log = TrajectoryLog::new(TrajectoryFormat::Csv).unwrap();
            let mut step = 0;
            while log_size(&log) <= GZIP_ABOVE_BYTES {
                log.begin_step(step as f64 * 0.2);
                for k in 0..200 {
                    log.push(row(&format!("v{k}")));
                }
                step += 1;
            }
            log.begin_step(step as f64 * 0.2);
            log.finish()
        };
        let (a, b) = (make(), make());
        assert_eq!(a.name, "trajectories.csv.gz");
        assert_eq!(a.bytes, b.bytes);
        let mut text = String::new();
        std::io::Read::read_to_string(&mut flate2::read::GzDecoder::new(&a.bytes[..]), &mut text)
            .unwrap();
        assert!(text.starts_with("time,id,type"));
        assert!(text.len() > GZIP_ABOVE_BYTES);
    }

    fn log_size(log: &TrajectoryLog) -> usize {
        match &log.sink {
            Sink::Plain(b) => b.len(),
            Sink::Gzip(_) => usize::MAX,
        }
    }

    #[test]
    fn fcd_steps_look_like_sumo_s() {
        let mut log = TrajectoryLog::new(TrajectoryFormat::Fcd).unwrap();
        log.begin_step(0.0);
        log.begin_step(0.2);
        log.push(row("c1"));
        let f = log.finish();
        assert_eq!(f.name, "trajectories.fcd.xml");
        let text = String::from_utf8(f.bytes).unwrap();
        assert!(text.contains("    <timestep time=\"0.00\"/>\n"));
        assert!(text.contains("<vehicle id=\"c1\" x=\"100.00\" y=\"-4.50\" angle=\"90.00\" type=\"cav\" speed=\"20.00\" pos=\"12.35\" lane=\"acc_0\" slope=\"0.00\"/>"));
        assert!(text.ends_with("</fcd-export>\n"));
    }
}
