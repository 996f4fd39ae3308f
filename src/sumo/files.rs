//! What SUMO is given for one episode: the network, the vehicle types, the demand, and options.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::config::hdv::{CarFollowing, HdvProfile};
use crate::config::Config;
use crate::model::road::{Road, EMBEDDED_NET};

/// Why the episode's SUMO input could not be prepared.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// The configured network file does not exist.
    #[error("net file {0} does not exist")]
    MissingNet(PathBuf),
    /// A file or the temporary directory could not be written.
    #[error("cannot write SUMO input {path}: {cause}")]
    Write {
        /// The file or directory.
        path: PathBuf,
        /// The operating system's reason.
        cause: std::io::Error,
    },
}

/// SUMO vehicle types `hdv` and `cav` from the configured IDM parameters and the HDV driver
/// profile (`[hdv]`).
///
/// Both are 5 m × 2 m with a 35 m/s maximum; speedFactor 1 and speedDev 0 so that the desired
/// speed is exactly the one the demand draws (SUMO's default would randomise it). A profile
/// with per-driver draws makes `hdv` a `vTypeDistribution` of driver types `hdv.0`, `hdv.1`, …
/// (drawn from the episode's seed), from which SUMO gives each HDV one. `lane_width` (m, the
/// network's) sets the CAV type's lateral speed on SUMO versions that cap it
/// ([`cav_lateral_speed`]).
pub fn vehicle_types(config: &Config, lane_width: f64) -> String {
    let profile = config
        .hdv
        .resolved()
        .expect("a validated configuration names a known profile");
    let hdv = match profile.draws.is_empty() {
        true => vtype_line(&hdv_attributes(config, &profile, "hdv")),
        false => driver_types(config, &profile),
    };
    let mut cav_attributes = base_attributes(config, "cav", "0,200,0");
    for (k, v) in cav_lateral_speed(config, lane_width) {
        set(&mut cav_attributes, k, &v);
    }
    let cav = vtype_line(&cav_attributes);
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- Vehicle types of the merge scenario (written by bkpbs from its configuration). -->\n<additional>\n{hdv}{cav}</additional>\n"
    )
}

/// The CAV type's lateral speed limits on a SUMO that caps a lane change's lateral speed
/// ([`super::version::caps_lane_change_lateral_speed`]): `maxSpeedLat` and
/// `lcMaxSpeedLatStanding` one lane width per `--lanechange.duration`, so a commanded lane
/// change crosses its lane in that time at any speed, standing included, as on SUMO 1.15 and as
/// the planner's motion primitives model it. With SUMO's defaults (1 m/s + the speed) a merge
/// from standstill took 4.5 s instead of 1 s, half in either lane; a higher `maxSpeedLat` makes
/// that SUMO move faster than one lane per duration. HDV types keep the defaults: they are
/// SUMO's own drivers, as each version has them.
fn cav_lateral_speed(config: &Config, lane_width: f64) -> Vec<(&'static str, String)> {
    if !super::version::caps_lane_change_lateral_speed() {
        return Vec::new();
    }
    let v = (lane_width / config.scenario.lane_change_duration).to_string();
    vec![("maxSpeedLat", v.clone()), ("lcMaxSpeedLatStanding", v)]
}

/// Random stream of the drivers' drawn parameters.
pub const DRIVER_STREAM: u64 = 5;

/// Attributes in SUMO's order of the vType line.
type Attributes = Vec<(String, String)>;

/// The IDM type of the configuration (`[idm]`, `[scenario]`), as both kinds start.
fn base_attributes(config: &Config, id: &str, color: &str) -> Attributes {
    let s = &config.scenario;
    let i = &config.idm;
    [
        ("id", id.to_string()),
        ("vClass", "passenger".into()),
        ("length", s.vehicle_length.to_string()),
        ("width", s.vehicle_width.to_string()),
        ("minGap", i.min_gap.to_string()),
        ("maxSpeed", s.v_max.to_string()),
        ("accel", i.accel.to_string()),
        ("decel", i.decel.to_string()),
        ("emergencyDecel", i.max_decel.to_string()),
        ("tau", i.time_headway.to_string()),
        ("delta", i.delta.to_string()),
        ("carFollowModel", "IDM".into()),
        ("laneChangeModel", "LC2013".into()),
        ("speedFactor", "1".into()),
        ("speedDev", "0".into()),
        ("sigma", "0".into()),
        ("color", color.into()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

/// The HDV type of a profile: its model, then its own attributes over the derived ones.
fn hdv_attributes(config: &Config, profile: &HdvProfile, id: &str) -> Attributes {
    let mut a = base_attributes(config, id, "0,90,255");
    if profile.car_following == CarFollowing::Krauss {
        a.retain(|(k, _)| k != "delta");
    }
    set(&mut a, "carFollowModel", profile.car_following.sumo_name());
    for (k, v) in &profile.attributes {
        set(&mut a, k, v);
    }
    a
}

/// Replaces attribute `key`, or appends it before the colour.
fn set(a: &mut Attributes, key: &str, value: &str) {
    match a.iter_mut().find(|(k, _)| k == key) {
        Some(slot) => slot.1 = value.to_string(),
        None => {
            let at = a.len() - 1;
            a.insert(at, (key.to_string(), value.to_string()));
        }
    }
}

fn vtype_line(a: &Attributes) -> String {
    // Values are checked where they are configured; escaped here all the same, so nothing
    // written into SUMO's XML can end an attribute.
    let attrs: Vec<String> = a
        .iter()
        .map(|(k, v)| format!("{k}=\"{}\"", xml_escape(v)))
        .collect();
    format!("    <vType {}/>\n", attrs.join(" "))
}

/// `text` with XML's five special characters escaped.
fn xml_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// `hdv` as a distribution of `driver_types` types, each with its drawn attributes (see
/// [`driver_type_draws`]), equally likely.
fn driver_types(config: &Config, profile: &HdvProfile) -> String {
    let mut out = String::from("    <vTypeDistribution id=\"hdv\">\n");
    for (k, draws) in driver_type_draws(config).iter().enumerate() {
        let mut a = hdv_attributes(config, profile, &format!("hdv.{k}"));
        for (key, v) in draws {
            set(&mut a, key, &format!("{v:.3}"));
        }
        // The hardest braking must stay at least the comfortable one.
        let decel = draws.get("decel").copied().unwrap_or(0.0);
        if decel > config.idm.max_decel {
            set(&mut a, "emergencyDecel", &format!("{decel:.3}"));
        }
        set(&mut a, "probability", "1");
        out.push_str("    ");
        out.push_str(&vtype_line(&a));
    }
    out.push_str("    </vTypeDistribution>\n");
    out
}

/// The attributes each driver type of the configuration's profile draws (type `hdv.k` is entry
/// k), uniformly in the profile's ranges from the episode's seed, rounded to 3 decimals as
/// written; empty for a profile without draws.
pub fn driver_type_draws(config: &Config) -> Vec<BTreeMap<String, f64>> {
    let Ok(profile) = config.hdv.resolved() else {
        return Vec::new();
    };
    if profile.draws.is_empty() {
        return Vec::new();
    }
    let mut rng = ChaCha8Rng::seed_from_u64(config.scenario.seed);
    rng.set_stream(DRIVER_STREAM);
    (0..profile.driver_types)
        .map(|_| {
            profile
                .draws
                .iter()
                .map(|(key, [low, high])| {
                    let v = if high > low {
                        rng.gen_range(*low..=*high)
                    } else {
                        *low
                    };
                    (key.clone(), (v * 1000.0).round() / 1000.0)
                })
                .collect()
        })
        .collect()
}

/// Prefix of an episode's input directory in the temporary directory: `bkpbs-episode-<pid>-…`.
pub const INPUT_DIR_PREFIX: &str = "bkpbs-episode-";

/// The files of one episode, kept in a directory that lives as long as this value.
pub struct EpisodeInput {
    _dir: tempfile::TempDir,
    /// The network file: the configured one, or the embedded network written out.
    pub net: PathBuf,
    /// The vehicle types (`vtypes.add.xml`), see [`vehicle_types`].
    pub vehicle_types: PathBuf,
    /// The routes and demand flows (`routes.rou.xml`).
    pub routes: PathBuf,
}

impl EpisodeInput {
    /// Writes the network (unless the config names one), vehicle types and the routes of
    /// `road` (the network's frame).
    pub fn write(config: &Config, road: &Road) -> Result<Self, InputError> {
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
        let vehicle_types = put("vtypes.add.xml", &vehicle_types(config, road.lane_width))?;
        let routes = put("routes.rou.xml", &routes_xml(road))?;
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
    let mut args: Vec<String> = vec![
        program(config.sumo.gui),
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
    args.extend(gui_options(config));
    args.extend(config.sumo.extra_args.iter().cloned());
    args
}

/// What sumo-gui needs when `sumo.gui` shows the episode: start at once, close at the end, and
/// pause each step (real time by default); nothing otherwise.
pub fn gui_options(config: &Config) -> Vec<String> {
    if !config.sumo.gui {
        return Vec::new();
    }
    let delay = (config.sumo.gui_delay_ms).unwrap_or(config.scenario.dt * 1000.0);
    [
        ("--start", "true".to_string()),
        ("--quit-on-end", "true".to_string()),
        ("--delay", format!("{delay}")),
    ]
    .into_iter()
    .flat_map(|(k, v)| [k.to_string(), v])
    .collect()
}

/// The program that shows an episode (`sumo.gui`); `Simulation::start` drives it through
/// libtraci when a command line starts with it.
pub const GUI_PROGRAM: &str = "sumo-gui";

/// The program of a command line: `sumo` (a name libsumo ignores) or [`gui_program`].
pub fn program(gui: bool) -> String {
    if gui {
        gui_program()
    } else {
        "sumo".into()
    }
}

/// The sumo-gui to start: the one beside the SUMO bkpbs was built against when that is not
/// Debian's system SUMO, else the first on `PATH`.
pub fn gui_program() -> String {
    super::version::BUILT_HOME
        .map(|home| std::path::Path::new(home).join("bin").join(GUI_PROGRAM))
        .filter(|p| p.is_file())
        .map_or_else(|| GUI_PROGRAM.into(), |p| p.display().to_string())
}

/// Why sumo-gui cannot be shown here, if it cannot: no display, an X display nobody answers
/// at (sumo-gui would die, and libtraci retry its port for a minute), or no sumo-gui.
pub fn gui_unavailable() -> Option<String> {
    let var = |v: &str| std::env::var(v).ok().filter(|d| !d.is_empty());
    let (display, wayland) = (var("DISPLAY"), var("WAYLAND_DISPLAY"));
    if display.is_none() && wayland.is_none() {
        return Some(
            "no display for sumo-gui (DISPLAY is not set); on a machine without one run under a \
             virtual X server: xvfb-run -a bkpbs episode --gui …"
                .into(),
        );
    }
    if let (Some(d), None) = (&display, &wayland) {
        if !x_server_answers(d) {
            return Some(format!(
                "no X server answers at DISPLAY={d} for sumo-gui; start one, or run under a \
                 virtual X server: xvfb-run -a bkpbs episode --gui …"
            ));
        }
    }
    let on_path = gui_program() != GUI_PROGRAM
        || std::env::var_os("PATH").is_some_and(|path| {
            std::env::split_paths(&path).any(|dir| dir.join(GUI_PROGRAM).is_file())
        });
    (!on_path).then(|| format!("{GUI_PROGRAM} is not installed (Debian: apt-get install sumo)"))
}

/// Whether something listens where X display `display` (`[host]:N[.S]`) lives: the local
/// socket `/tmp/.X11-unix/XN` (or its abstract twin) for a local display, TCP port 6000 + N
/// for a remote one. A display name of another form is given the benefit of the doubt.
pub fn x_server_answers(display: &str) -> bool {
    use std::os::linux::net::SocketAddrExt;
    let Some((host, rest)) = display.rsplit_once(':') else {
        return true;
    };
    let Ok(n) = rest.split('.').next().unwrap_or("").parse::<u16>() else {
        return true;
    };
    if host.is_empty() || host == "unix" {
        let path = format!("/tmp/.X11-unix/X{n}");
        let abstract_name = std::os::unix::net::SocketAddr::from_abstract_name(path.as_bytes());
        return std::os::unix::net::UnixStream::connect(&path).is_ok()
            || abstract_name
                .and_then(|a| std::os::unix::net::UnixStream::connect_addr(&a))
                .is_ok();
    }
    let Some(port) = n.checked_add(6000) else {
        return false;
    };
    use std::net::ToSocketAddrs;
    let timeout = std::time::Duration::from_secs(2);
    (host, port).to_socket_addrs().is_ok_and(|mut addrs| {
        addrs.any(|a| std::net::TcpStream::connect_timeout(&a, timeout).is_ok())
    })
}

/// SUMO route file with one route per entry of `road`, named after it (vehicles are added at
/// run time by entry control).
pub fn routes_xml(road: &Road) -> String {
    let mut xml = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- the merge scenario's routes, one per entry -->\n<routes>\n",
    );
    let mut route = |id: String, edges: &[Arc<str>]| {
        let edges: Vec<&str> = edges.iter().map(|x| &**x).collect();
        xml += &format!("    <route id=\"{id}\" edges=\"{}\"/>\n", edges.join(" "));
    };
    for (k, e) in road.entries.iter().enumerate() {
        route(e.name.clone(), &e.route);
        for x in 0..road.exits.len() {
            if let Some(edges) = road.exit_route(k, x) {
                route(road.exit_route_name(k, x), &edges);
            }
        }
    }
    xml + "</routes>\n"
}
