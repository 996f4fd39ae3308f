//! The road frame and SUMO, both directions: the [`Road`] of the scenario's network file, a
//! road-frame [`VehicleState`] from what SUMO reports about one vehicle (edge, lane, lane
//! position of the front bumper, lateral offset, speed, acceleration and angle), and back from a
//! frame lane to the SUMO lane index a lane-change command needs.
//!
//! The episode runner reads these values for all vehicles in one libsumo call; a user's own
//! TraCI or libsumo loop reads them one getter at a time (the Python bindings' `Controller`).
//! Both go through this module, so a controller sees the same scene either way.

use std::path::Path;
use std::sync::Arc;

use crate::config::Scenario;
use crate::model::road::Road;
use crate::model::scene::{Kind, Origin, Scene, VehicleState};
use crate::sumo::layout::Discovery;
use crate::sumo::network::{Net, NetworkFileError};
use crate::sumo::RawVehicleState;

/// Why a network cannot serve as a merge road.
#[derive(Debug, thiserror::Error)]
pub enum NetworkError {
    /// The network file could not be read.
    #[error(transparent)]
    File(#[from] NetworkFileError),
    /// The network holds no one region to plan on, or its lanes cannot be placed in a frame.
    #[error("network {path}: {what}")]
    Shape {
        /// The network file.
        path: std::path::PathBuf,
        /// What could not be placed.
        what: String,
    },
}

/// The merge regions of a network, each with its road frame or why it cannot be planned on.
pub struct Regions {
    /// What was found: the regions' layouts, the junctions that are no merge, the edges left
    /// out.
    pub found: Discovery,
    /// The road frame of each region of `found`, in its order.
    pub roads: Vec<Result<Road, String>>,
}

impl Regions {
    /// The regions of `net`, each placed in its frame.
    pub fn of(net: &Net) -> Regions {
        let found = Discovery::of(net);
        let roads = found
            .regions
            .iter()
            .map(|layout| crate::sumo::road_frame::road(net, layout))
            .collect();
        Regions { found, roads }
    }

    /// The indices of the regions `selection` picks (`[scenario] regions`: merge edges to
    /// keep, `!EDGE` to leave out; empty: all).
    ///
    /// # Errors
    /// An entry that names no merge edge of the network.
    pub fn select(&self, selection: &[String]) -> Result<Vec<usize>, String> {
        let names = |k: usize| self.found.regions[k].merge_edges().collect::<Vec<_>>();
        let all = 0..self.found.regions.len();
        let (mut wanted, mut excluded) = (Vec::new(), Vec::new());
        for entry in selection {
            match entry.strip_prefix('!') {
                Some(edge) => excluded.push(edge),
                None => wanted.push(entry.as_str()),
            }
        }
        let unknown = |e: &&str| !all.clone().any(|k| names(k).contains(e));
        if let Some(edge) = (selection.iter())
            .map(|e| e.strip_prefix('!').unwrap_or(e))
            .find(unknown)
        {
            return Err(format!(
                "regions: '{edge}' is no edge an on-ramp joins (the merges: {})",
                self.merge_list()
            ));
        }
        let kept = |k: &usize| {
            let n = names(*k);
            let named = |e: &&str| n.contains(e);
            !excluded.iter().any(named) && (wanted.is_empty() || wanted.iter().any(named))
        };
        Ok(all.filter(kept).collect())
    }

    /// The merge edges of every region, `A, B; C` (a region's merges together).
    pub fn merge_list(&self) -> String {
        let list: Vec<String> = (0..self.found.regions.len())
            .map(|k| self.region_name(k))
            .collect();
        if list.is_empty() {
            "none".into()
        } else {
            list.join("; ")
        }
    }

    /// The road frame of the one region `selection` leaves: what an episode plans on.
    ///
    /// # Errors
    /// No region, more than one, or one that cannot be placed in a frame, each in one phrase.
    pub fn planned(self, selection: &[String]) -> Result<Road, String> {
        let picked = self.picked(selection)?;
        if let [_, _, ..] = picked[..] {
            let names: Vec<String> = picked.iter().map(|&k| self.region_name(k)).collect();
            return Err(format!(
                "{} merge regions (merges at {}): an episode plans one; choose it with \
                 --regions EDGE ([scenario] regions)",
                picked.len(),
                names.join("; ")
            ));
        }
        let mut roads = self.roads;
        roads.swap_remove(picked[0])
    }

    /// The road frames of every region `selection` leaves: what an episode on a user's own
    /// scenario plans.
    ///
    /// # Errors
    /// No region, or one that cannot be placed in a frame (naming it).
    pub fn all_planned(self, selection: &[String]) -> Result<Vec<Road>, String> {
        if self.nothing_to_plan_but_sumos(selection) {
            return Ok(Vec::new());
        }
        let picked = self.picked(selection)?;
        let names: Vec<String> = picked.iter().map(|&k| self.region_name(k)).collect();
        let mut roads: Vec<Option<Result<Road, String>>> =
            self.roads.into_iter().map(Some).collect();
        picked
            .iter()
            .zip(names)
            .map(|(&k, name)| {
                let road = roads[k].take().expect("each region picked once");
                road.map_err(|why| format!("region at {name}: {why}"))
            })
            .collect()
    }

    /// Whether every region found is left to SUMO's drivers (and `selection` picks none):
    /// an episode on a user's scenario then runs with SUMO driving everyone.
    fn nothing_to_plan_but_sumos(&self, selection: &[String]) -> bool {
        selection.is_empty() && self.found.regions.is_empty() && !self.found.left_to_sumo.is_empty()
    }

    /// What an episode on a user's scenario says at its start: one line per region left to
    /// SUMO's drivers.
    pub fn left_to_sumo_lines(&self) -> Vec<String> {
        self.found.left_to_sumo.iter().map(|l| l.line()).collect()
    }

    /// The regions `selection` picks, at least one.
    fn picked(&self, selection: &[String]) -> Result<Vec<usize>, String> {
        let picked = self.select(selection)?;
        if !picked.is_empty() {
            Ok(picked)
        } else if self.found.regions.is_empty() {
            Err(self.no_merge())
        } else {
            Err(format!(
                "regions leaves no merge region (the merges: {})",
                self.merge_list()
            ))
        }
    }

    /// Region `k` by the edges its on-ramps join, `A, B`.
    fn region_name(&self, k: usize) -> String {
        self.found.regions[k]
            .merge_edges()
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Why a network without regions has none.
    fn no_merge(&self) -> String {
        let why: Vec<String> = self
            .found
            .not_merges
            .iter()
            .map(|n| format!("ramp '{}' {}", n.ramp, n.why))
            .collect();
        let unplanned = self.found.changes.iter().map(|(c, _)| c);
        let why = why
            .into_iter()
            .chain(self.found.left_to_sumo.iter().map(|l| l.line()))
            .chain(unplanned.map(|c| format!("{} {}", c.kind.as_str(), c.what)))
            .collect::<Vec<_>>();
        if why.is_empty() {
            "no on-ramp joins a carriageway on an acceleration lane: no merge to plan".into()
        } else {
            format!("no merge to plan: {}", why.join("; "))
        }
    }
}

/// The road frame of the network file at `path`: its merge regions found, and the one
/// `selection` picks placed in its frame.
///
/// # Errors
/// An unreadable file, or a network without the one region to plan.
pub fn road_from_net_file(path: &Path, selection: &[String]) -> Result<Road, NetworkError> {
    let net = Net::read(path)?;
    road_from_net(&net, path, selection)
}

/// The road frame of `net` (read from `path`, named in errors) in the region `selection` picks.
///
/// # Errors
/// As [`road_from_net_file`].
pub fn road_from_net(net: &Net, path: &Path, selection: &[String]) -> Result<Road, NetworkError> {
    Regions::of(net)
        .planned(selection)
        .map_err(|what| NetworkError::Shape {
            path: path.to_path_buf(),
            what,
        })
}

/// The road frames of every region `selection` picks of a user's scenario (`scenario.sumocfg`):
/// an episode on a scenario of its own plans them all.
///
/// # Errors
/// An unreadable configuration or network, no region, or a region that cannot be placed in
/// a frame.
pub fn scenario_roads(scenario: &Scenario) -> Result<Vec<Road>, NetworkError> {
    let Some(path) = &scenario.sumocfg else {
        return Ok(vec![scenario_road(scenario)?]);
    };
    let net_path = sumocfg_net(path)?;
    let regions = Regions::of(&Net::read(&net_path)?);
    regions
        .all_planned(&scenario.regions)
        .map_err(|what| NetworkError::Shape {
            path: net_path,
            what,
        })
}

/// One line per merge region of a user's scenario (`scenario.sumocfg`) that is left to SUMO's
/// drivers, saying why: what an episode prints at its start. None without a configuration.
///
/// # Errors
/// An unreadable configuration or network.
pub fn scenario_left_to_sumo(scenario: &Scenario) -> Result<Vec<String>, NetworkError> {
    let Some(path) = &scenario.sumocfg else {
        return Ok(Vec::new());
    };
    let net = Net::read(&sumocfg_net(path)?)?;
    Ok(Regions::of(&net).left_to_sumo_lines())
}

/// The network a SUMO configuration names.
fn sumocfg_net(path: &Path) -> Result<std::path::PathBuf, NetworkError> {
    crate::sumo::sumocfg::SumoConfig::read(path)
        .map(|c| c.net)
        .map_err(|e| NetworkError::Shape {
            path: path.to_path_buf(),
            what: e.to_string(),
        })
}

/// The road frame of the scenario's network: the configured file (in its configured region),
/// or the embedded one.
///
/// # Errors
/// As [`road_from_net_file`].
pub fn scenario_road(scenario: &Scenario) -> Result<Road, NetworkError> {
    if let Some(cfg) = &scenario.sumocfg {
        return road_from_net_file(&sumocfg_net(cfg)?, &scenario.regions);
    }
    match &scenario.net_file {
        Some(path) => road_from_net_file(path, &scenario.regions),
        None => Ok(embedded_road()),
    }
}

/// The road frame of the network embedded in the binary (the paper's), read once per process.
pub fn embedded_road() -> Road {
    static ROAD: std::sync::OnceLock<Road> = std::sync::OnceLock::new();
    ROAD.get_or_init(|| {
        let path = Path::new("merge.net.xml");
        let net =
            Net::parse(path, crate::model::road::EMBEDDED_NET).expect("the embedded net parses");
        road_from_net(&net, path, &[]).expect("the embedded net is a merge")
    })
    .clone()
}

/// The frame lane of `lane_index` on the edge of code `edge_code`, if the frame has it.
fn lane_frame(
    road: &Road,
    edge_code: i32,
    lane_index: i32,
) -> Option<&crate::model::road::LaneFrame> {
    let e = road.edges.get(usize::try_from(edge_code).ok()?)?;
    e.lanes.get(usize::try_from(lane_index).ok()?)?.as_ref()
}

/// The speed limit (m/s) of SUMO lane `lane_index` on the edge of code `edge_code`; infinite
/// off the frame or on a lane built by hand.
pub fn speed_limit(road: &Road, edge_code: i32, lane_index: i32) -> f64 {
    lane_frame(road, edge_code, lane_index).map_or(f64::INFINITY, |f| f.speed_limit)
}

/// Frame `s` and lane of a SUMO (edge code, lane index, lane position); `None` off the section.
pub fn to_frame(
    road: &Road,
    edge_code: i32,
    lane_index: i32,
    lane_position: f64,
) -> Option<(f64, i32)> {
    let f = lane_frame(road, edge_code, lane_index)?;
    Some((f.s_at(lane_position), f.lane))
}

/// SUMO lane index on edge `edge_code` of frame lane `lane`, if that edge has it.
pub fn sumo_lane_index(road: &Road, edge_code: i32, lane: i32) -> Option<i32> {
    let e = road.edges.get(usize::try_from(edge_code).ok()?)?;
    let idx = e
        .lanes
        .iter()
        .position(|l| l.as_ref().is_some_and(|l| l.lane == lane))?;
    Some(idx as i32)
}

/// Whether a reading on `edge_code` lies on an on-ramp, before its merge zone.
pub fn is_on_ramp(road: &Road, edge_code: i32) -> bool {
    usize::try_from(edge_code)
        .ok()
        .and_then(|c| road.edges.get(c))
        .is_some_and(|e| e.on_ramp)
}

/// The speed SUMO is commanded for a planned speed: within [0, v_max]. The one place where
/// every controller's speeds are bounded, for the runner and the bindings alike.
pub fn commanded_speed(planned: f64, scenario: &Scenario) -> f64 {
    planned.clamp(0.0, scenario.v_max)
}

/// A scene in the road frame and the SUMO edge each of its vehicles was read on, so a frame
/// lane can be turned back into the SUMO lane index a command needs.
#[derive(Debug, Clone)]
pub struct SumoScene {
    /// The vehicles in the road frame.
    pub scene: Scene,
    /// Per vehicle of `scene`, the code of the SUMO edge it was read on.
    pub edge_codes: Vec<i32>,
}

impl SumoScene {
    /// An empty scene on `road` at time 0.
    pub fn new(road: &Road) -> SumoScene {
        SumoScene {
            scene: Scene {
                time: 0.0,
                road: road.clone(),
                vehicles: Vec::new(),
            },
            edge_codes: Vec::new(),
        }
    }

    /// Empties the scene and sets its time.
    pub fn clear(&mut self, time: f64) {
        self.scene.time = time;
        self.scene.vehicles.clear();
        self.edge_codes.clear();
    }

    /// Adds a vehicle read on SUMO edge `edge_code`.
    pub fn push(&mut self, vehicle: VehicleState, edge_code: i32) {
        self.scene.vehicles.push(vehicle);
        self.edge_codes.push(edge_code);
    }

    /// The SUMO lane index of frame lane `lane` on the edge scene vehicle `vehicle` is on.
    pub fn sumo_lane_index(&self, vehicle: usize, lane: i32) -> Option<i32> {
        sumo_lane_index(&self.scene.road, self.edge_codes[vehicle], lane)
    }
}

/// What SUMO's readings do not say about a vehicle: who it is and what it wants.
#[derive(Debug, Clone, PartialEq)]
pub struct Identity {
    /// SUMO's vehicle id.
    pub id: Arc<str>,
    /// Who drives it.
    pub kind: Kind,
    /// Where it entered the section.
    pub origin: Origin,
    /// The speed the vehicle wants to drive (m/s).
    pub desired_speed: f64,
}

/// The code of a SUMO edge of the merge section (its index in `road.edges`), as
/// [`RawVehicleState::edge_code`] carries it; `None` for any other edge (e.g. an off-ramp).
pub fn edge_code(road: &Road, road_id: &str) -> Option<i32> {
    road.edges
        .iter()
        .position(|e| &*e.name == road_id)
        .map(|i| i as i32)
}

/// The names of the frame's edges in code order, for `Simulation::set_edge_codes`.
pub fn edge_names(road: &Road) -> Vec<&str> {
    road.edges.iter().map(|e| &*e.name).collect()
}

/// Where a vehicle entered, from the demand's vehicle ids (`main.N`, `ramp.N`, `ramp2.N` on a
/// network of several ramps); `None` for ids of another scheme.
pub fn origin_from_id(id: &str) -> Option<Origin> {
    if id.starts_with("main.") {
        return Some(Origin::Main);
    }
    let rest = id.strip_prefix("ramp")?;
    rest.trim_start_matches(|c: char| c.is_ascii_digit())
        .starts_with('.')
        .then_some(Origin::Ramp)
}

/// Where a vehicle entered, from the edge it was first seen on: a ramp or else the main road.
pub fn origin_from_edge(road: &Road, edge_code: i32) -> Origin {
    if is_on_ramp(road, edge_code) {
        Origin::Ramp
    } else {
        Origin::Main
    }
}

/// Front-bumper `s` and road-frame lane of a reading; `None` off the merge section.
pub fn frame_position(road: &Road, raw: &RawVehicleState) -> Option<(f64, i32)> {
    to_frame(road, raw.edge_code, raw.lane_index, raw.lane_position)
}

/// The vehicle at the frame position [`frame_position`] gave: the centre lies half a length
/// behind the front bumper, and its heading relative to the road (radians, positive to the left)
/// is [`heading`]'s.
pub fn state_at(
    road: &Road,
    scenario: &Scenario,
    who: Identity,
    raw: &RawVehicleState,
    front: f64,
    lane: i32,
) -> VehicleState {
    let size = (scenario.vehicle_length, scenario.vehicle_width);
    state_sized(road, who, raw, (front, lane), size)
}

/// Like [`state_at`] for a vehicle of its own `(length, width)` (m), as SUMO has its type.
pub fn state_sized(
    road: &Road,
    who: Identity,
    raw: &RawVehicleState,
    (front, lane): (f64, i32),
    (length, width): (f64, f64),
) -> VehicleState {
    VehicleState {
        id: who.id,
        kind: who.kind,
        origin: who.origin,
        s: front - 0.5 * length,
        lane,
        lateral: raw.lateral_offset,
        speed: raw.speed,
        accel: raw.acceleration,
        heading: heading(road, raw, front),
        desired_speed: who.desired_speed,
        length,
        width,
        max_speed: f64::INFINITY,
        limits: crate::model::scene::Limits::NONE,
        on_ramp: is_on_ramp(road, raw.edge_code),
    }
}

/// A vehicle's heading relative to the road at its front bumper `front` (radians, positive to
/// the left): the direction it moves in, from its speed and lateral speed, on a lane of the
/// frame (all run parallel to the road); 0 while it stands, and 0 on an on-ramp edge. Off the
/// ramps, for a reading without a lateral speed it is SUMO's angle (degrees, 0 = north, clockwise) against
/// the road's.
///
/// The frame straightens an on-ramp (its `s` runs along the ramp), and a ramp of one lane has
/// no lane change, so a vehicle on it moves straight along the frame. SUMO's angle there, up to
/// 30° off the carriageway on SUMO's `ramp` game, turned the planned body across the
/// straightened 3.2 m ramp, so every plan left the road from its start and the first ramp CAV
/// braked to a stop for good, closing the ramp; it also cut the commanded speed to `v cos θ`.
///
/// SUMO has no body angle of its own: the angle it reports during a lane change is a drawing,
/// and versions draw it differently. 1.15 turns it up to 30° off the lane whatever the speed
/// and back as the change ends; 1.28 draws the direction of motion, and after a lane change at
/// standstill keeps the last one while the vehicle stands. Read as a heading, that kept angle
/// (up to 0.8 rad) made a CAV's body cross the next lane, so its planner braked it for good at
/// the end of the acceleration lane. The direction of motion is what SUMO executes on any
/// version.
pub fn heading(road: &Road, raw: &RawVehicleState, front: f64) -> f64 {
    if is_on_ramp(road, raw.edge_code) {
        return 0.0;
    }
    if raw.lateral_speed.is_nan() {
        return (90.0 - raw.angle).to_radians() - road.heading_at(front);
    }
    if raw.speed == 0.0 {
        return 0.0;
    }
    raw.lateral_speed.atan2(raw.speed)
}

/// The vehicle in the road frame; `None` when it is off the merge section.
pub fn vehicle_state(
    road: &Road,
    scenario: &Scenario,
    who: Identity,
    raw: &RawVehicleState,
) -> Option<VehicleState> {
    let (front, lane) = frame_position(road, raw)?;
    Some(state_at(road, scenario, who, raw, front, lane))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edge_names_map_to_codes() {
        let r = Road::paper_default();
        assert_eq!(edge_code(&r, "main_in"), Some(0));
        assert_eq!(edge_code(&r, "main_out"), Some(2));
        assert_eq!(edge_code(&r, "ramp"), Some(3));
        assert_eq!(edge_code(&r, ":n1_0"), None);
        assert_eq!(embedded_road(), r);
    }

    #[test]
    fn frame_mapping_round_trips() {
        let r = Road::paper_default();
        // main_in lane 1 (left) at 10 m -> frame lane 2, s = 10.
        assert_eq!(to_frame(&r, 0, 1, 10.0), Some((10.0, 2)));
        // acc lane 0 (acceleration lane) -> frame lane 0, s = 150 + pos.
        assert_eq!(to_frame(&r, 1, 0, 20.0), Some((170.0, 0)));
        assert_eq!(to_frame(&r, 2, 0, 5.0), Some((335.0, 1)));
        assert_eq!(to_frame(&r, 3, 0, 5.0), Some((150.0 - 166.79 + 5.0, 0)));
        assert_eq!(to_frame(&r, -1, 0, 5.0), None);
        assert_eq!(sumo_lane_index(&r, 1, 1), Some(1));
        assert_eq!(sumo_lane_index(&r, 0, 1), Some(0));
        assert_eq!(sumo_lane_index(&r, 0, 0), None);
        assert_eq!(sumo_lane_index(&r, 2, 3), None);
    }

    #[test]
    fn origin_from_demand_ids_only() {
        assert_eq!(origin_from_id("ramp.12"), Some(Origin::Ramp));
        assert_eq!(origin_from_id("main.0"), Some(Origin::Main));
        assert_eq!(origin_from_id("rampage"), None);
        assert_eq!(origin_from_id("ramp3.7"), Some(Origin::Ramp));
        assert_eq!(origin_from_id("main2.7"), None);
        assert_eq!(origin_from_id("veh0"), None);
    }

    #[test]
    fn reading_on_the_acceleration_lane() {
        let road = Road::paper_default();
        let sc = Scenario::default();
        let raw = RawVehicleState {
            speed: 20.0,
            angle: 80.0,
            lateral_speed: 20.0 * 10f64.to_radians().tan(),
            lane_position: 30.0,
            lateral_offset: 0.5,
            lane_index: 0,
            edge_code: edge_code(&road, "acc").unwrap(),
            ..Default::default()
        };
        let who = Identity {
            id: Arc::from("ramp.3"),
            kind: Kind::Cav,
            origin: Origin::Ramp,
            desired_speed: 35.0,
        };
        let v = vehicle_state(&road, &sc, who, &raw).unwrap();
        assert_eq!((v.s, v.lane, v.on_ramp), (177.5, 0, false));
        assert!((v.heading - 10f64.to_radians()).abs() < 1e-12);
        assert_eq!(v.front(), 180.0);
        let off = RawVehicleState {
            edge_code: -1,
            ..raw
        };
        let who = Identity {
            id: Arc::from("x"),
            kind: Kind::Hdv,
            origin: Origin::Main,
            desired_speed: 30.0,
        };
        assert!(vehicle_state(&road, &sc, who, &off).is_none());
    }

    #[test]
    fn the_heading_is_the_direction_of_motion_not_sumos_drawn_angle() {
        let road = Road::paper_default();
        // SUMO 1.28 after a lane change at standstill: angle 42.74°, speed 0.
        let stood = RawVehicleState {
            speed: 0.0,
            angle: 42.74,
            lateral_speed: 0.0,
            lane_position: 179.0,
            lane_index: 1,
            edge_code: edge_code(&road, "acc").unwrap(),
            ..Default::default()
        };
        assert_eq!(heading(&road, &stood, 329.0), 0.0);
        // SUMO 1.15 in a lane change at 26.9 m/s: angle 66° (24° off), moving 4.5 m/s sideways.
        let changing = RawVehicleState {
            speed: 26.9,
            angle: 66.0,
            lateral_speed: 4.5,
            ..stood
        };
        assert!((heading(&road, &changing, 329.0) - 4.5f64.atan2(26.9)).abs() < 1e-15);
        // On the ramp's slanted part, 27° off the carriageway: the frame runs along the ramp.
        let on_ramp = RawVehicleState {
            edge_code: edge_code(&road, "ramp").unwrap(),
            angle: 63.0,
            lateral_speed: f64::NAN,
            ..changing
        };
        assert_eq!(heading(&road, &on_ramp, 100.0), 0.0);
        let unknown = RawVehicleState {
            lateral_speed: f64::NAN,
            ..changing
        };
        assert!((heading(&road, &unknown, 329.0) - 24f64.to_radians()).abs() < 1e-12);
    }
}
