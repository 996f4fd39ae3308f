//! Every file the project reads, read through one bounded reader: only a regular file (a FIFO
//! would block the run until someone writes to it, a device such as `/dev/zero` never ends, a
//! directory is no file), and no more than its kind's limit, read with the limit as a bound so
//! that a file growing while it is read cannot exhaust memory either. The error says which
//! limit, so a user whose network really is that large knows what was refused.

use std::io::Read;
use std::path::Path;

/// What a file holds, and so how large it may be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// A SUMO network (`.net.xml`): OpenStreetMap imports of whole regions run to hundreds of
    /// megabytes.
    Network,
    /// A TOML configuration or campaign table, written by hand.
    Config,
    /// A model or policy file (JSON weights).
    Model,
    /// A data set, trace or result table bkpbs wrote (CSV, JSON lines).
    Data,
}

impl FileKind {
    /// The largest file of this kind read (bytes).
    pub fn limit(self) -> u64 {
        const MIB: u64 = 1 << 20;
        match self {
            FileKind::Network => 2048 * MIB,
            FileKind::Config => 16 * MIB,
            FileKind::Model => 256 * MIB,
            FileKind::Data => 4096 * MIB,
        }
    }

    fn name(self) -> &'static str {
        match self {
            FileKind::Network => "a network file",
            FileKind::Config => "a configuration file",
            FileKind::Model => "a model file",
            FileKind::Data => "a data file",
        }
    }
}

/// The whole of the regular file at `path`, if it is no larger than `kind` allows.
///
/// # Errors
/// Not a regular file (refused before it is opened, so a FIFO does not block), larger than the
/// limit, or the operating system's reason.
pub fn read_bytes(path: &Path, kind: FileKind) -> std::io::Result<Vec<u8>> {
    let mut file = open(path, kind)?;
    let mut bytes = Vec::with_capacity(file.size as usize);
    file.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// The regular file at `path`, opened to be read as a stream (a large CSV table) that fails
/// once it yields more than `kind` allows.
///
/// # Errors
/// As [`read_bytes`], the size error when the stream passes the limit.
pub fn open(path: &Path, kind: FileKind) -> std::io::Result<BoundedFile> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(refused(format!("not a regular file ({})", what(&meta))));
    }
    if meta.len() > kind.limit() {
        return Err(too_large(kind));
    }
    Ok(BoundedFile {
        file: std::fs::File::open(path)?,
        size: meta.len(),
        left: kind.limit(),
        kind,
    })
}

/// A file read with a bound: reading past its kind's limit is an error, not more memory.
pub struct BoundedFile {
    file: std::fs::File,
    /// Its size when opened (bytes).
    size: u64,
    /// Bytes it may still yield.
    left: u64,
    kind: FileKind,
}

impl Read for BoundedFile {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        // One byte more than allowed is asked for, to tell "exactly the limit" from "more".
        let want = (buf.len() as u64).min(self.left + 1) as usize;
        let n = self.file.read(&mut buf[..want])?;
        if n as u64 > self.left {
            return Err(too_large(self.kind));
        }
        self.left -= n as u64;
        Ok(n)
    }
}

fn too_large(kind: FileKind) -> std::io::Error {
    refused(format!(
        "larger than {} MiB, the limit for {}",
        kind.limit() >> 20,
        kind.name()
    ))
}

/// Like [`read_bytes`], as UTF-8 text.
///
/// # Errors
/// As [`read_bytes`], or text that is not UTF-8.
pub fn read_text(path: &Path, kind: FileKind) -> std::io::Result<String> {
    String::from_utf8(read_bytes(path, kind)?)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "not UTF-8 text"))
}

fn refused(message: String) -> std::io::Error {
    std::io::Error::new(std::io::ErrorKind::InvalidInput, message)
}

/// What a path that is no regular file is.
fn what(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_fifos_are_refused_at_once() {
        let e = read_text(Path::new("/dev/zero"), FileKind::Network).unwrap_err();
        assert_eq!(e.to_string(), "not a regular file (a device)");
        let d = tempfile::tempdir().unwrap();
        let e = read_text(d.path(), FileKind::Config).unwrap_err();
        assert_eq!(e.to_string(), "not a regular file (a directory)");
        let fifo = d.path().join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path; mkfifo only creates the node.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = read_text(&fifo, FileKind::Config).unwrap_err();
        assert_eq!(e.to_string(), "not a regular file (a FIFO)");
        let f = d.path().join("ok.toml");
        std::fs::write(&f, "a = 1").unwrap();
        assert_eq!(read_text(&f, FileKind::Config).unwrap(), "a = 1");
    }

    #[test]
    fn a_file_over_its_kinds_limit_is_refused_naming_the_limit() {
        let d = tempfile::tempdir().unwrap();
        let f = d.path().join("big.toml");
        let file = std::fs::File::create(&f).unwrap();
        file.set_len(FileKind::Config.limit() + 1).unwrap(); // sparse: no disk used
        let e = read_text(&f, FileKind::Config).unwrap_err();
        assert_eq!(
            e.to_string(),
            "larger than 16 MiB, the limit for a configuration file"
        );
    }
}
