//! Which SUMO: the version bkpbs was built against, and a check that the process runs that one.
//!
//! Every libsumo has the same soname, so a binary built against one SUMO loads another without
//! complaint when `LD_LIBRARY_PATH` (or a missing run-time path) points there, and its results
//! then come from a SUMO nobody chose. Results also move between SUMO versions, so the version
//! is part of every result (`sumo_version` in `episode.csv` and `campaign.toml`).

use super::{decode, ffi, SumoError};
use std::os::raw::c_char;

/// The SUMO version bkpbs was built against (e.g. `1.15.0`), as that libsumo reported it to
/// the build script.
pub const BUILT: &str = env!("BKPBS_SUMO_VERSION");

/// The directory of the SUMO bkpbs was built against when it was not Debian's system SUMO
/// (`$SUMO_HOME` at build time): its `bin/sumo-gui` is the one that matches.
pub const BUILT_HOME: Option<&str> = option_env!("BKPBS_SUMO_HOME");

/// The release of [`BUILT`] as (major, minor); a version that does not parse (a build from
/// SUMO's git, `v1_15_0+…`) is read the same way after its `v`, with `_` as the separator.
pub fn release() -> (u32, u32) {
    let mut parts = BUILT
        .trim_start_matches('v')
        .split(['.', '_', '-', '+'])
        .map(|p| p.parse::<u32>().unwrap_or(0));
    (parts.next().unwrap_or(0), parts.next().unwrap_or(0))
}

/// Whether this SUMO caps the lateral speed of a lane change under `--lanechange.duration` at
/// `lcMaxSpeedLatStanding` + `lcMaxSpeedLatFactor` × speed (default 1 m/s + the speed): 1.28
/// does, 1.15 does not (see the guide's SUMO facts); later than 1.15 is taken to.
pub fn caps_lane_change_lateral_speed() -> bool {
    release() > (1, 15)
}

/// The version SUMO reports through the current shim: the loaded libsumo's own, or (after a
/// libtraci start) the connected sumo-gui's; without the "SUMO " prefix.
fn reported() -> Result<String, SumoError> {
    let mut ptr: *const c_char = std::ptr::null();
    let mut len = 0usize;
    // SAFETY: valid out-pointers; the returned buffer is copied at once.
    unsafe {
        decode("getVersion", ffi::bk_version(&mut ptr, &mut len))?;
        let bytes = std::slice::from_raw_parts(ptr as *const u8, len);
        let text = String::from_utf8_lossy(bytes);
        Ok(text.trim().trim_start_matches("SUMO ").to_string())
    }
}

/// The file the process loaded libsumo from, for the error message (`/proc/self/maps`).
fn loaded_library() -> Option<String> {
    let maps = std::fs::read_to_string("/proc/self/maps").ok()?;
    let line = maps.lines().find(|l| l.contains("libsumocpp"))?;
    line.split_whitespace().last().map(str::to_string)
}

/// Checks that the SUMO this process talks to is the one bkpbs was built against: the loaded
/// libsumo (before a start), or the connected sumo-gui (`gui`, after a libtraci start).
pub(super) fn check(gui: bool) -> Result<(), SumoError> {
    let loaded = reported()?;
    if loaded == BUILT {
        return Ok(());
    }
    let from = if gui {
        "sumo-gui".to_string()
    } else {
        loaded_library().unwrap_or_else(|| "libsumocpp".into())
    };
    Err(SumoError::VersionMismatch {
        built: BUILT,
        loaded,
        from,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_version_is_a_release_number() {
        // A release says `1.15.0`; a build from SUMO's git says `v1_15_0+0123-abcdef`.
        let parts: Vec<&str> = BUILT
            .trim_start_matches('v')
            .split(['.', '_', '-', '+'])
            .collect();
        assert!(parts.len() >= 3, "{BUILT}");
        assert!(
            parts[..3].iter().all(|p| p.parse::<u32>().is_ok()),
            "{BUILT}"
        );
    }

    #[test]
    fn the_loaded_libsumo_is_the_built_one() {
        assert_eq!(reported().unwrap(), BUILT);
        assert!(loaded_library().unwrap().contains("libsumocpp"));
    }
}
