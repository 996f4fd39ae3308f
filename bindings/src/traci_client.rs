//! The caller's TraCI module (`traci`, `libsumo`, or a `traci` connection) as the core's
//! [`SumoClient`]: every call the episode on a user's scenario makes of SUMO, made through the
//! module of the caller's own loop. Vehicles are read by `bkpbs.sumo.read_vehicles` (one
//! subscription per vehicle) and put in SUMO's order of `vehicle.getIDList`, the order in
//! which the core's own loop reads them, so that both plan alike.

use std::collections::HashMap;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use bkpbs::model::scene::{Following, Limits};
use bkpbs::sumo::{Collision, NewVehicle, RawVehicleState, SumoClient, SumoError, VehicleReadings};

/// The caller's module, and the codes of the edges whose vehicles are read by index.
pub struct TraciClient<'py> {
    module: Bound<'py, PyAny>,
    codes: HashMap<String, i32>,
}

/// A Python exception in call `call`, as the core's SUMO error.
fn failed(call: &'static str) -> impl Fn(PyErr) -> SumoError {
    move |e| SumoError::Sumo {
        call,
        message: e.to_string(),
    }
}

impl<'py> TraciClient<'py> {
    /// The client of `module`, reading the vehicles of `edges` by their index there.
    pub fn new(module: Bound<'py, PyAny>, edges: &[String]) -> Self {
        let mut client = TraciClient {
            module,
            codes: HashMap::new(),
        };
        let names: Vec<&str> = edges.iter().map(String::as_str).collect();
        client.register(&names);
        client
    }

    fn register(&mut self, edges: &[&str]) {
        self.codes = edges
            .iter()
            .enumerate()
            .map(|(k, e)| (e.to_string(), k as i32))
            .collect();
    }

    /// `domain.function(args)` of the module, extracted as `T`.
    fn call<T>(
        &self,
        call: &'static str,
        args: impl pyo3::call::PyCallArgs<'py>,
    ) -> Result<T, SumoError>
    where
        T: for<'a> FromPyObject<'a, 'py>,
        for<'a> <T as FromPyObject<'a, 'py>>::Error: Into<PyErr>,
    {
        let (domain, function) = call.split_once('.').expect("domain.function");
        let on = failed(call);
        let value = self
            .module
            .getattr(domain)
            .and_then(|d| d.call_method1(function, args))
            .map_err(&on)?;
        value.extract::<T>().map_err(|e| on(e.into()))
    }

    /// A command that answers nothing.
    fn command(
        &self,
        call: &'static str,
        args: impl pyo3::call::PyCallArgs<'py>,
    ) -> Result<(), SumoError> {
        self.call::<Bound<'py, PyAny>>(call, args).map(drop)
    }

    /// One vehicle of `bkpbs.read_vehicles`'s list, as the core reads it.
    fn reading(&self, v: &Bound<'py, PyDict>) -> Result<RawVehicleState, SumoError> {
        let on = failed("vehicle.getSubscriptionResults");
        let get = |k: &str| -> Result<Bound<'py, PyAny>, SumoError> {
            v.get_item(k)
                .map_err(&on)?
                .ok_or_else(|| on(pyo3::exceptions::PyKeyError::new_err(k.to_string())))
        };
        let num = |k: &str| -> Result<f64, SumoError> { get(k)?.extract().map_err(&on) };
        let road: String = get("road_id")?.extract().map_err(&on)?;
        Ok(RawVehicleState {
            x: num("x")?,
            y: num("y")?,
            speed: num("speed")?,
            acceleration: num("acceleration")?,
            angle: num("angle")?,
            lane_position: num("lane_position")?,
            lateral_offset: num("lateral_offset")?,
            lateral_speed: num("lateral_speed")?,
            lane_index: get("lane_index")?.extract().map_err(&on)?,
            edge_code: self.codes.get(&road).copied().unwrap_or(-1),
        })
    }
}

impl SumoClient for TraciClient<'_> {
    fn time(&self) -> Result<f64, SumoError> {
        self.call("simulation.getTime", ())
    }
    fn departed(&self) -> Result<Vec<String>, SumoError> {
        self.call("simulation.getDepartedIDList", ())
    }
    fn arrived(&self) -> Result<Vec<String>, SumoError> {
        self.call("simulation.getArrivedIDList", ())
    }
    fn pending(&self) -> Result<Vec<String>, SumoError> {
        self.call("simulation.getPendingVehicles", ())
    }
    fn vehicle_type_ids(&self) -> Result<Vec<String>, SumoError> {
        self.call("vehicletype.getIDList", ())
    }
    fn set_edge_codes(&mut self, edges: &[&str]) -> Result<(), SumoError> {
        self.register(edges);
        Ok(())
    }
    fn read_vehicles(&self, out: &mut VehicleReadings) -> Result<(), SumoError> {
        let py = self.module.py();
        let on = failed("vehicle.getSubscriptionResults");
        let list = py
            .import("bkpbs.sumo")
            .and_then(|m| m.call_method1("read_vehicles", (&self.module,)))
            .map_err(&on)?;
        let mut by_id = HashMap::new();
        for v in list.try_iter().map_err(&on)? {
            let v = v.map_err(&on)?;
            let d = v.cast::<PyDict>().map_err(|e| on(e.into()))?;
            let id: String = d
                .get_item("id")
                .map_err(&on)?
                .map(|i| i.extract())
                .transpose()
                .map_err(&on)?
                .unwrap_or_default();
            by_id.insert(id, self.reading(d)?);
        }
        let ids: Vec<String> = self.call("vehicle.getIDList", ())?;
        let ids: Vec<String> = ids.into_iter().filter(|i| by_id.contains_key(i)).collect();
        let states = ids.iter().map(|i| by_id[i]).collect();
        out.replace(ids, states);
        Ok(())
    }
    fn collisions(&self) -> Result<Vec<Collision>, SumoError> {
        let on = failed("simulation.getCollisions");
        let list: Vec<Bound<'_, PyAny>> = self.call("simulation.getCollisions", ())?;
        list.iter()
            .map(|c| {
                let text = |k: &str| -> PyResult<String> { c.getattr(k)?.extract() };
                Ok(Collision {
                    collider: text("collider")?,
                    victim: text("victim")?,
                    collider_type: text("colliderType")?,
                    victim_type: text("victimType")?,
                    kind: text("type")?,
                    lane: text("lane")?,
                    position: c.getattr("pos")?.extract()?,
                })
            })
            .collect::<PyResult<_>>()
            .map_err(on)
    }
    fn vehicle_type(&self, id: &str) -> Result<String, SumoError> {
        self.call("vehicle.getTypeID", (id,))
    }
    fn vehicle_route(&self, id: &str) -> Result<Vec<String>, SumoError> {
        self.call("vehicle.getRoute", (id,))
    }
    fn vehicle_size(&self, id: &str) -> Result<(f64, f64), SumoError> {
        Ok((
            self.call("vehicle.getLength", (id,))?,
            self.call("vehicle.getWidth", (id,))?,
        ))
    }
    fn vehicle_max_speed(&self, id: &str) -> Result<f64, SumoError> {
        self.call("vehicle.getMaxSpeed", (id,))
    }
    fn vehicle_speed_factor(&self, id: &str) -> Result<f64, SumoError> {
        self.call("vehicle.getSpeedFactor", (id,))
    }
    fn vehicle_limits(&self, id: &str) -> Result<Limits, SumoError> {
        Ok(Limits {
            accel: self.call("vehicle.getAccel", (id,))?,
            decel: self.call("vehicle.getDecel", (id,))?,
            emergency_decel: self.call("vehicle.getEmergencyDecel", (id,))?,
            following: Some(Following {
                tau: self.call("vehicle.getTau", (id,))?,
                min_gap: self.call("vehicle.getMinGap", (id,))?,
            }),
        })
    }
    fn driving_distance(&self, id: &str, edge: &str, pos: f64) -> Result<f64, SumoError> {
        self.call("vehicle.getDrivingDistance", (id, edge, pos))
    }
    fn set_speeds(&mut self, speeds: &[(&str, f64)]) -> Result<(), SumoError> {
        speeds.iter().try_for_each(|(id, v)| self.set_speed(id, *v))
    }
    fn set_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError> {
        self.command("vehicle.setSpeed", (id, speed))
    }
    fn set_speed_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError> {
        self.command("vehicle.setSpeedMode", (id, mode))
    }
    fn set_lane_change_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError> {
        self.command("vehicle.setLaneChangeMode", (id, mode))
    }
    fn change_lane(&mut self, id: &str, lane_index: i32, duration: f64) -> Result<(), SumoError> {
        self.command("vehicle.changeLane", (id, lane_index, duration))
    }
    fn remove_vehicle(&mut self, id: &str) -> Result<(), SumoError> {
        // SUMO's REMOVE_VAPORIZED, as the core's own loop removes a crashed vehicle.
        self.command("vehicle.remove", (id, 4))
    }
    fn set_color(&mut self, id: &str, [r, g, b]: [u8; 3]) -> Result<(), SumoError> {
        self.command("vehicle.setColor", (id, (r, g, b, 255u8)))
    }
    fn add_vehicle(&mut self, v: NewVehicle) -> Result<(), SumoError> {
        // As the core's own loop adds one: now, at the lane's start, at this speed.
        let (lane, speed) = (v.lane.to_string(), format!("{:.6}", v.speed));
        let args = (v.id, v.route, v.type_id, "now", lane, "base", speed);
        self.command("vehicle.add", args)
    }
    fn set_max_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError> {
        self.command("vehicle.setMaxSpeed", (id, speed))
    }
}
