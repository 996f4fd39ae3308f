//! Files written whole or not at all: a temporary file in the same directory, synced, then
//! renamed over the target. A crash or a kill never leaves a half-written result, and an
//! earlier result stays until it is replaced whole. The lowest layer: results, model files and
//! data sets all go through it. [`interrupt`]: stop signals as requests, so that a run
//! interrupted by them tidies up, and [`watchdog`] ends one that is stuck inside SUMO.
//! [`bounded`]: every file read, read with a bound.

pub mod bounded;
pub mod build;
pub mod child;
pub mod cores;
pub mod interrupt;
pub mod progress;
pub mod watchdog;

use std::io::Write;
use std::path::{Path, PathBuf};

/// Why results could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {cause}")]
pub struct WriteError {
    /// The file or directory that could not be written.
    pub path: PathBuf,
    /// The operating system's reason.
    pub cause: std::io::Error,
}

/// Creates directory `dir` if needed and checks that files can be written in it, so that a
/// run whose results could not be saved is refused before it starts, not after.
pub fn ensure_writable_dir(dir: &Path) -> Result<(), WriteError> {
    let err = |cause| WriteError {
        path: dir.to_path_buf(),
        cause,
    };
    std::fs::create_dir_all(dir).map_err(err)?;
    tempfile::Builder::new()
        .prefix(".bkpbs-probe-")
        .tempfile_in(dir)
        .map(drop)
        .map_err(err)
}

/// Whether process `pid` exists (a zombie counts; leaving its files for a later sweep is
/// harmless): how a temporary file or directory naming its writer is told stale.
pub fn process_alive(pid: u32) -> bool {
    // SAFETY: signal 0 only checks that the process exists.
    let r = unsafe { libc::kill(pid as libc::pid_t, 0) };
    r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

/// Removes the entries of `dir` named `<prefix><pid>-…` whose process `pid` is gone: the
/// temporary files and directories of runs that were killed.
pub fn sweep_stale(dir: &Path, prefix: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(rest) = name.to_str().and_then(|n| n.strip_prefix(prefix)) else {
            continue;
        };
        let pid = rest
            .split_once('-')
            .and_then(|(p, _)| p.parse::<u32>().ok());
        if pid.is_some_and(|p| !process_alive(p)) {
            let path = e.path();
            let _ = if path.is_dir() {
                std::fs::remove_dir_all(&path)
            } else {
                std::fs::remove_file(&path)
            };
        }
    }
}

/// Temporary files are `.bkpbs-<pid>-<random>.tmp`: the writer's process id tells a stale one
/// (its writer is gone) from one another process is writing right now.
pub const TEMPORARY_PREFIX: &str = ".bkpbs-";
const TEMPORARY_SUFFIX: &str = ".tmp";

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    let err = |cause| WriteError {
        path: path.to_path_buf(),
        cause,
    };
    let tmp = stage(path, bytes)?;
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}

/// The directory `path` is written in, created if needed.
fn parent_dir(path: &Path) -> Result<&Path, WriteError> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|cause| WriteError {
        path: path.to_path_buf(),
        cause,
    })?;
    Ok(dir)
}

/// `bytes` in a synced temporary file next to `path`, ready to be renamed over it (removed
/// again if dropped).
fn stage(path: &Path, bytes: &[u8]) -> Result<tempfile::NamedTempFile, WriteError> {
    let err = |cause| WriteError {
        path: path.to_path_buf(),
        cause,
    };
    let dir = parent_dir(path)?;
    // Readable by whoever the umask allows (0644 typically), like any file a tool writes; a
    // temporary file's own default, 0600, left shared results unreadable to colleagues.
    let mut tmp = tempfile::Builder::new()
        .prefix(&format!("{TEMPORARY_PREFIX}{}-", std::process::id()))
        .suffix(TEMPORARY_SUFFIX)
        .permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666))
        .tempfile_in(dir)
        .map_err(err)?;
    tmp.write_all(bytes).map_err(err)?;
    tmp.as_file().sync_all().map_err(err)?;
    Ok(tmp)
}

/// One file of a set replaced together: its name and new contents, or `None` to remove an
/// earlier one (a file this result does not have).
pub type SetFile<'a> = (&'a str, Option<&'a [u8]>);

/// Replaces a set of files in `dir` together; the last one is the set's marker, whose presence
/// says the set is complete.
///
/// Every new file is staged (written and synced) and every target checked before anything
/// is replaced, so a failure there (disk full, a target that is a directory) leaves the
/// earlier set untouched. Then the marker goes first and comes back last: in between, and
/// after a kill or a failed rename, the directory has no marker and reads as unfinished, never
/// as a complete mix of old and new files.
pub fn replace_together(dir: &Path, files: &[SetFile]) -> Result<Vec<PathBuf>, WriteError> {
    let (marker, _) = files.last().expect("a set has a marker");
    let paths: Vec<PathBuf> = files.iter().map(|(name, _)| dir.join(name)).collect();
    for p in &paths {
        refuse_directory(p)?;
    }
    let mut staged = Vec::new();
    for (p, (_, bytes)) in paths.iter().zip(files) {
        staged.push(bytes.map(|b| stage(p, b)).transpose()?);
    }
    remove_if_present(&dir.join(marker))?;
    let mut written = Vec::new();
    for (p, tmp) in paths.into_iter().zip(staged) {
        match tmp {
            Some(tmp) => {
                tmp.persist(&p).map_err(|e| WriteError {
                    path: p.clone(),
                    cause: e.error,
                })?;
                written.push(p);
            }
            None => remove_if_present(&p)?,
        }
    }
    // The renames themselves are made durable with the directory (best effort: not every
    // file system can sync a directory).
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(written)
}

/// A target that is a directory cannot be replaced by a file: said before anything changes.
fn refuse_directory(path: &Path) -> Result<(), WriteError> {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => Err(WriteError {
            path: path.to_path_buf(),
            cause: std::io::Error::other("is a directory"),
        }),
        _ => Ok(()),
    }
}

fn remove_if_present(path: &Path) -> Result<(), WriteError> {
    match std::fs::remove_file(path) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(cause) => Err(WriteError {
            path: path.to_path_buf(),
            cause,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    #[test]
    fn only_the_leftovers_of_dead_processes_are_swept() {
        let dead = {
            let mut child = std::process::Command::new("true").spawn().unwrap();
            let pid = child.id();
            child.wait().unwrap();
            pid
        };
        let me = std::process::id();
        let d = tempfile::tempdir().unwrap();
        let file = |pid: u32| d.path().join(format!(".bkpbs-{pid}-abc.tmp"));
        let dir = |pid: u32| d.path().join(format!("bkpbs-episode-{pid}-xyz"));
        for pid in [dead, me] {
            std::fs::write(file(pid), "x").unwrap();
            std::fs::create_dir(dir(pid)).unwrap();
            std::fs::write(dir(pid).join("merge.net.xml"), "x").unwrap();
        }
        std::fs::write(d.path().join(".bkpbs-probe-abc"), "x").unwrap();
        sweep_stale(d.path(), TEMPORARY_PREFIX);
        sweep_stale(d.path(), "bkpbs-episode-");
        assert!(!file(dead).exists() && !dir(dead).exists());
        assert!(file(me).exists() && dir(me).exists());
        assert!(d.path().join(".bkpbs-probe-abc").exists());
    }

    #[test]
    fn files_get_the_umask_s_modes() {
        // SAFETY: reading the umask means setting it; it is put back at once.
        let umask = unsafe {
            let m = libc::umask(0o022);
            libc::umask(m);
            m
        };
        let d = tempfile::tempdir().unwrap();
        let path = d.path().join("a.csv");
        write_atomic(&path, b"x\n").unwrap();
        let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(
            mode,
            0o666 & !(umask as u32),
            "mode {mode:o}, umask {umask:o}"
        );
        assert_eq!(std::fs::read(&path).unwrap(), b"x\n");
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_set_is_replaced_whole_and_a_file_it_lacks_is_removed() {
        let d = tempfile::tempdir().unwrap();
        let old: [SetFile; 3] = [
            ("log", Some(b"old log")),
            ("a.csv", Some(b"old a")),
            ("done.csv", Some(b"old done")),
        ];
        replace_together(d.path(), &old).unwrap();
        let new: [SetFile; 3] = [
            ("log", None),
            ("a.csv", Some(b"new a")),
            ("done.csv", Some(b"new done")),
        ];
        let written = replace_together(d.path(), &new).unwrap();
        assert_eq!(written.len(), 2);
        assert_eq!(names(d.path()), ["a.csv", "done.csv"]);
        assert_eq!(std::fs::read(d.path().join("a.csv")).unwrap(), b"new a");
        assert_eq!(
            std::fs::read(d.path().join("done.csv")).unwrap(),
            b"new done"
        );
    }

    #[test]
    fn a_target_that_cannot_be_replaced_leaves_the_earlier_set_untouched() {
        // An episode.csv that had become a directory once left new vehicles.csv and timing.csv
        // next to the old collisions.csv.
        let d = tempfile::tempdir().unwrap();
        let set = |tag: &'static [u8]| -> [SetFile<'static>; 3] {
            [
                ("v.csv", Some(tag)),
                ("c.csv", Some(tag)),
                ("done.csv", Some(tag)),
            ]
        };
        replace_together(d.path(), &set(b"old")).unwrap();
        std::fs::remove_file(d.path().join("c.csv")).unwrap();
        std::fs::create_dir(d.path().join("c.csv")).unwrap();
        let e = replace_together(d.path(), &set(b"new")).unwrap_err();
        assert!(
            e.to_string().contains("c.csv") && e.to_string().contains("directory"),
            "{e}"
        );
        assert_eq!(std::fs::read(d.path().join("v.csv")).unwrap(), b"old");
        assert_eq!(std::fs::read(d.path().join("done.csv")).unwrap(), b"old");
        assert_eq!(
            names(d.path()),
            ["c.csv", "done.csv", "v.csv"],
            "no temporaries left"
        );
    }
}
