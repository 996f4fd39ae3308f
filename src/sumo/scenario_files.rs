//! The files a SUMO configuration names — itself, its `net-file`, `route-files` and
//! `additional-files`, and any other option whose value is an existing file — and their
//! SHA-256 digests: what a campaign over scenarios records per cell, so that a cell whose
//! scenario changed (an edited route file, another copy of the scenario found from another
//! working directory) runs again instead of counting as done; and what a campaign on a cluster
//! without shared storage ships to the node that runs the cell ([`crate::campaign::portable`]).
//!
//! Outputs (`*-output`) are not inputs; files a named file itself names (an `<include>`, a
//! detector's output) are not followed: SUMO reads them, and the guide says so.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use super::sumocfg::SumoConfigError;
use crate::io::bounded::{open, read_text, FileKind};

/// The options that name input files, with SUMO's short forms.
const INPUTS: [&[&str]; 3] = [
    &["net-file", "n"],
    &["route-files", "r"],
    &["additional-files", "a"],
];

/// Each file the configuration at `cfg` names, as it names it (the configuration itself by
/// its file name), with its path resolved against the configuration's directory.
///
/// # Errors
/// The configuration cannot be read or is no XML.
pub fn named_files(cfg: &Path) -> Result<Vec<(String, PathBuf)>, SumoConfigError> {
    let text = read_text(cfg, FileKind::Config).map_err(|cause| SumoConfigError::Read {
        path: cfg.to_path_buf(),
        cause,
    })?;
    let doc = roxmltree::Document::parse(&text).map_err(|e| SumoConfigError::Content {
        path: cfg.to_path_buf(),
        what: e.to_string(),
    })?;
    let dir = cfg.parent().unwrap_or(Path::new("."));
    let own = cfg.file_name().map_or_else(
        || cfg.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    let mut files = vec![(own, cfg.to_path_buf())];
    let mut add = |name: &str, required: bool| {
        let path = dir.join(name);
        let known = files.iter().any(|(n, _)| n == name);
        if !name.is_empty() && !known && (required || path.is_file()) {
            files.push((name.to_string(), path));
        }
    };
    for node in doc.descendants().filter(|n| n.is_element()) {
        let tag = node.tag_name().name();
        let Some(value) = node.attribute("value") else {
            continue;
        };
        // The inputs SUMO must read, each of them; any other value that is a file here (a
        // vehicle-type file an option names, the gui settings) too; outputs never.
        let required = INPUTS.iter().any(|names| names.contains(&tag));
        if !tag.ends_with("-output") {
            for name in value.split([',', ' ', '\t', '\n']) {
                add(name, required);
            }
        }
    }
    Ok(files)
}

/// The SHA-256 (hex) of every file [`named_files`] lists, by the name the configuration gives
/// it.
///
/// # Errors
/// A file that cannot be read: missing, not a regular file (a FIFO is refused before it is
/// opened, so it cannot block), or larger than a network file may be.
pub fn digests(cfg: &Path) -> Result<BTreeMap<String, String>, SumoConfigError> {
    let mut out = BTreeMap::new();
    for (name, path) in named_files(cfg)? {
        let digest = digest_of(&path).map_err(|cause| SumoConfigError::Content {
            path: cfg.to_path_buf(),
            what: format!("cannot read the file it names, '{name}': {cause}"),
        })?;
        out.insert(name, digest);
    }
    Ok(out)
}

/// The first file whose digest is not the one `recorded`, or that one lists and the other
/// not, as a sentence; `None` when the configuration at `cfg` names the very same files.
///
/// # Errors
/// As [`digests`].
pub fn first_change(
    cfg: &Path,
    recorded: &BTreeMap<String, String>,
) -> Result<Option<String>, SumoConfigError> {
    let now = digests(cfg)?;
    let names = recorded.keys().chain(now.keys());
    Ok(names
        .into_iter()
        .find_map(|name| match (recorded.get(name), now.get(name)) {
            (Some(a), Some(b)) if a == b => None,
            (Some(_), Some(_)) => Some(format!("'{name}' changed")),
            (Some(_), None) => Some(format!("'{name}' is no longer named")),
            _ => Some(format!("'{name}' is new")),
        }))
}

/// The SHA-256 of the regular file at `path`, read as a stream (bounded memory).
pub(crate) fn digest_of(path: &Path) -> std::io::Result<String> {
    let mut file = open(path, FileKind::Network)?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = file.read(&mut buf)?;
        if n == 0 {
            break;
        }
        hasher.update(&buf[..n]);
    }
    Ok(hasher
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(dir: &Path) -> PathBuf {
        std::fs::write(dir.join("a.net.xml"), "<net/>").unwrap();
        std::fs::write(dir.join("a.rou.xml"), "<routes/>").unwrap();
        std::fs::write(dir.join("b.add.xml"), "<additional/>").unwrap();
        let cfg = dir.join("a.sumocfg");
        std::fs::write(
            &cfg,
            r#"<configuration><input><net-file value="a.net.xml"/>
               <route-files value="a.rou.xml"/><additional-files value="b.add.xml, a.rou.xml"/>
               </input></configuration>"#,
        )
        .unwrap();
        cfg
    }

    #[test]
    fn every_named_file_is_digested_and_an_edit_is_named() {
        let d = tempfile::tempdir().unwrap();
        let cfg = scenario(d.path());
        let recorded = digests(&cfg).unwrap();
        let names: Vec<&str> = recorded.keys().map(String::as_str).collect();
        assert_eq!(names, ["a.net.xml", "a.rou.xml", "a.sumocfg", "b.add.xml"]);
        // sha256sum of the 6 bytes "<net/>"
        assert_eq!(
            recorded["a.net.xml"],
            "9d6a064fb2248075588a97f3e7233521dadb5a5eabd1560a849c01b9f4b5c732"
        );
        assert_eq!(first_change(&cfg, &recorded).unwrap(), None);
        std::fs::write(d.path().join("a.rou.xml"), "<routes> </routes>").unwrap();
        assert_eq!(
            first_change(&cfg, &recorded).unwrap().as_deref(),
            Some("'a.rou.xml' changed")
        );
    }

    /// Every file the options name, relative to the configuration, once; not the outputs, nor
    /// values that are no file (a missing input is listed: it is an error to digest).
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
            "v.xml",
        ] {
            std::fs::write(d.path().join(f), "").unwrap();
        }
        let cfg = d.path().join("s.sumocfg");
        std::fs::write(
            &cfg,
            r#"<configuration><input><net-file value="nets/a.net.xml"/>
               <route-files value="r1.rou.xml, r2.rou.xml"/>
               <additional-files value="add.xml,missing.xml,nets/a.net.xml"/></input>
               <output><summary-output value="out.xml"/></output><begin value="0"/>
               <gui-settings-file value="v.xml"/></configuration>"#,
        )
        .unwrap();
        let names: Vec<String> = named_files(&cfg)
            .unwrap()
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        let want = [
            "s.sumocfg",
            "nets/a.net.xml",
            "r1.rou.xml",
            "r2.rou.xml",
            "add.xml",
            "missing.xml",
            "v.xml",
        ];
        assert_eq!(names, want);
    }

    #[test]
    fn a_fifo_or_missing_file_is_refused_naming_it() {
        let d = tempfile::tempdir().unwrap();
        let cfg = scenario(d.path());
        std::fs::remove_file(d.path().join("b.add.xml")).unwrap();
        let e = digests(&cfg).unwrap_err().to_string();
        assert!(
            e.contains("cannot read the file it names, 'b.add.xml'"),
            "{e}"
        );
        let fifo = std::ffi::CString::new(d.path().join("b.add.xml").to_str().unwrap()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(fifo.as_ptr(), 0o600) }, 0);
        let e = digests(&cfg).unwrap_err().to_string();
        assert!(
            e.contains("'b.add.xml'") && e.contains("not a regular file"),
            "{e}"
        );
    }
}
