//! A user's SUMO configuration (`.sumocfg`): the options bkpbs must know before it runs it —
//! the network (to find the merge regions), the step length (the planner's step), the
//! simulated interval — read as SUMO reads them: each option an element with a `value`,
//! anywhere under `<configuration>` (or `<sumoConfiguration>`), file names relative to the configuration's directory.
//! Everything else in it (routes, flows, vehicle types, additional files, the user's own
//! options) SUMO reads itself, from the file.

use std::path::{Path, PathBuf};

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
    /// An unreadable file, no `<configuration>`, no `net-file`, or a time that is no number.
    pub fn read(path: &Path) -> Result<SumoConfig, SumoConfigError> {
        let bad = |what: String| SumoConfigError::Content {
            path: path.to_path_buf(),
            what,
        };
        let text = read_config(path)?;
        let doc = parse(path, &text)?;
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
        Ok(SumoConfig {
            path: path.to_path_buf(),
            net: dir.join(net),
            step_length: time(&["step-length"])?.unwrap_or(1.0),
            begin: time(&["begin", "b"])?.unwrap_or(0.0),
            end: time(&["end", "e"])?,
        })
    }

    /// The files the configuration at `path` names in its options — its network, routes,
    /// additional files and any other option whose value (or a comma-separated part of it) is
    /// an existing file, relative to the configuration's directory —, the configuration
    /// first, each once. What a copy of the scenario on another machine takes along; outputs
    /// (`*-output`) are left out, and files those files name in turn are not followed.
    ///
    /// # Errors
    /// An unreadable file or one that is no SUMO configuration.
    pub fn named_files(path: &Path) -> Result<Vec<PathBuf>, SumoConfigError> {
        let text = read_config(path)?;
        let doc = parse(path, &text)?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut files = vec![path.to_path_buf()];
        let values = doc
            .descendants()
            .filter(|n| !n.tag_name().name().ends_with("-output"))
            .filter_map(|n| n.attribute("value"));
        for part in values.flat_map(|v| v.split(',')).map(str::trim) {
            let file = dir.join(part);
            if !part.is_empty() && file.is_file() && !files.contains(&file) {
                files.push(file);
            }
        }
        Ok(files)
    }

    /// The steps of `dt` of the interval of the configuration at `path`: an episode's default
    /// length. `None` for a file that cannot be read (the episode reports it when it starts)
    /// or that sets no end.
    pub fn steps_of(path: &Path, dt: f64) -> Option<u32> {
        SumoConfig::read(path).ok()?.steps(dt)
    }

    /// Steps of `dt` from its begin to its end, if it has an end.
    pub fn steps(&self, dt: f64) -> Option<u32> {
        self.end
            .map(|end| ((end - self.begin) / dt).round().max(0.0) as u32)
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

/// The text of the configuration at `path`.
fn read_config(path: &Path) -> Result<String, SumoConfigError> {
    read_text(path, FileKind::Config).map_err(|cause| SumoConfigError::Read {
        path: path.to_path_buf(),
        cause,
    })
}

/// The configuration `text` (of the file at `path`) as an XML document with one of SUMO's
/// configuration roots.
fn parse<'t>(path: &Path, text: &'t str) -> Result<roxmltree::Document<'t>, SumoConfigError> {
    let bad = |what: String| SumoConfigError::Content {
        path: path.to_path_buf(),
        what,
    };
    let doc = roxmltree::Document::parse(text).map_err(|e| bad(e.to_string()))?;
    // SUMO writes `<sumoConfiguration>` (the shipped games of 1.28), older versions
    // `<configuration>`; it reads both.
    let root = doc.root_element().tag_name().name();
    if !ROOTS.contains(&root) {
        return Err(bad(format!(
            "its root element is <{root}>, not <configuration> or <sumoConfiguration>"
        )));
    }
    Ok(doc)
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
        assert_eq!(c.steps(0.2), Some(8700));
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

    /// Every file the options name, relative to the configuration, once; not the outputs,
    /// nor values that are no file.
    #[test]
    fn named_files_are_the_inputs_it_names() {
        let d = tempfile::tempdir().unwrap();
        std::fs::create_dir(d.path().join("nets")).unwrap();
        for f in [
            "nets/a.net.xml",
            "r1.rou.xml",
            "r2.rou.xml",
            "add.xml",
            "out.xml",
        ] {
            std::fs::write(d.path().join(f), "").unwrap();
        }
        let p = write(
            d.path(),
            r#"<input><net-file value="nets/a.net.xml"/><route-files value="r1.rou.xml, r2.rou.xml"/>
               <additional-files value="add.xml,missing.xml,nets/a.net.xml"/></input>
               <output><summary-output value="out.xml"/></output><begin value="0"/>"#,
        );
        let names = SumoConfig::named_files(&p).unwrap();
        let want: Vec<PathBuf> = [
            "s.sumocfg",
            "nets/a.net.xml",
            "r1.rou.xml",
            "r2.rou.xml",
            "add.xml",
        ]
        .iter()
        .map(|f| d.path().join(f))
        .collect();
        assert_eq!(names, want);
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
