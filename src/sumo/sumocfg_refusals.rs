//! What a user's SUMO configuration may not ask of an episode: nothing in it reaches outside the
//! episode. A TraCI server (`remote-port`) would listen on every network interface while
//! libsumo runs the simulation in-process, and then wait for a client that never comes; an
//! `output-prefix` moves every output, bkpbs's own included (`../../` put its tripinfo at the
//! file system's root); saving the configuration or the simulation's state is a run of its own
//! (libsumo answers `save-configuration` with "A network was not yet constructed"); an output
//! named `host:port` is a network connection SUMO opens. Each is refused in one line naming the
//! option and the file, before SUMO starts (`SumoConfig::read`).

/// Options that make SUMO a TraCI server, with their values that leave it off.
const SERVER: [(&str, &str); 2] = [("remote-port", "0"), ("num-clients", "1")];

/// Options that make SUMO save its configuration (or a template or schema of it) instead of
/// running, with their synonyms.
const SAVE_CONFIGURATION: [&str; 5] = [
    "save-configuration",
    "C",
    "save-config",
    "save-template",
    "save-schema",
];

/// Output options whose names do not end in `-output` or `-dump` (SUMO 1.15's synonyms and
/// its report logs).
const OTHER_OUTPUTS: [&str; 10] = [
    "ndump",
    "netstate",
    "summary",
    "tripinfo",
    "vehroutes",
    "personroutes",
    "log",
    "l",
    "log-file",
    "message-log",
];

/// The first of a configuration's `options` (name, value) that reaches outside the episode,
/// named with its value, and what to do instead; none if nothing does.
pub fn first_refusal(options: &[(String, String)]) -> Option<String> {
    options.iter().find_map(|(name, value)| {
        let why = refusal(name, value.trim())?;
        Some(format!("it sets {name} = '{value}': {why}"))
    })
}

/// Why option `name` of value `value` is refused, if it is.
fn refusal(name: &str, value: &str) -> Option<&'static str> {
    if SERVER.iter().any(|&(k, off)| k == name && value != off) {
        return Some(
            "SUMO would open a TraCI server on a network port and wait for clients, but bkpbs \
             runs SUMO in its own process; remove it",
        );
    }
    if value.is_empty() {
        return None;
    }
    if name == "output-prefix" {
        return Some(
            "it would move every output of the episode, bkpbs's own included; write the prefix \
             into your output file names instead",
        );
    }
    if SAVE_CONFIGURATION.contains(&name) {
        return Some("SUMO would save a configuration instead of running it; remove it");
    }
    if name.starts_with("save-state.") {
        return Some(
            "an episode saves no simulation state (run `sumo -c` for that); remove the \
             save-state options",
        );
    }
    if is_output(name) && is_socket(value) {
        return Some(
            "SUMO would send this output to a network address; name a file (relative to the \
             configuration) instead",
        );
    }
    None
}

/// Whether `name` is an option naming a file SUMO writes: an output, a log, or a device's
/// file (`device.ssm.file`).
fn is_output(name: &str) -> bool {
    name.ends_with("-output")
        || name.ends_with("-dump")
        || name == "error-log"
        || OTHER_OUTPUTS.contains(&name)
        || (name.starts_with("device.") && name.ends_with(".file"))
}

/// Whether SUMO takes the file name `value` for a `host:port` network address (its
/// `FileHelpers::isSocket`: a colon past the second character, or an IPv6 address in
/// brackets), as it does for every output.
fn is_socket(value: &str) -> bool {
    value.starts_with('[') || value.find(':').is_some_and(|k| k > 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(name: &str, value: &str) -> Option<String> {
        first_refusal(&[(name.to_string(), value.to_string())])
    }

    fn refused(name: &str, value: &str, words: &[&str]) {
        let e = check(name, value).unwrap_or_else(|| panic!("{name} = {value} runs"));
        for w in words {
            assert!(e.contains(w), "'{w}' not in: {e}");
        }
    }

    #[test]
    fn what_reaches_outside_is_refused_naming_the_option() {
        refused(
            "remote-port",
            "8813",
            &["remote-port = '8813'", "TraCI server"],
        );
        refused("num-clients", "2", &["num-clients"]);
        refused("output-prefix", "../../", &["output-prefix"]);
        refused("save-configuration", "x.cfg", &["save-configuration"]);
        refused("C", "x.cfg", &["C = 'x.cfg'"]);
        refused("save-state.times", "10", &["save-state.times"]);
        refused("fcd-output", "localhost:9000", &["network address"]);
        refused("error-log", "[::1]:9000", &["error-log"]);
        refused("device.ssm.file", "host:1", &["device.ssm.file"]);
    }

    #[test]
    fn what_stays_inside_runs() {
        for (name, value) in [
            ("remote-port", "0"),
            ("num-clients", "1"),
            ("output-prefix", ""),
            ("fcd-output", "out/fcd.xml"),
            ("begin", "0:10:00"),
            ("tripinfo-output", "C:trips.xml"),
        ] {
            assert_eq!(check(name, value), None, "{name} = {value}");
        }
    }
}
