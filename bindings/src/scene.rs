//! Vehicles as a user's own TraCI or libsumo loop reads them (dicts or objects with the same
//! attribute names), checked and turned into the core's readings: SUMO's units and conventions,
//! mapped to the road frame by `bkpbs::sumo::frame` exactly as the episode runner maps them.

use std::cell::Cell;
use std::collections::HashMap;
use std::sync::Arc;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use bkpbs::config::Scenario;
use bkpbs::model::road::Road;
use bkpbs::model::scene::{Kind, Origin};
use bkpbs::sumo::frame::{self, Identity, SumoScene};
use bkpbs::sumo::RawVehicleState;

use crate::errors::bad_input;

/// Keys every vehicle must have.
pub const REQUIRED: [&str; 8] = [
    "id",
    "type",
    "angle",
    "speed",
    "acceleration",
    "lane_index",
    "lane_position",
    "road_id",
];
/// Keys a vehicle may have: `x`/`y` are accepted as read (the frame comes from the road, lane and
/// lane position), `lateral_offset` is `getLateralLanePosition` (default 0), `origin` is
/// `"main"`/`"ramp"`, `desired_speed` in m/s.
pub const OPTIONAL: [&str; 5] = ["x", "y", "lateral_offset", "origin", "desired_speed"];

/// One vehicle as read from SUMO, checked.
#[derive(Debug, Clone)]
pub struct Reading {
    pub id: String,
    pub kind: Kind,
    /// The SUMO reading; `edge_code` is -1 off the merge section.
    pub raw: RawVehicleState,
    pub origin: Option<Origin>,
    pub desired_speed: Option<f64>,
}

/// The known keys as Python strings, made once per scene rather than once per lookup.
pub struct Keys<'py>(Vec<Bound<'py, PyString>>);

impl<'py> Keys<'py> {
    pub fn new(py: Python<'py>) -> Keys<'py> {
        Keys(
            REQUIRED
                .iter()
                .chain(&OPTIONAL)
                .map(|k| PyString::intern(py, k))
                .collect(),
        )
    }

    fn get(&self, key: &str) -> &Bound<'py, PyString> {
        let i = REQUIRED
            .iter()
            .chain(&OPTIONAL)
            .position(|k| *k == key)
            .expect("a known key");
        &self.0[i]
    }
}

/// Reads vehicle number `i` of the caller's list.
fn read_vehicle(i: usize, obj: &Bound<'_, PyAny>, keys: &Keys<'_>) -> PyResult<Reading> {
    let dict = obj.cast::<PyDict>().ok();
    if dict.is_none() && !obj.hasattr("id")? {
        return Err(bad_input(format!(
            "vehicle {i}: expected a dict (or an object with attributes) {}, got {}",
            REQUIRED.join(", "),
            obj.get_type().name()?
        )));
    }
    // Known keys found in the dict; more keys than that means an unknown one.
    let found = Cell::new(0usize);
    let get = |key: &str| -> PyResult<Option<Bound<'_, PyAny>>> {
        let v = match dict {
            Some(d) => d.get_item(keys.get(key))?,
            None => obj.getattr_opt(keys.get(key))?,
        };
        found.set(found.get() + usize::from(v.is_some()));
        Ok(v.filter(|v| !v.is_none()))
    };
    let id: String = match get("id")? {
        Some(v) => v
            .cast::<PyString>()
            .map_err(|_| bad_input(format!("vehicle {i}: 'id' must be a string")))?
            .to_cow()?
            .to_string(),
        None => return Err(bad_input(format!("vehicle {i}: missing key 'id'"))),
    };
    let who = format!("vehicle {i} ('{id}')");
    let required = |key: &str| -> PyResult<Bound<'_, PyAny>> {
        get(key)?.ok_or_else(|| {
            bad_input(format!(
                "{who}: missing key '{key}' (a vehicle needs {})",
                REQUIRED.join(", ")
            ))
        })
    };
    let string = |key: &str| -> PyResult<String> {
        let v = required(key)?;
        let s = v
            .cast::<PyString>()
            .map_err(|_| bad_input(format!("{who}: '{key}' must be a string")))?;
        Ok(s.to_cow()?.to_string())
    };
    let number = |key: &str, v: Bound<'_, PyAny>| -> PyResult<f64> {
        match v.extract::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(bad_input(format!(
                "{who}: '{key}' must be a finite number, got {}",
                v.repr()?
            ))),
        }
    };
    let type_id = string("type")?;
    let road_id = string("road_id")?;
    let lane_index_obj = required("lane_index")?;
    let lane_index: i32 = lane_index_obj.extract().map_err(|_| {
        bad_input(format!(
            "{who}: 'lane_index' must be an integer, got {}",
            lane_index_obj
                .repr()
                .map(|r| r.to_string())
                .unwrap_or_default()
        ))
    })?;
    let optional_number =
        |key: &str| -> PyResult<Option<f64>> { get(key)?.map(|v| number(key, v)).transpose() };
    let origin = match get("origin")? {
        None => None,
        Some(v) => match v.extract::<String>().ok().as_deref() {
            Some("main") => Some(Origin::Main),
            Some("ramp") => Some(Origin::Ramp),
            _ => {
                return Err(bad_input(format!(
                    "{who}: 'origin' must be \"main\" or \"ramp\", got {}",
                    v.repr()?
                )))
            }
        },
    };
    let desired_speed = optional_number("desired_speed")?;
    if desired_speed.is_some_and(|d| d < 0.0) {
        return Err(bad_input(format!(
            "{who}: 'desired_speed' must not be negative"
        )));
    }
    let raw = RawVehicleState {
        x: optional_number("x")?.unwrap_or(0.0),
        y: optional_number("y")?.unwrap_or(0.0),
        speed: number("speed", required("speed")?)?,
        acceleration: number("acceleration", required("acceleration")?)?,
        angle: number("angle", required("angle")?)?,
        lane_position: number("lane_position", required("lane_position")?)?,
        lateral_offset: optional_number("lateral_offset")?.unwrap_or(0.0),
        lane_index,
        edge_code: frame::edge_code(&road_id).unwrap_or(-1),
    };
    if let Some(d) = dict.filter(|d| d.len() > found.get()) {
        for k in d.keys() {
            let k: String = k.extract().unwrap_or_else(|_| "<not a string>".into());
            if !REQUIRED.contains(&k.as_str()) && !OPTIONAL.contains(&k.as_str()) {
                return Err(bad_input(format!(
                    "{who}: unknown key '{k}' (known: {}, {})",
                    REQUIRED.join(", "),
                    OPTIONAL.join(", ")
                )));
            }
        }
    }
    Ok(Reading {
        kind: Kind::from_type_id(&type_id).unwrap_or(Kind::Hdv),
        id,
        raw,
        origin,
        desired_speed,
    })
}

/// The scene of `vehicles` (a list of dicts or objects) at `time`. Vehicles off the merge
/// section are left out. A vehicle's origin is its `origin` key, else its id's prefix
/// (`main.`/`ramp.`), else what `origins` remembers from an earlier call, else the road it is
/// on; `origins` is replaced by this call's.
pub fn scene_of(
    vehicles: &Bound<'_, PyAny>,
    road: &Road,
    scenario: &Scenario,
    origins: &mut HashMap<String, Origin>,
    time: f64,
) -> PyResult<SumoScene> {
    let mut framed = SumoScene::new(road);
    framed.clear(time);
    let mut seen = HashMap::new();
    let list = vehicles
        .try_iter()
        .map_err(|_| bad_input("vehicles must be a list of dicts (or objects)"))?;
    let keys = Keys::new(vehicles.py());
    for (i, item) in list.enumerate() {
        let r = read_vehicle(i, &item?, &keys)?;
        let origin = r
            .origin
            .or_else(|| frame::origin_from_id(&r.id))
            .or_else(|| origins.get(&r.id).copied())
            .unwrap_or_else(|| frame::origin_from_edge(r.raw.edge_code));
        let who = Identity {
            id: Arc::from(r.id.as_str()),
            kind: r.kind,
            origin,
            desired_speed: r.desired_speed.unwrap_or(match r.kind {
                Kind::Cav => scenario.v_max,
                Kind::Hdv => r.raw.speed,
            }),
        };
        seen.insert(r.id, origin);
        if let Some(v) = frame::vehicle_state(road, scenario, who, &r.raw) {
            framed.push(v, r.raw.edge_code);
        }
    }
    *origins = seen;
    Ok(framed)
}
