//! What SUMO is given for one episode: the network, the vehicle types, the demand, and options.

use std::path::{Path, PathBuf};

use crate::config::Config;
use crate::model::road::EMBEDDED_NET;

/// Why the episode's SUMO input could not be prepared.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("net file {0} does not exist")]
    MissingNet(PathBuf),
    #[error("cannot write SUMO input {path}: {cause}")]
    Write {
        path: PathBuf,
        cause: std::io::Error,
    },
}

/// SUMO vehicle types `hdv` and `cav` from the configured IDM parameters.
///
/// Both are 5 m × 2 m with a 35 m/s maximum; speedFactor 1 and speedDev 0 so that the desired
/// speed is exactly the one the demand draws (SUMO's default would randomise it).
pub fn vehicle_types(config: &Config) -> String {
    let s = &config.scenario;
    let i = &config.idm;
    let vtype = |id: &str, color: &str| {
        format!(
            "    <vType id=\"{id}\" vClass=\"passenger\" length=\"{}\" width=\"{}\" minGap=\"{}\" maxSpeed=\"{}\" accel=\"{}\" decel=\"{}\" emergencyDecel=\"{}\" tau=\"{}\" delta=\"{}\" carFollowModel=\"IDM\" laneChangeModel=\"LC2013\" speedFactor=\"1\" speedDev=\"0\" sigma=\"0\" color=\"{color}\"/>\n",
            s.vehicle_length, s.vehicle_width, i.min_gap, s.v_max, i.accel, i.decel, i.max_decel, i.time_headway, i.delta
        )
    };
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- Vehicle types of the merge scenario (written by bkpbs from its configuration). -->\n<additional>\n{}{}</additional>\n",
        vtype("hdv", "0,90,255"),
        vtype("cav", "0,200,0")
    )
}

/// Prefix of an episode's input directory in the temporary directory: `bkpbs-episode-<pid>-…`.
pub const INPUT_DIR_PREFIX: &str = "bkpbs-episode-";

/// The files of one episode, kept in a directory that lives as long as this value.
pub struct EpisodeInput {
    _dir: tempfile::TempDir,
    pub net: PathBuf,
    pub vehicle_types: PathBuf,
    pub routes: PathBuf,
}

impl EpisodeInput {
    /// Writes the network (unless the config names one), vehicle types and routes.
    pub fn write(config: &Config) -> Result<Self, InputError> {
        // Directories of killed runs (SIGINT, SIGKILL) are swept here, by the next run: their
        // names carry their process id.
        crate::io::sweep_stale(&std::env::temp_dir(), INPUT_DIR_PREFIX);
        let dir = tempfile::Builder::new()
            .prefix(&format!("{INPUT_DIR_PREFIX}{}-", std::process::id()))
            .tempdir()
            .map_err(|cause| InputError::Write {
                path: std::env::temp_dir(),
                cause,
            })?;
        let put = |name: &str, text: &str| -> Result<PathBuf, InputError> {
            let path = dir.path().join(name);
            std::fs::write(&path, text).map_err(|cause| InputError::Write {
                path: path.clone(),
                cause,
            })?;
            Ok(path)
        };
        let net = match &config.scenario.net_file {
            Some(p) if !p.is_file() => return Err(InputError::MissingNet(p.clone())),
            Some(p) => p.clone(),
            None => put("merge.net.xml", EMBEDDED_NET)?,
        };
        let vehicle_types = put("vtypes.add.xml", &vehicle_types(config))?;
        let routes = put("routes.rou.xml", ROUTES)?;
        Ok(EpisodeInput {
            _dir: dir,
            net,
            vehicle_types,
            routes,
        })
    }

    /// The SUMO command line for these files.
    pub fn command_line(&self, config: &Config) -> Vec<String> {
        command_line(config, &self.net, &self.vehicle_types, &self.routes)
    }
}

/// SUMO options of the merge scenario.
///
/// Collisions are physical overlaps only (`mingap-factor 0`); SUMO only reports them
/// (`collision.action warn`) and the episode removes both vehicles right after the step, because
/// SUMO 1.15's own removal in the middle of its move stage trips an internal assertion (and
/// aborts the process) when a participant is changing lanes across an edge boundary. No
/// teleporting, so a jam stays a jam; lane changes take `lane_change_duration` seconds at
/// constant lateral speed.
pub fn command_line(config: &Config, net: &Path, vtypes: &Path, routes: &Path) -> Vec<String> {
    let s = &config.scenario;
    let program = if config.sumo.gui { GUI_PROGRAM } else { "sumo" };
    let mut args: Vec<String> = vec![
        program.into(),
        "--net-file".into(),
        net.display().to_string(),
        "--additional-files".into(),
        std::iter::once(vtypes.display().to_string())
            .chain(
                config
                    .sumo
                    .additional_files
                    .iter()
                    .map(|p| p.display().to_string()),
            )
            .collect::<Vec<_>>()
            .join(","),
        "--route-files".into(),
        routes.display().to_string(),
        "--step-length".into(),
        format!("{}", s.dt),
        "--begin".into(),
        "0".into(),
        "--seed".into(),
        format!("{}", s.seed % (i32::MAX as u64)),
        "--collision.action".into(),
        "warn".into(),
        "--collision.check-junctions".into(),
        "true".into(),
        "--collision.mingap-factor".into(),
        "0".into(),
        "--time-to-teleport".into(),
        "-1".into(),
        "--lanechange.duration".into(),
        format!("{}", s.lane_change_duration),
    ];
    if !config.sumo.verbose {
        for opt in ["--no-warnings", "--no-step-log", "--duration-log.disable"] {
            args.push(opt.into());
            args.push("true".into());
        }
    }
    if config.sumo.gui {
        // Start at once, close at the end, and pause each step (real time by default).
        let delay = config.sumo.gui_delay_ms.unwrap_or(s.dt * 1000.0);
        for (opt, value) in [
            ("--start", "true".to_string()),
            ("--quit-on-end", "true".to_string()),
            ("--delay", format!("{delay}")),
        ] {
            args.push(opt.into());
            args.push(value);
        }
    }
    args.extend(config.sumo.extra_args.iter().cloned());
    args
}

/// The program that shows an episode (`sumo.gui`); `Simulation::start` drives it through
/// libtraci when a command line starts with it.
pub const GUI_PROGRAM: &str = "sumo-gui";

/// Why sumo-gui cannot be shown here, if it cannot: no display, or no sumo-gui.
pub fn gui_unavailable() -> Option<String> {
    let display = ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|d| !d.is_empty()));
    if !display {
        return Some(
            "no display for sumo-gui (DISPLAY is not set); on a machine without one run under a \
             virtual X server: xvfb-run -a bkpbs episode --gui …"
                .into(),
        );
    }
    let on_path = std::env::var_os("PATH").is_some_and(|path| {
        std::env::split_paths(&path).any(|dir| dir.join(GUI_PROGRAM).is_file())
    });
    (!on_path).then(|| format!("{GUI_PROGRAM} is not installed (Debian: apt-get install sumo)"))
}

/// SUMO route file with the two routes (vehicles are added at run time by entry control).
pub const ROUTES: &str = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- the merge scenario's two routes -->\n<routes>\n    <route id=\"main\" edges=\"main_in acc main_out\"/>\n    <route id=\"ramp\" edges=\"ramp acc main_out\"/>\n</routes>\n";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_vehicle_types_match_the_defaults() {
        let shipped = include_str!("../../sumo_net/vtypes.add.xml");
        assert_eq!(
            shipped,
            vehicle_types(&Config::default()),
            "sumo_net/vtypes.add.xml drifted from the defaults: regenerate it with `bkpbs config --vtypes`"
        );
    }

    #[test]
    fn missing_net_file_is_named() {
        let mut c = Config::default();
        c.scenario.net_file = Some("nowhere/merge.net.xml".into());
        let e = EpisodeInput::write(&c).err().unwrap().to_string();
        assert!(e.contains("nowhere/merge.net.xml"), "{e}");
    }
}
