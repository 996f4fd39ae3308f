//! Vehicles as a user's own TraCI or libsumo loop reads them (dicts or objects with the same
//! attribute names), checked and turned into the core's readings: SUMO's units and conventions,
//! mapped to the road frame by `bkpbs::sumo::frame` exactly as the episode runner maps them.

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
/// lane position), `lateral_offset` is `getLateralLanePosition` (default 0), `lateral_speed` is
/// `getLateralSpeed` (the heading is the direction of motion when it is given, SUMO's drawn
/// `angle` otherwise: see `bkpbs::sumo::frame::heading`), `origin` is `"main"`/`"ramp"`,
/// `desired_speed` in m/s.
pub const OPTIONAL: [&str; 6] = [
    "x",
    "y",
    "lateral_offset",
    "lateral_speed",
    "origin",
    "desired_speed",
];

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
fn read_vehicle(
    i: usize,
    obj: &Bound<'_, PyAny>,
    keys: &Keys<'_>,
    road: &Road,
) -> PyResult<Reading> {
    let mut v = VehicleReader::open(i, obj, keys)?;
    let id = v.id()?;
    let type_id = v.string("type")?;
    let road_id = v.string("road_id")?;
    let lane_index = v.lane_index()?;
    let origin = v.origin()?;
    let desired_speed = v.desired_speed()?;
    let raw = RawVehicleState {
        x: v.optional_number("x")?.unwrap_or(0.0),
        y: v.optional_number("y")?.unwrap_or(0.0),
        speed: v.required_number("speed")?,
        acceleration: v.required_number("acceleration")?,
        angle: v.required_number("angle")?,
        lane_position: v.required_number("lane_position")?,
        lateral_offset: v.optional_number("lateral_offset")?.unwrap_or(0.0),
        lateral_speed: v.optional_number("lateral_speed")?.unwrap_or(f64::NAN),
        lane_index,
        edge_code: frame::edge_code(road, &road_id).unwrap_or(-1),
    };
    v.reject_unknown_keys()?;
    Ok(Reading {
        kind: Kind::from_type_id(&type_id).unwrap_or(Kind::Hdv),
        id,
        raw,
        origin,
        desired_speed,
    })
}

/// One vehicle of the caller's list, a dict or an object with attributes, read key by key so
/// that each error names the vehicle and the key at fault.
struct VehicleReader<'a, 'py> {
    obj: &'a Bound<'py, PyAny>,
    dict: Option<&'a Bound<'py, PyDict>>,
    keys: &'a Keys<'py>,
    /// Known keys found in the dict; more keys than that means an unknown one.
    found: usize,
    /// How errors name the vehicle: "vehicle i", then "vehicle i ('id')" once the id is read.
    who: String,
}

impl<'a, 'py> VehicleReader<'a, 'py> {
    /// Refuses anything that is neither a dict nor has an `id` attribute.
    fn open(i: usize, obj: &'a Bound<'py, PyAny>, keys: &'a Keys<'py>) -> PyResult<Self> {
        let dict = obj.cast::<PyDict>().ok();
        if dict.is_none() && !obj.hasattr("id")? {
            return Err(bad_input(format!(
                "vehicle {i}: expected a dict (or an object with attributes) {}, got {}",
                REQUIRED.join(", "),
                obj.get_type().name()?
            )));
        }
        Ok(VehicleReader {
            obj,
            dict,
            keys,
            found: 0,
            who: format!("vehicle {i}"),
        })
    }

    /// The value of `key`; `None` when it is missing or Python's `None`.
    fn get(&mut self, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let v = match self.dict {
            Some(d) => d.get_item(self.keys.get(key))?,
            None => self.obj.getattr_opt(self.keys.get(key))?,
        };
        self.found += usize::from(v.is_some());
        Ok(v.filter(|v| !v.is_none()))
    }

    /// The id, which from then on names the vehicle in errors.
    fn id(&mut self) -> PyResult<String> {
        let value = self.get("id")?;
        let who = &self.who;
        let id = match value {
            Some(v) => v
                .cast::<PyString>()
                .map_err(|_| bad_input(format!("{who}: 'id' must be a string")))?
                .to_cow()?
                .to_string(),
            None => return Err(bad_input(format!("{who}: missing key 'id'"))),
        };
        self.who = format!("{who} ('{id}')");
        Ok(id)
    }

    fn required(&mut self, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let value = self.get(key)?;
        let who = &self.who;
        value.ok_or_else(|| {
            bad_input(format!(
                "{who}: missing key '{key}' (a vehicle needs {})",
                REQUIRED.join(", ")
            ))
        })
    }

    fn string(&mut self, key: &str) -> PyResult<String> {
        let v = self.required(key)?;
        let who = &self.who;
        let s = v
            .cast::<PyString>()
            .map_err(|_| bad_input(format!("{who}: '{key}' must be a string")))?;
        Ok(s.to_cow()?.to_string())
    }

    fn number(&self, key: &str, v: Bound<'py, PyAny>) -> PyResult<f64> {
        let who = &self.who;
        match v.extract::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(bad_input(format!(
                "{who}: '{key}' must be a finite number, got {}",
                v.repr()?
            ))),
        }
    }

    fn required_number(&mut self, key: &str) -> PyResult<f64> {
        let v = self.required(key)?;
        self.number(key, v)
    }

    fn optional_number(&mut self, key: &str) -> PyResult<Option<f64>> {
        self.get(key)?.map(|v| self.number(key, v)).transpose()
    }

    fn lane_index(&mut self) -> PyResult<i32> {
        let v = self.required("lane_index")?;
        let who = &self.who;
        v.extract().map_err(|_| {
            bad_input(format!(
                "{who}: 'lane_index' must be an integer, got {}",
                v.repr().map(|r| r.to_string()).unwrap_or_default()
            ))
        })
    }

    fn origin(&mut self) -> PyResult<Option<Origin>> {
        let Some(v) = self.get("origin")? else {
            return Ok(None);
        };
        let who = &self.who;
        match v.extract::<String>().ok().as_deref() {
            Some("main") => Ok(Some(Origin::Main)),
            Some("ramp") => Ok(Some(Origin::Ramp)),
            _ => Err(bad_input(format!(
                "{who}: 'origin' must be \"main\" or \"ramp\", got {}",
                v.repr()?
            ))),
        }
    }

    fn desired_speed(&mut self) -> PyResult<Option<f64>> {
        let desired_speed = self.optional_number("desired_speed")?;
        if desired_speed.is_some_and(|d| d < 0.0) {
            let who = &self.who;
            return Err(bad_input(format!(
                "{who}: 'desired_speed' must not be negative"
            )));
        }
        Ok(desired_speed)
    }

    /// Refuses a dict with keys beyond the known ones (a misspelt key would otherwise be
    /// ignored). Objects may carry any other attributes.
    fn reject_unknown_keys(&self) -> PyResult<()> {
        let Some(d) = self.dict.filter(|d| d.len() > self.found) else {
            return Ok(());
        };
        let who = &self.who;
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
        Ok(())
    }
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
        let r = read_vehicle(i, &item?, &keys, road)?;
        let origin = r
            .origin
            .or_else(|| frame::origin_from_id(&r.id))
            .or_else(|| origins.get(&r.id).copied())
            .unwrap_or_else(|| frame::origin_from_edge(road, r.raw.edge_code));
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
