//! An episode of a campaign run on a machine that shares no files with the campaign (a Ray
//! cluster without shared storage): its inputs travel to it and its results come back, both as
//! bytes, through the scheduler.
//!
//! Where the campaign runs, [`inputs`] lists the files the episode's configuration names — its
//! scenario's `.sumocfg` and every file that names, the network, the model, calibration and
//! policy files, SUMO's additional files — for the scheduler to ship. On the node, [`run`]
//! writes those bytes under a private directory, at their paths below it (so that a
//! configuration's relative names still meet), runs the episode against the copies
//! ([`relocate`]) and returns the cell's files. Back where the campaign runs, [`store`] puts
//! them into the cell directory. The cell then holds what the local runner writes, byte for
//! byte; its `settings.toml` records the campaign's configuration (its paths as given), not the
//! copies'.

use std::path::{Component, Path, PathBuf};

use super::worker::{self, Request, DONE_FILE, ERROR_FILE};
use crate::config::Config;
use crate::io::{self, WriteError};

/// One file of an episode and its bytes: an input by its absolute path where the campaign
/// runs, a result by its path in the cell directory.
pub type File = (PathBuf, Vec<u8>);

/// Why an episode's files could not be put into, or read from, a directory.
#[derive(Debug, thiserror::Error)]
pub enum PortableError {
    /// A file could not be written.
    #[error(transparent)]
    Write(#[from] WriteError),
    /// A file could not be read.
    #[error("cannot read {path}: {cause}")]
    Read {
        /// The file or directory.
        path: PathBuf,
        /// The operating system's reason.
        cause: std::io::Error,
    },
    /// A file's name cannot be placed where it belongs.
    #[error("episode file '{path}': {what}")]
    Name {
        /// The name as given.
        path: PathBuf,
        /// What is wrong with it.
        what: &'static str,
    },
}

/// The existing files `config` names, as absolute paths (relative ones resolved against
/// `base`, the campaign's working directory), sorted, each once. A file that does not exist
/// here is left out: the episode reports it where it runs, as it would here.
pub fn inputs(config: &Config, base: &Path) -> Vec<PathBuf> {
    let mut named: Vec<PathBuf> = Vec::new();
    if let Some(cfg) = &config.scenario.sumocfg {
        let cfg = absolute(base, cfg);
        match crate::sumo::scenario_files::named_files(&cfg) {
            Ok(files) => named.extend(files.into_iter().map(|(_, path)| path)),
            Err(_) => named.push(cfg),
        }
    }
    named.extend(
        super::provenance::named_inputs(config)
            .into_iter()
            .map(|(_, f)| f),
    );
    let mut files: Vec<PathBuf> = named
        .iter()
        .map(|f| absolute(base, f))
        .filter(|f| f.is_file())
        .collect();
    files.sort();
    files.dedup();
    files
}

/// `config` with every file it names moved below `root`, at its absolute path (relative ones
/// resolved against `base`): where [`run`] writes the copies of the [`inputs`].
pub fn relocate(config: &Config, base: &Path, root: &Path) -> Config {
    let at = |p: &mut PathBuf| *p = mirror(root, &absolute(base, p));
    let mut c = config.clone();
    let (s, p) = (&mut c.scenario, &mut c.predictor);
    let single = [
        &mut s.sumocfg,
        &mut s.net_file,
        &mut p.conditioned_model,
        &mut p.unconditioned_model,
        &mut p.calibration,
        &mut p.calibrations,
        &mut c.rl.policy,
    ];
    single.into_iter().flatten().for_each(at);
    c.sumo.additional_files.iter_mut().for_each(at);
    c
}

/// Runs `req`'s episode in this process against `inputs` (the [`inputs`] listed where the
/// campaign runs, whose working directory is `base`), copied below `scratch`, a private
/// directory the caller removes afterwards; returns the cell's files (paths relative to it).
///
/// # Errors
/// The episode failed (the message `error.txt` records), or an input could not be written
/// or a result read.
pub fn run(
    req: &Request,
    base: &Path,
    inputs: &[File],
    scratch: &Path,
) -> Result<Vec<File>, String> {
    let root = scratch.join("inputs");
    for (path, bytes) in inputs {
        if !path.is_absolute() || !plain(path.strip_prefix("/").unwrap_or(path)) {
            return Err(format!(
                "input '{}' is no absolute plain path",
                path.display()
            ));
        }
        io::write_atomic(&mirror(&root, path), bytes).map_err(|e| e.to_string())?;
    }
    let here = Request {
        position: req.position,
        planner: req.planner.clone(),
        dir: scratch.join("cell"),
        config: relocate(&req.config, base, &root),
    };
    worker::run_cell_recording(&here, &req.config)?;
    let mut files = Vec::new();
    read_tree(&here.dir, Path::new(""), &mut files).map_err(|e| e.to_string())?;
    Ok(files)
}

/// Puts an episode's files, as [`run`] returned them, into its cell directory `dir`: they
/// replace the cell's earlier files as one set (its `error.txt`, files the set lacks and its
/// subdirectories go), `episode.csv` last, as the episode itself writes them.
///
/// # Errors
/// A name that is not a plain relative path, a set without `episode.csv`, or a file that
/// cannot be written.
pub fn store(dir: &Path, files: &[File]) -> Result<(), PortableError> {
    let bad = |path: &Path, what| PortableError::Name {
        path: path.to_path_buf(),
        what,
    };
    let mut top: Vec<(&str, Option<&[u8]>)> = Vec::new();
    let mut nested = Vec::new();
    for (name, bytes) in files {
        if name.is_absolute() || !plain(name) {
            return Err(bad(name, "not a plain relative path"));
        }
        match name.to_str() {
            Some(n) if !n.contains('/') => top.push((n, Some(bytes))),
            Some(_) => nested.push((name, bytes)),
            None => return Err(bad(name, "not UTF-8")),
        }
    }
    let Some(marker) = top.iter().position(|(n, _)| *n == DONE_FILE) else {
        return Err(bad(
            Path::new(DONE_FILE),
            "missing from the episode's files",
        ));
    };
    let done = top.remove(marker);
    let old = clear(dir)?;
    let gone: Vec<&str> = old
        .iter()
        .map(String::as_str)
        .filter(|n| !top.iter().any(|(t, _)| t == n))
        .collect();
    top.extend(gone.into_iter().map(|n| (n, None)));
    top.push(done);
    for (name, bytes) in nested {
        io::write_atomic(&dir.join(name), bytes)?;
    }
    io::replace_together(dir, &top)?;
    Ok(())
}

/// Readies `dir` for a new set of files: removes its `episode.csv` first (from here on the cell
/// reads as unfinished, as when a local worker starts it), its `error.txt` and subdirectories,
/// and returns the names of its other files (not the temporaries of a writer at work).
fn clear(dir: &Path) -> Result<Vec<String>, PortableError> {
    let read = |cause| PortableError::Read {
        path: dir.to_path_buf(),
        cause,
    };
    match std::fs::remove_file(dir.join(DONE_FILE)) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            let path = dir.join(DONE_FILE);
            return Err(WriteError { path, cause: e }.into());
        }
        _ => {}
    }
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(read(e)),
    };
    let mut names = Vec::new();
    for entry in entries {
        let entry = entry.map_err(read)?;
        let (path, name) = (entry.path(), entry.file_name());
        let name = name.to_string_lossy();
        let removed = if path.is_dir() {
            std::fs::remove_dir_all(&path)
        } else if name == ERROR_FILE {
            std::fs::remove_file(&path)
        } else {
            if !name.starts_with(io::TEMPORARY_PREFIX) {
                names.push(name.into_owned());
            }
            Ok(())
        };
        removed.map_err(|cause| WriteError { path, cause })?;
    }
    Ok(names)
}

/// Every file below `dir` (its path from `dir` joined to `prefix`), in name order.
fn read_tree(dir: &Path, prefix: &Path, files: &mut Vec<File>) -> Result<(), PortableError> {
    let read = |path: &Path, cause| PortableError::Read {
        path: path.to_path_buf(),
        cause,
    };
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .and_then(|d| d.collect::<Result<Vec<_>, _>>())
        .map_err(|e| read(dir, e))?;
    entries.sort_by_key(|e| e.file_name());
    for entry in entries {
        let (path, name) = (entry.path(), prefix.join(entry.file_name()));
        if path.is_dir() {
            read_tree(&path, &name, files)?;
        } else {
            let bytes = std::fs::read(&path).map_err(|e| read(&path, e))?;
            files.push((name, bytes));
        }
    }
    Ok(())
}

/// `path` made absolute against `base`, with `.` and `..` resolved by name (a copy below
/// another root has no symbolic links to follow).
fn absolute(base: &Path, path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in base.join(path).components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// Where the copy of the file at the absolute `path` lies below `root`.
fn mirror(root: &Path, path: &Path) -> PathBuf {
    root.join(path.strip_prefix("/").unwrap_or(path))
}

/// Does `path` consist of names only (no root, `.` or `..`), and of at least one?
fn plain(path: &Path) -> bool {
    path.components().next().is_some()
        && path.components().all(|c| matches!(c, Component::Normal(_)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(path: &Path, text: &str) {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }

    /// A scenario whose configuration names files beside it and above it (`../`), given by a
    /// relative path: every file is listed once, and the relocated configuration finds the
    /// copies where [`run`] writes them.
    #[test]
    fn inputs_and_their_copies_meet() {
        let d = tempfile::tempdir().unwrap();
        let base = d.path().join("work");
        touch(&base.join("nets/n.net.xml"), "net");
        touch(&base.join("scen/r.rou.xml"), "routes");
        touch(
            &base.join("scen/a.sumocfg"),
            r#"<configuration><net-file value="../nets/n.net.xml"/>
               <route-files value="r.rou.xml,../nets/n.net.xml"/></configuration>"#,
        );
        touch(&base.join("m/sumo-safe/calibration.json"), "{}");
        let mut c = Config::default();
        c.scenario.sumocfg = Some("./scen/a.sumocfg".into());
        c.predictor.calibrations = Some("m".into());
        c.sumo.additional_files = vec!["missing.add.xml".into()];
        let files = inputs(&c, &base);
        let want: Vec<PathBuf> = [
            "m/sumo-safe/calibration.json",
            "nets/n.net.xml",
            "scen/a.sumocfg",
            "scen/r.rou.xml",
        ]
        .iter()
        .map(|f| base.join(f))
        .collect();
        assert_eq!(files, want);
        let root = d.path().join("node");
        let moved = relocate(&c, &base, &root);
        let cfg = moved.scenario.sumocfg.unwrap();
        assert_eq!(cfg, mirror(&root, &base.join("scen/a.sumocfg")));
        assert_eq!(
            moved.predictor.calibrations.unwrap(),
            mirror(&root, &base.join("m"))
        );
        for f in &files {
            touch(&mirror(&root, f), "copy");
        }
        // SUMO resolves `../nets` against the copy's directory.
        assert!(cfg.parent().unwrap().join("../nets/n.net.xml").is_file());
    }

    /// Every path the configuration holds is relocated: a new one must be added to
    /// [`relocate`] (and to [`inputs`]) and here.
    #[test]
    fn every_path_setting_is_relocated() {
        let sources = [
            include_str!("../config/scenario.rs"),
            include_str!("../config/planning.rs"),
            include_str!("../config/simulator.rs"),
            include_str!("../config/mod.rs"),
            include_str!("../config/hdv.rs"),
            include_str!("../config/drivers.rs"),
            include_str!("../config/rules.rs"),
        ];
        let mut fields: Vec<&str> = sources
            .iter()
            .flat_map(|s| s.lines())
            .filter(|l| l.trim_start().starts_with("pub ") && l.contains("PathBuf"))
            .filter_map(|l| l.trim_start()[4..].split(':').next())
            .collect();
        fields.sort();
        let relocated = [
            "additional_files",
            "calibration",
            "calibrations",
            "conditioned_model",
            "net_file",
            "policy",
            "sumocfg",
            "unconditioned_model",
        ];
        assert_eq!(fields, relocated);
    }

    /// Stored files replace the cell's earlier set: its failure note, files and subdirectories
    /// the new set lacks go; a writer's temporary stays.
    #[test]
    fn store_replaces_the_cell_s_files() {
        let d = tempfile::tempdir().unwrap();
        let cell = d.path().join("cell");
        for f in [
            "error.txt",
            "sumo.log",
            "trajectories/r/old.csv",
            ".bkpbs-1-x.tmp",
        ] {
            touch(&cell.join(f), "old");
        }
        let file = |n: &str| (PathBuf::from(n), n.as_bytes().to_vec());
        let files = [
            file("episode.csv"),
            file("trajectories/m/t.csv"),
            file("vehicles.csv"),
        ];
        store(&cell, &files).unwrap();
        let mut found = Vec::new();
        read_tree(&cell, Path::new(""), &mut found).unwrap();
        let want = [
            file(".bkpbs-1-x.tmp"),
            file("episode.csv"),
            file("trajectories/m/t.csv"),
        ];
        let mut want = want.to_vec();
        want[0].1 = b"old".to_vec();
        want.push(file("vehicles.csv"));
        assert_eq!(found, want);
        for bad in ["../x", "/etc/x", "a/../b", ""] {
            let e = store(&cell, &[file("episode.csv"), file(bad)]).unwrap_err();
            assert!(e.to_string().contains("plain relative path"), "{bad}: {e}");
        }
        let e = store(&cell, &[file("vehicles.csv")]).unwrap_err();
        assert!(e.to_string().contains("episode.csv"), "{e}");
    }
}
