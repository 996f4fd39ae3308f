//! Safe, in-process access to SUMO through Debian's libsumo.
//!
//! libsumo keeps one global simulation per process, so [`Simulation`] is a handle to that one
//! slot: opening a second one from the same thread is an error, and a different thread waits until
//! the first closes. The handle is neither `Send` nor `Sync`. Every call goes through the C++ shim
//! (`shim.cpp`), which catches every C++ exception; `decode` turns the shim's status into a
//! [`SumoError`] carrying SUMO's own message and the call that failed.

pub mod client;
pub mod files;
pub mod frame;
pub mod layout;
pub mod network;
pub mod road_frame;
pub mod route_files;
pub mod scenario_files;
pub mod scenario_record;
pub mod sumocfg;
pub mod version;

mod error;
#[cfg(test)]
pub(crate) mod fake;
mod ffi;
mod new_vehicle;
mod quiet;
mod sumocfg_refusals;
mod vehicle;

use std::ffi::{CStr, CString};
use std::marker::PhantomData;
use std::os::raw::c_char;
use std::sync::{Condvar, Mutex};
use std::thread::{self, ThreadId};

pub use client::SumoClient;
pub use error::SumoError;
pub use ffi::RawVehicleState;
pub use new_vehicle::NewVehicle;
pub use quiet::StderrCapture;

/// Turns a shim status code into a `Result`, attaching SUMO's message.
fn decode(call: &'static str, status: i32) -> Result<(), SumoError> {
    if status == 0 {
        return Ok(());
    }
    // SAFETY: the shim always returns a valid NUL-terminated string it owns.
    let raw = unsafe { CStr::from_ptr(ffi::bk_last_error()) }.to_string_lossy();
    // SUMO sometimes breaks its messages over lines; errors here are reported on one.
    let message = raw.split_whitespace().collect::<Vec<_>>().join(" ");
    Err(SumoError::Sumo { call, message })
}

fn c_string(s: &str) -> Result<CString, SumoError> {
    CString::new(s).map_err(|_| SumoError::NulInString(s.to_string()))
}

/// Splits a NUL-separated buffer owned by the shim into owned strings.
///
/// # Safety
/// `ptr` must point to `len` readable bytes (or be anything when `len` is 0).
unsafe fn split_nul(ptr: *const c_char, len: usize) -> Vec<String> {
    if len == 0 {
        return Vec::new();
    }
    let bytes = std::slice::from_raw_parts(ptr as *const u8, len);
    let body = bytes.strip_suffix(&[0]).unwrap_or(bytes);
    body.split(|b| *b == 0)
        .map(|b| String::from_utf8_lossy(b).into_owned())
        .collect()
}

static SLOT: Mutex<Option<ThreadId>> = Mutex::new(None);
static SLOT_FREED: Condvar = Condvar::new();

/// Proof of holding the process's one libsumo slot; released on drop.
struct SlotGuard {
    _not_send: PhantomData<*const ()>,
}

impl SlotGuard {
    fn acquire() -> Result<Self, SumoError> {
        let me = thread::current().id();
        let mut owner = SLOT.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            match *owner {
                None => {
                    *owner = Some(me);
                    return Ok(SlotGuard {
                        _not_send: PhantomData,
                    });
                }
                Some(t) if t == me => return Err(SumoError::AlreadyOpen),
                Some(_) => owner = SLOT_FREED.wait(owner).unwrap_or_else(|e| e.into_inner()),
            }
        }
    }
}

impl Drop for SlotGuard {
    fn drop(&mut self) {
        *SLOT.lock().unwrap_or_else(|e| e.into_inner()) = None;
        SLOT_FREED.notify_one();
    }
}

/// A collision SUMO detected in the last step; `collider` drove into `victim`.
#[derive(Debug, Clone, PartialEq)]
pub struct Collision {
    /// Id of the vehicle that drove into the other.
    pub collider: String,
    /// Id of the vehicle it drove into.
    pub victim: String,
    /// SUMO type id of the collider (e.g. `cav`, `hdv`, `hdv.0`).
    pub collider_type: String,
    /// SUMO type id of the victim.
    pub victim_type: String,
    /// SUMO's collision kind, e.g. "collision" or "frontal".
    pub kind: String,
    /// SUMO id of the lane it happened on.
    pub lane: String,
    /// Where along that lane (m from its start).
    pub position: f64,
}

/// All vehicles of one step: ids and raw states in the same order.
///
/// Reused from step to step so that, while the set of vehicles is unchanged, reading allocates
/// nothing.
#[derive(Debug, Default)]
pub struct VehicleReadings {
    /// SUMO ids of the vehicles now in the network.
    pub ids: Vec<String>,
    /// Their readings, in the order of `ids`.
    pub states: Vec<RawVehicleState>,
    /// Changes whenever `ids` changes, so callers can keep per-id lookups between steps.
    pub generation: u64,
    id_bytes: Vec<u8>,
}

/// The open libsumo simulation of this process.
pub struct Simulation {
    open: bool,
    /// The bound on one SUMO call, for the watchdog.
    stall_limit: std::time::Duration,
    /// SUMO's time after the last step (s), to see that each step advances it.
    time: f64,
    /// Reused buffers of [`Simulation::set_speeds`].
    batch_ids: Vec<u8>,
    batch_speeds: Vec<f64>,
    _slot: SlotGuard,
}

impl Simulation {
    /// Starts SUMO with a full command line: in this process through libsumo (`args[0]` is a
    /// program name it ignores), or, when `args[0]` is `sumo-gui`, that program driven through
    /// libtraci (same calls, same results, shown live).
    ///
    /// Waits while another thread of this process has a simulation open. Each SUMO call of
    /// the start, the steps and the close must return within `stall_limit`, or the watchdog
    /// ends the process with one error line ([`crate::io::watchdog`]); while the simulation is
    /// open, a libsumo abort is one error line too ([`quiet::report_aborts`]).
    pub fn start(args: &[String], stall_limit: std::time::Duration) -> Result<Self, SumoError> {
        let slot = SlotGuard::acquire()?;
        let gui = args
            .first()
            .is_some_and(|p| p.ends_with(files::GUI_PROGRAM));
        ffi::use_traci(gui);
        if !gui {
            version::check(false)?;
        }
        let mut buf = Vec::new();
        for a in args {
            buf.extend_from_slice(c_string(a)?.as_bytes_with_nul());
        }
        let what = if gui {
            "starting sumo-gui"
        } else {
            "starting SUMO"
        };
        let busy = crate::io::watchdog::busy(what, None, stall_limit);
        quiet::report_aborts(true);
        // SAFETY: `buf` holds `args.len()` NUL-terminated strings.
        let started = decode("start", unsafe {
            ffi::bk_start(buf.as_ptr() as *const c_char, args.len())
        });
        drop(busy);
        if let Err(e) = started {
            quiet::report_aborts(false);
            return Err(e);
        }
        let mut sim = Simulation {
            open: true,
            stall_limit,
            time: f64::NEG_INFINITY,
            batch_ids: Vec::new(),
            batch_speeds: Vec::new(),
            _slot: slot,
        };
        if gui {
            version::check(true)?;
        }
        sim.time = sim.time()?;
        Ok(sim)
    }

    /// Ends the simulation and frees the process's slot for the next one.
    pub fn close(mut self) -> Result<(), SumoError> {
        self.open = false;
        let _busy = crate::io::watchdog::busy("closing SUMO", None, self.stall_limit);
        // SAFETY: plain call into the shim.
        let closed = decode("close", unsafe { ffi::bk_close() });
        quiet::report_aborts(false);
        closed
    }

    /// Advances SUMO by one step of its `--step-length`; a step that leaves SUMO's clock where
    /// it was is an error (a simulation that stops advancing would otherwise run forever).
    pub fn step(&mut self) -> Result<(), SumoError> {
        let busy =
            crate::io::watchdog::busy("the simulation step", Some(self.time), self.stall_limit);
        // SAFETY: plain call into the shim.
        decode("simulationStep", unsafe { ffi::bk_step() })?;
        drop(busy);
        let now = self.time()?;
        if now <= self.time {
            return Err(SumoError::Stalled { time: now });
        }
        self.time = now;
        Ok(())
    }

    /// Current simulation time (s).
    pub fn time(&self) -> Result<f64, SumoError> {
        let mut t = 0.0;
        // SAFETY: `t` is a valid out-pointer.
        decode("getTime", unsafe { ffi::bk_time(&mut t) })?;
        Ok(t)
    }

    /// Vehicles loaded or in the net that have not yet arrived (SUMO's own count).
    pub fn min_expected_number(&self) -> Result<i32, SumoError> {
        let mut n = 0;
        // SAFETY: `n` is a valid out-pointer.
        decode("getMinExpectedNumber", unsafe {
            ffi::bk_min_expected_number(&mut n)
        })?;
        Ok(n)
    }

    fn id_list(&self, which: i32, call: &'static str) -> Result<Vec<String>, SumoError> {
        let mut ptr: *const c_char = std::ptr::null();
        let mut len = 0usize;
        // SAFETY: out-pointers are valid; the buffer stays alive until the next id-list call, and
        // we copy it before returning.
        unsafe {
            decode(call, ffi::bk_id_list(which, &mut ptr, &mut len))?;
            Ok(split_nul(ptr, len))
        }
    }

    /// Ids of the vehicles now in the network.
    pub fn vehicle_ids(&self) -> Result<Vec<String>, SumoError> {
        self.id_list(ffi::LIST_VEHICLES, "getIDList")
    }

    /// Vehicles inserted during the last step.
    pub fn departed(&self) -> Result<Vec<String>, SumoError> {
        self.id_list(ffi::LIST_DEPARTED, "getDepartedIDList")
    }

    /// Vehicles whose departure time has come but which SUMO has not inserted (yet): no room
    /// at their departure position, or held back by the insertion order.
    pub fn pending(&self) -> Result<Vec<String>, SumoError> {
        self.id_list(ffi::LIST_PENDING, "getPendingVehicles")
    }

    /// Vehicles that left the network during the last step (in SUMO 1.15 this includes vehicles
    /// removed after a collision, one step after the collision).
    pub fn arrived(&self) -> Result<Vec<String>, SumoError> {
        self.id_list(ffi::LIST_ARRIVED, "getArrivedIDList")
    }

    /// Ids of all lanes of the network.
    pub fn lane_ids(&self) -> Result<Vec<String>, SumoError> {
        self.id_list(ffi::LIST_LANES, "lane.getIDList")
    }

    /// Ids of all edges of the network (internal ones included).
    pub fn edge_ids(&self) -> Result<Vec<String>, SumoError> {
        self.id_list(ffi::LIST_EDGES, "edge.getIDList")
    }

    /// Ids of the vehicle types loaded (those of every route and additional file read so far).
    pub fn vehicle_type_ids(&self) -> Result<Vec<String>, SumoError> {
        self.id_list(ffi::LIST_VEHICLE_TYPES, "vehicletype.getIDList")
    }

    /// Chooses the edges that [`Simulation::read_vehicles`] reports by index
    /// (`RawVehicleState::edge_code`), so no edge name crosses the boundary each step.
    pub fn set_edge_codes(&mut self, edges: &[&str]) -> Result<(), SumoError> {
        let mut buf = Vec::new();
        for e in edges {
            buf.extend_from_slice(c_string(e)?.as_bytes_with_nul());
        }
        // SAFETY: `buf` holds `edges.len()` NUL-terminated strings.
        decode("setEdgeNames", unsafe {
            ffi::bk_set_edge_names(buf.as_ptr() as *const c_char, edges.len())
        })
    }

    /// Reads the state of every vehicle in one call into `out`.
    pub fn read_vehicles(&self, out: &mut VehicleReadings) -> Result<(), SumoError> {
        let mut states: *const RawVehicleState = std::ptr::null();
        let mut count = 0usize;
        let mut strings: *const c_char = std::ptr::null();
        let mut strings_len = 0usize;
        // SAFETY: out-pointers are valid; the shim's buffers stay alive until its next
        // `bk_read_vehicles`, and both are copied here before returning.
        unsafe {
            decode(
                "readVehicles",
                ffi::bk_read_vehicles(&mut states, &mut count, &mut strings, &mut strings_len),
            )?;
            out.states.clear();
            if count > 0 {
                out.states
                    .extend_from_slice(std::slice::from_raw_parts(states, count));
            }
            let bytes: &[u8] = if strings_len == 0 {
                &[]
            } else {
                std::slice::from_raw_parts(strings as *const u8, strings_len)
            };
            if bytes != out.id_bytes.as_slice() {
                out.id_bytes.clear();
                out.id_bytes.extend_from_slice(bytes);
                out.ids = split_nul(strings, strings_len);
                out.generation += 1;
            }
        }
        Ok(())
    }

    /// Collisions detected during the last step.
    pub fn collisions(&self) -> Result<Vec<Collision>, SumoError> {
        let mut items: *const ffi::RawCollision = std::ptr::null();
        let mut count = 0usize;
        let mut strings: *const c_char = std::ptr::null();
        let mut strings_len = 0usize;
        // SAFETY: out-pointers are valid and both buffers are copied before returning.
        unsafe {
            decode(
                "getCollisions",
                ffi::bk_collisions(&mut items, &mut count, &mut strings, &mut strings_len),
            )?;
            if count == 0 {
                return Ok(Vec::new());
            }
            let raw = std::slice::from_raw_parts(items, count);
            let mut s = split_nul(strings, strings_len).into_iter();
            let mut next = || s.next().unwrap_or_default();
            Ok(raw
                .iter()
                .map(|r| Collision {
                    collider: next(),
                    victim: next(),
                    collider_type: next(),
                    victim_type: next(),
                    kind: next(),
                    lane: next(),
                    position: r.position,
                })
                .collect())
        }
    }

    /// Sets the speed SUMO gives the vehicle in the next step (m/s); negative hands speed back.
    pub fn set_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError> {
        let cid = c_string(id)?;
        // SAFETY: valid C string.
        decode("vehicle.setSpeed", unsafe {
            ffi::bk_set_speed(cid.as_ptr(), speed)
        })
    }

    /// Adds `v`, departing now from the start of its route on its lane at its speed; SUMO
    /// inserts it in the coming step if there is room, else retries.
    pub fn add_vehicle(&mut self, v: NewVehicle) -> Result<(), SumoError> {
        let (id, route, ty) = (c_string(v.id)?, c_string(v.route)?, c_string(v.type_id)?);
        // SAFETY: valid C strings.
        decode("vehicle.add", unsafe {
            ffi::bk_vehicle_add(id.as_ptr(), route.as_ptr(), ty.as_ptr(), v.lane, v.speed)
        })
    }

    /// Takes a vehicle out of the simulation now.
    pub fn remove_vehicle(&mut self, id: &str) -> Result<(), SumoError> {
        let cid = c_string(id)?;
        // SAFETY: valid C string.
        decode("vehicle.remove", unsafe {
            ffi::bk_vehicle_remove(cid.as_ptr())
        })
    }

    /// [`Simulation::set_speed`] for many vehicles in one call across the boundary.
    pub fn set_speeds<'a>(
        &mut self,
        commands: impl Iterator<Item = (&'a str, f64)>,
    ) -> Result<(), SumoError> {
        self.batch_ids.clear();
        self.batch_speeds.clear();
        for (id, speed) in commands {
            if id.as_bytes().contains(&0) {
                return Err(SumoError::NulInString(id.to_string()));
            }
            self.batch_ids.extend_from_slice(id.as_bytes());
            self.batch_ids.push(0);
            self.batch_speeds.push(speed);
        }
        if self.batch_speeds.is_empty() {
            return Ok(());
        }
        // SAFETY: `batch_ids` holds `batch_speeds.len()` NUL-terminated strings.
        decode("vehicle.setSpeed", unsafe {
            ffi::bk_set_speeds(
                self.batch_ids.as_ptr() as *const c_char,
                self.batch_speeds.len(),
                self.batch_speeds.as_ptr(),
            )
        })
    }

    /// Sets the vehicle's own maximum speed, which IDM uses as its desired speed.
    pub fn set_max_speed(&mut self, id: &str, speed: f64) -> Result<(), SumoError> {
        let cid = c_string(id)?;
        // SAFETY: valid C string.
        decode("vehicle.setMaxSpeed", unsafe {
            ffi::bk_set_max_speed(cid.as_ptr(), speed)
        })
    }

    /// The vehicle's colour in the GUI (red, green, blue).
    pub fn set_color(&mut self, id: &str, [r, g, b]: [u8; 3]) -> Result<(), SumoError> {
        let cid = c_string(id)?;
        // SAFETY: valid C string.
        decode("vehicle.setColor", unsafe {
            ffi::bk_set_color(cid.as_ptr(), r.into(), g.into(), b.into())
        })
    }

    /// SUMO's speed-mode bit set (0 = no checks at all: the command is the speed).
    pub fn set_speed_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError> {
        let cid = c_string(id)?;
        // SAFETY: valid C string.
        decode("vehicle.setSpeedMode", unsafe {
            ffi::bk_set_speed_mode(cid.as_ptr(), mode)
        })
    }

    /// SUMO's lane-change-mode bit set (0 = no own changes, TraCI requests obeyed blindly).
    pub fn set_lane_change_mode(&mut self, id: &str, mode: i32) -> Result<(), SumoError> {
        let cid = c_string(id)?;
        // SAFETY: valid C string.
        decode("vehicle.setLaneChangeMode", unsafe {
            ffi::bk_set_lane_change_mode(cid.as_ptr(), mode)
        })
    }

    /// Asks the vehicle to move to `lane_index` of its current edge and stay there for
    /// `duration` seconds (the manoeuvre itself takes `--lanechange.duration`).
    pub fn change_lane(
        &mut self,
        id: &str,
        lane_index: i32,
        duration: f64,
    ) -> Result<(), SumoError> {
        let cid = c_string(id)?;
        // SAFETY: valid C string.
        decode("vehicle.changeLane", unsafe {
            ffi::bk_change_lane(cid.as_ptr(), lane_index, duration)
        })
    }

    /// Length of a lane (m).
    pub fn lane_length(&self, lane: &str) -> Result<f64, SumoError> {
        self.lane_scalar(lane, "lane.getLength", ffi::bk_lane_length)
    }

    /// Width of a lane (m).
    pub fn lane_width(&self, lane: &str) -> Result<f64, SumoError> {
        self.lane_scalar(lane, "lane.getWidth", ffi::bk_lane_width)
    }

    /// Speed limit of a lane (m/s).
    pub fn lane_max_speed(&self, lane: &str) -> Result<f64, SumoError> {
        self.lane_scalar(lane, "lane.getMaxSpeed", ffi::bk_lane_max_speed)
    }

    fn lane_scalar(
        &self,
        lane: &str,
        call: &'static str,
        f: unsafe fn(*const c_char, *mut f64) -> i32,
    ) -> Result<f64, SumoError> {
        let clane = c_string(lane)?;
        let mut v = 0.0;
        // SAFETY: valid C string and out-pointer.
        decode(call, unsafe { f(clane.as_ptr(), &mut v) })?;
        Ok(v)
    }

    /// Number of lanes of an edge.
    pub fn edge_lane_count(&self, edge: &str) -> Result<usize, SumoError> {
        let cedge = c_string(edge)?;
        let mut n = 0;
        // SAFETY: valid C string and out-pointer.
        decode("edge.getLaneNumber", unsafe {
            ffi::bk_edge_lane_count(cedge.as_ptr(), &mut n)
        })?;
        Ok(n.max(0) as usize)
    }

    /// Points of a lane's centre line.
    pub fn lane_shape(&self, lane: &str) -> Result<Vec<(f64, f64)>, SumoError> {
        let clane = c_string(lane)?;
        let mut ptr: *const f64 = std::ptr::null();
        let mut n = 0usize;
        // SAFETY: valid pointers; the buffer is copied at once.
        unsafe {
            decode(
                "lane.getShape",
                ffi::bk_lane_shape(clane.as_ptr(), &mut ptr, &mut n),
            )?;
            if n == 0 {
                return Ok(Vec::new());
            }
            let flat = std::slice::from_raw_parts(ptr, n);
            Ok(flat.chunks_exact(2).map(|p| (p[0], p[1])).collect())
        }
    }
}

impl Drop for Simulation {
    fn drop(&mut self) {
        if self.open {
            // SAFETY: plain call; an error here has nowhere to go and is ignored.
            unsafe {
                ffi::bk_close();
            }
            quiet::report_aborts(false);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_nul_handles_empty_and_trailing_nul() {
        let buf = b"a\0bc\0\0d\0";
        let v = unsafe { split_nul(buf.as_ptr() as *const c_char, buf.len()) };
        assert_eq!(v, vec!["a", "bc", "", "d"]);
        let v = unsafe { split_nul(std::ptr::null(), 0) };
        assert!(v.is_empty());
    }

    #[test]
    fn decode_ok_is_ok() {
        assert!(decode("x", 0).is_ok());
    }
}
