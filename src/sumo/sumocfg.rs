//! A user's SUMO configuration (`.sumocfg`): the options bkpbs must know before it runs it —
//! the network (to find the merge regions), the step length (the planner's step), the
//! simulated interval — read as SUMO reads them: each option an element with a `value`,
//! anywhere under `<configuration>` (or `<sumoConfiguration>`), file names relative to the configuration's directory.
//! Everything else in it (routes, flows, vehicle types, additional files, the user's own
//! options) SUMO reads itself, from the file; bkpbs keeps a list of every option it sets, to
//! say which of them an episode changes and to refuse those that reach outside it.

use std::path::{Path, PathBuf};

use crate::config::MAX_STEPS;
use crate::io::bounded::{read_text, FileKind};

/// What bkpbs reads of a `.sumocfg`.
#[derive(Debug, Clone, PartialEq)]
pub struct SumoConfig {
    /// The configuration file.
    pub path: PathBuf,
    /// Its `net-file`, resolved against the file's directory.
    pub net: PathBuf,
    /// Its `step-length` (s; SUMO's default 1 s when absent).
    pub step_length: f64,
    /// Its `begin` (s; default 0).
    pub begin: f64,
    /// Its `end` (s), if it sets one.
    pub end: Option<f64>,
    /// Every option it sets, as SUMO reads them (an element with a `value`), in its order:
    /// (name, value).
    pub options: Vec<(String, String)>,
}

/// The root elements of a SUMO configuration file.
const ROOTS: [&str; 2] = ["configuration", "sumoConfiguration"];

/// Why a configuration cannot be run.
#[derive(Debug, thiserror::Error)]
pub enum SumoConfigError {
    /// It could not be read.
    #[error("cannot read SUMO configuration {path}: {cause}")]
    Read {
        /// The configuration file.
        path: PathBuf,
        /// The operating system's reason.
        cause: std::io::Error,
    },
    /// It is not a SUMO configuration bkpbs can run.
    #[error("SUMO configuration {path}: {what}")]
    Content {
        /// The configuration file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

impl SumoConfig {
    /// Reads the configuration at `path`.
    ///
    /// # Errors
    /// An unreadable file, no `<configuration>`, no `net-file`, a time that is no number, or an
    /// option that reaches outside the episode (`sumocfg_refusals`).
    pub fn read(path: &Path) -> Result<SumoConfig, SumoConfigError> {
        let bad = |what: String| SumoConfigError::Content {
            path: path.to_path_buf(),
            what,
        };
        let text = read_text(path, FileKind::Config).map_err(|cause| SumoConfigError::Read {
            path: path.to_path_buf(),
            cause,
        })?;
        let doc = roxmltree::Document::parse(&text).map_err(|e| bad(e.to_string()))?;
        // SUMO writes `<sumoConfiguration>` (the shipped games of 1.28), older versions
        // `<configuration>`; it reads both.
        let root = doc.root_element().tag_name().name();
        if !ROOTS.contains(&root) {
            return Err(bad(format!(
                "its root element is <{root}>, not <configuration> or <sumoConfiguration>"
            )));
        }
        let option = |names: &[&str]| {
            doc.descendants()
                .find(|n| names.iter().any(|k| n.has_tag_name(*k)))
                .and_then(|n| n.attribute("value"))
        };
        let time = |names: &[&str]| -> Result<Option<f64>, SumoConfigError> {
            option(names)
                .map(|v| {
                    parse_time(v).ok_or_else(|| bad(format!("{} '{v}' is not a time", names[0])))
                })
                .transpose()
        };
        let net = option(&["net-file", "n"])
            .ok_or_else(|| bad("no net-file: bkpbs needs the network to find its merges".into()))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let cfg = SumoConfig {
            path: path.to_path_buf(),
            net: dir.join(net),
            step_length: time(&["step-length"])?.unwrap_or(1.0),
            begin: time(&["begin", "b"])?.unwrap_or(0.0),
            // SUMO's -1: no end.
            end: time(&["end", "e"])?.filter(|e| *e >= 0.0),
            options: doc
                .descendants()
                .filter(|n| n.is_element() && *n != doc.root_element())
                .filter_map(|n| {
                    let value = n.attribute("value")?;
                    Some((n.tag_name().name().to_string(), value.to_string()))
                })
                .collect(),
        };
        match super::sumocfg_refusals::first_refusal(&cfg.options) {
            Some(what) => Err(bad(what)),
            None => Ok(cfg),
        }
    }

    /// The value the configuration gives the option of any of `names` (an option's name and
    /// its abbreviations or synonyms), if it sets it.
    pub fn option(&self, names: &[&str]) -> Option<&str> {
        self.options
            .iter()
            .find(|(k, _)| names.contains(&k.as_str()))
            .map(|(_, v)| v.as_str())
    }

    /// An episode's length in steps of `dt`: `given` (`--steps`), else the configuration's
    /// `begin`–`end` interval.
    ///
    /// # Errors
    /// An unreadable configuration, or one that sets no `end` when no length is given: SUMO
    /// would run it until every vehicle has arrived, bkpbs runs a fixed number of steps.
    pub fn episode_steps(path: &Path, dt: f64, given: Option<u32>) -> Result<u32, SumoConfigError> {
        let cfg = SumoConfig::read(path)?;
        match (given, cfg.steps(dt)?) {
            (Some(n), _) | (None, Some(n)) => Ok(n),
            (None, None) => Err(SumoConfigError::Content {
                path: path.to_path_buf(),
                what: "it sets no <end> (SUMO would run until every vehicle has arrived; an \
                       episode runs a fixed number of steps): set <end value=\"…\"/> in it or \
                       give --steps"
                    .into(),
            }),
        }
    }

    /// Steps of `dt` from its begin to its end, if it has an end.
    ///
    /// # Errors
    /// An end not after the begin, or an interval longer than an episode runs
    /// (`scenario.steps`'s bound, [`MAX_STEPS`]): said naming the file, not as a step count of 0 or 4294967295.
    pub fn steps(&self, dt: f64) -> Result<Option<u32>, SumoConfigError> {
        let Some(end) = self.end else {
            return Ok(None);
        };
        let bad = |what: String| SumoConfigError::Content {
            path: self.path.clone(),
            what,
        };
        let steps = ((end - self.begin) / dt).round();
        if steps < 1.0 {
            return Err(bad(format!(
                "its <end> {end} s is not after its <begin> {} s",
                self.begin
            )));
        }
        if steps > f64::from(MAX_STEPS) {
            return Err(bad(format!(
                "its <begin>–<end> interval of {} s is {steps:e} steps of {dt} s, more than an \
                 episode runs ({MAX_STEPS}): give --steps",
                end - self.begin
            )));
        }
        Ok(Some(steps as u32))
    }

    /// Checks that the scenario runs at the planner's step `dt`.
    ///
    /// # Errors
    /// The one line saying both step lengths.
    pub fn check_step(&self, dt: f64) -> Result<(), SumoConfigError> {
        if (self.step_length - dt).abs() > 1e-9 {
            return Err(SumoConfigError::Content {
                path: self.path.clone(),
                what: format!(
                    "step-length {} s, but the planners plan in steps of {dt} s \
                     (scenario.dt): set <step-length value=\"{dt}\"/> in it",
                    self.step_length
                ),
            });
        }
        Ok(())
    }
}

/// A SUMO time value: seconds, or `h:m:s` / `d:h:m:s`.
fn parse_time(v: &str) -> Option<f64> {
    let parts: Vec<f64> = v
        .split(':')
        .map(|p| p.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()?;
    let scales = [86400.0, 3600.0, 60.0, 1.0];
    if parts.len() > scales.len() {
        return None;
    }
    let scales = &scales[scales.len() - parts.len()..];
    Some(parts.iter().zip(scales).map(|(p, s)| p * s).sum())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, body: &str) -> PathBuf {
        let p = dir.join("s.sumocfg");
        std::fs::write(&p, format!("<configuration>{body}</configuration>")).unwrap();
        p
    }

    #[test]
    fn options_as_sumo_reads_them() {
        let d = tempfile::tempdir().unwrap();
        let p = write(
            d.path(),
            r#"<input><net-file value="nets/a.net.xml"/></input>
               <time><begin value="60"/><end value="0:30:00"/><step-length value=".2"/></time>"#,
        );
        let c = SumoConfig::read(&p).unwrap();
        assert_eq!(c.net, d.path().join("nets/a.net.xml"));
        assert_eq!((c.begin, c.end, c.step_length), (60.0, Some(1800.0), 0.2));
        assert_eq!(c.steps(0.2).unwrap(), Some(8700));
        c.check_step(0.2).unwrap();
    }

    #[test]
    fn what_cannot_run_is_one_line() {
        let d = tempfile::tempdir().unwrap();
        let p = write(d.path(), r#"<time><step-length value="0.5"/></time>"#);
        let e = SumoConfig::read(&p).unwrap_err().to_string();
        assert!(e.contains("no net-file"), "{e}");
        let p = write(
            d.path(),
            r#"<net-file value="a.net.xml"/><step-length value="0.5"/>"#,
        );
        let e = SumoConfig::read(&p).unwrap().check_step(0.2).unwrap_err();
        assert!(e.to_string().contains("step-length 0.5 s"), "{e}");
        let p = write(d.path(), r#"<net-file value="a"/><end value="soon"/>"#);
        let e = SumoConfig::read(&p).unwrap_err().to_string();
        assert!(e.contains("end 'soon' is not a time"), "{e}");
        // SUMO's default step is 1 s.
        let p = write(d.path(), r#"<net-file value="a"/>"#);
        assert_eq!(SumoConfig::read(&p).unwrap().step_length, 1.0);
        let p = d.path().join("r.sumocfg");
        std::fs::write(&p, r#"<routes><net-file value="a"/></routes>"#).unwrap();
        let e = SumoConfig::read(&p).unwrap_err().to_string();
        assert!(e.contains("root element is <routes>"), "{e}");
    }

    /// An option that reaches outside the episode is refused naming it and the file.
    #[test]
    fn a_traci_server_is_refused_naming_the_file() {
        let d = tempfile::tempdir().unwrap();
        let p = write(
            d.path(),
            r#"<net-file value="a"/><remote-port value="8813"/>"#,
        );
        let e = SumoConfig::read(&p).unwrap_err().to_string();
        assert!(e.contains("s.sumocfg") && e.contains("remote-port"), "{e}");
    }

    /// The root newer SUMO writes (the games shipped with 1.28 have it).
    #[test]
    fn a_sumo_configuration_root_is_read_too() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("s.sumocfg");
        let body = r#"<input><net-file value="a.net.xml"/></input>"#;
        std::fs::write(&p, format!("<sumoConfiguration>{body}</sumoConfiguration>")).unwrap();
        assert_eq!(
            SumoConfig::read(&p).unwrap().net,
            d.path().join("a.net.xml")
        );
    }
}
