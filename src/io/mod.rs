//! Files written whole or not at all: a temporary file in the same directory, synced, then
//! renamed over the target. A crash or a kill never leaves a half-written result, and an
//! earlier result stays until it is replaced whole. The lowest layer: results, model files and
//! data sets all go through it.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Why results could not be written.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}: {cause}")]
pub struct WriteError {
    pub path: PathBuf,
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

/// Temporary files are `.bkpbs-<pid>-<random>.tmp`: the writer's process id tells a stale one
/// (its writer is gone) from one another process is writing right now.
const TEMPORARY_PREFIX: &str = ".bkpbs-";
const TEMPORARY_SUFFIX: &str = ".tmp";

/// The process id of the writer of temporary file `name`, if it is one of ours.
pub fn temporary_writer(name: &str) -> Option<u32> {
    let rest = name
        .strip_prefix(TEMPORARY_PREFIX)?
        .strip_suffix(TEMPORARY_SUFFIX)?;
    rest.split_once('-')?.0.parse().ok()
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), WriteError> {
    let err = |cause| WriteError {
        path: path.to_path_buf(),
        cause,
    };
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(err)?;
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
    tmp.persist(path).map_err(|e| err(e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    #[test]
    fn temporaries_name_their_writer() {
        assert_eq!(temporary_writer(".bkpbs-1234-abcDEF.tmp"), Some(1234));
        assert_eq!(temporary_writer(".bkpbs-abcDEF.tmp"), None);
        assert_eq!(temporary_writer("episodes.csv"), None);
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
}
