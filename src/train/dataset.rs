//! The lane-change data set on disk: a compact little-endian binary file.
//!
//! Layout (all integers little-endian):
//!
//! ```text
//! magic         8 bytes  "BKPBSLC\0"
//! version       u32      FORMAT_VERSION
//! slots         u32      neighbour slots of graph (a)      (6)
//! cav_nodes     u32      CAV nodes per graph of (b)         (4)
//! preview       u32      graphs in sequence (b)             (15)
//! record_bytes  u32      bytes per record                   (892)
//! meta_bytes    u32      length of the JSON text that follows
//! meta          …        UTF-8 JSON: how the data was collected (CollectMeta)
//! count         u64      number of records
//! records       count × record_bytes
//! ```
//!
//! A record: `episode u32, step u32, subset u8 (0 ramp, 1 main), label u8 (0/1), ego lane u8,
//! ego flags u8 (bit 0: from the ramp)`; `f32` weight, ego lateral, speed, accel, distance to
//! the merge-zone end; 6 neighbour flag bytes (bit 0 present, bit 1 CAV) and 2 padding bytes;
//! 6 × (`f32` ds, dy, speed); 60 CAV-node presence bytes; 60 × (`f32` ds, dy, speed), step-major.
//! The file must hold exactly `count` records: anything shorter or longer is an error.

use std::path::{Path, PathBuf};

use crate::predict::features::{
    CavNode, Ego, Neighbour, Observation, Subset, CAV_NODES, PREVIEW, SLOTS,
};

/// First bytes of every data file.
pub const MAGIC: &[u8; 8] = b"BKPBSLC\0";
/// Bumped whenever the record layout changes.
pub const FORMAT_VERSION: u32 = 1;
/// Bytes of one record.
pub const RECORD_BYTES: usize = 12 + 5 * 4 + 8 + SLOTS.len() * 12 + PREVIEW * CAV_NODES * 13;

/// One HDV at one decision point, with what it did next.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// Episode number within the collection run (also the split key: never split an episode).
    pub episode: u32,
    /// Episode step of the decision point (the scene the observation was taken from).
    pub step: u32,
    /// Whether the HDV was on the merge lane (ramp) or on the main road.
    pub subset: Subset,
    /// It started a lane change at the next step.
    pub label: bool,
    /// Inverse of the probability with which the collector kept the sample (≥ 1): main-road
    /// negatives are thinned out, since lane changes are rare there.
    pub weight: f32,
    /// The model input: the HDV's graph (a) and the nearest CAVs' next states, sequence (b).
    pub obs: Observation,
}

/// A data file's contents.
#[derive(Debug, Clone, Default)]
pub struct Dataset {
    /// How the data was collected (JSON text).
    pub meta: String,
    /// The samples, in collection order.
    pub samples: Vec<Sample>,
}

/// Why a data file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum DataError {
    /// The file could not be read from disk.
    #[error("cannot read data file {path}: {cause}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        cause: std::io::Error,
    },
    /// The file could not be written.
    #[error(transparent)]
    Write(#[from] crate::io::WriteError),
    /// The file does not start with [`MAGIC`].
    #[error("{path} is not a bkpbs lane-change data file (bad magic bytes)")]
    Magic {
        /// The file.
        path: PathBuf,
    },
    /// The file has another [`FORMAT_VERSION`] than this build.
    #[error("{path}: data format version {found}, this build reads version {expected}")]
    Version {
        /// The file.
        path: PathBuf,
        /// Its format version.
        found: u32,
        /// This build's format version.
        expected: u32,
    },
    /// The header's record layout (slots, CAV nodes, preview, record bytes) differs from this
    /// build's: the file was written for another feature layout.
    #[error("{path}: record layout {found} differs from this build's {expected} (slots, CAV nodes, preview, record bytes)")]
    Layout {
        /// The file.
        path: PathBuf,
        /// The file's layout, as the list `[slots, cav_nodes, preview, record_bytes]`.
        found: String,
        /// This build's layout, in the same form.
        expected: String,
    },
    /// The file ends before its header or its `count` records do.
    #[error("{path} is truncated: {what}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// What is missing.
        what: String,
    },
    /// The contents are invalid: bytes after the last record, metadata not UTF-8, an impossible
    /// record count, or a record with an out-of-range code or a non-finite value.
    #[error("{path} is corrupt: {what}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// What is wrong (naming the record).
        what: String,
    },
}

impl Dataset {
    /// The whole file as bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(48 + self.meta.len() + self.samples.len() * RECORD_BYTES);
        b.extend_from_slice(MAGIC);
        for x in [
            FORMAT_VERSION,
            SLOTS.len() as u32,
            CAV_NODES as u32,
            PREVIEW as u32,
            RECORD_BYTES as u32,
            self.meta.len() as u32,
        ] {
            b.extend_from_slice(&x.to_le_bytes());
        }
        b.extend_from_slice(self.meta.as_bytes());
        b.extend_from_slice(&(self.samples.len() as u64).to_le_bytes());
        for s in &self.samples {
            let start = b.len();
            encode_record(s, &mut b);
            debug_assert_eq!(b.len() - start, RECORD_BYTES);
        }
        b
    }

    /// Writes the file atomically (temporary file, then rename).
    pub fn write(&self, path: &Path) -> Result<(), DataError> {
        crate::io::write_atomic(path, &self.to_bytes())?;
        Ok(())
    }

    /// Reads and checks a data file.
    pub fn read(path: &Path) -> Result<Dataset, DataError> {
        let bytes = crate::io::bounded::read_bytes(path, crate::io::bounded::FileKind::Data)
            .map_err(|cause| DataError::Read {
                path: path.to_path_buf(),
                cause,
            })?;
        Dataset::from_bytes(path, &bytes)
    }

    /// Parses a file's bytes; `path` only names the file in errors.
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Dataset, DataError> {
        let p = || path.to_path_buf();
        let truncated = |what: String| DataError::Truncated { path: p(), what };
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            if bytes.len() < MAGIC.len() && MAGIC.starts_with(bytes) {
                return Err(truncated(format!(
                    "{} bytes, not even a header",
                    bytes.len()
                )));
            }
            return Err(DataError::Magic { path: p() });
        }
        let mut r = Reader { bytes, at: 8 };
        let meta_len = read_layout(&mut r, path)?;
        let meta = r
            .take(meta_len)
            .ok_or_else(|| truncated("metadata cut short".into()))?;
        let meta = std::str::from_utf8(meta)
            .map_err(|_| DataError::Corrupt {
                path: p(),
                what: "metadata is not UTF-8".into(),
            })?
            .to_string();
        let count = r
            .take(8)
            .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
            .ok_or_else(|| truncated("record count cut short".into()))?;
        check_body_length(path, count, bytes.len() - r.at)?;
        let mut samples = Vec::with_capacity(count as usize);
        for (index, rec) in bytes[r.at..].chunks_exact(RECORD_BYTES).enumerate() {
            let s = decode_record(rec).map_err(|what| DataError::Corrupt {
                path: p(),
                what: format!("record {index}: {what}"),
            })?;
            samples.push(s);
        }
        Ok(Dataset { meta, samples })
    }
}

/// The header after the magic: this format version and this build's record layout, or the
/// error naming what the file has instead. Returns the metadata's length.
fn read_layout(r: &mut Reader, path: &Path) -> Result<usize, DataError> {
    let head = r.u32s::<6>().ok_or_else(|| DataError::Truncated {
        path: path.to_path_buf(),
        what: "header cut short".into(),
    })?;
    if head[0] != FORMAT_VERSION {
        return Err(DataError::Version {
            path: path.to_path_buf(),
            found: head[0],
            expected: FORMAT_VERSION,
        });
    }
    let expected = [SLOTS.len(), CAV_NODES, PREVIEW, RECORD_BYTES].map(|x| x as u32);
    if head[1..5] != expected {
        return Err(DataError::Layout {
            path: path.to_path_buf(),
            found: format!("{:?}", &head[1..5]),
            expected: format!("{expected:?}"),
        });
    }
    Ok(head[5] as usize)
}

/// The `body` bytes after the record count hold exactly `count` records: fewer is a cut-off
/// file, more is not a file this format wrote.
fn check_body_length(path: &Path, count: u64, body: usize) -> Result<(), DataError> {
    let corrupt = |what: String| DataError::Corrupt {
        path: path.to_path_buf(),
        what,
    };
    let need = count
        .checked_mul(RECORD_BYTES as u64)
        .ok_or_else(|| corrupt(format!("record count {count} is impossible")))?;
    if (body as u64) < need {
        return Err(DataError::Truncated {
            path: path.to_path_buf(),
            what: format!(
                "header announces {count} records ({need} bytes) but only {body} bytes follow"
            ),
        });
    }
    if body as u64 > need {
        return Err(corrupt(format!(
            "{} bytes follow the last of its {count} records",
            body as u64 - need
        )));
    }
    Ok(())
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let out = self.bytes.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(out)
    }

    fn u32s<const N: usize>(&mut self) -> Option<[u32; N]> {
        let b = self.take(4 * N)?;
        Some(std::array::from_fn(|i| {
            u32::from_le_bytes(b[4 * i..4 * i + 4].try_into().expect("4 bytes"))
        }))
    }

    fn f32(&mut self) -> f32 {
        let b = self.take(4).expect("record length checked");
        f32::from_le_bytes(b.try_into().expect("4 bytes"))
    }

    fn u8(&mut self) -> u8 {
        self.take(1).expect("record length checked")[0]
    }
}

fn encode_record(s: &Sample, b: &mut Vec<u8>) {
    let o = &s.obs;
    b.extend_from_slice(&s.episode.to_le_bytes());
    b.extend_from_slice(&s.step.to_le_bytes());
    b.extend_from_slice(&[
        s.subset.code(),
        s.label as u8,
        o.ego.lane,
        o.ego.from_ramp as u8,
    ]);
    for x in [
        s.weight,
        o.ego.lateral,
        o.ego.speed,
        o.ego.accel,
        o.ego.to_merge_end,
    ] {
        b.extend_from_slice(&x.to_le_bytes());
    }
    for n in &o.neighbours {
        b.push(n.present as u8 | (n.is_cav as u8) << 1);
    }
    b.extend_from_slice(&[0, 0]);
    for n in &o.neighbours {
        for x in [n.ds, n.dy, n.speed] {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
    for c in o.cavs.iter().flatten() {
        b.push(c.present as u8);
    }
    for c in o.cavs.iter().flatten() {
        for x in [c.ds, c.dy, c.speed] {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
}

fn decode_record(rec: &[u8]) -> Result<Sample, String> {
    let mut r = Reader { bytes: rec, at: 0 };
    let [episode, step] = r.u32s::<2>().expect("record length checked");
    let (subset, label, lane, flags) = (r.u8(), r.u8(), r.u8(), r.u8());
    let subset = Subset::from_code(subset).ok_or(format!("subset code {subset}"))?;
    if label > 1 {
        return Err(format!("label {label}"));
    }
    if lane > 2 || flags > 1 {
        return Err(format!("ego lane {lane} / flags {flags}"));
    }
    let floats: [f32; 5] = std::array::from_fn(|_| r.f32());
    let [weight, lateral, speed, accel, to_merge_end] = floats;
    if floats.iter().any(|x| !x.is_finite()) || weight < 1.0 {
        return Err(format!("ego values {floats:?}"));
    }
    let mut obs = Observation {
        ego: Ego {
            lane,
            lateral,
            speed,
            accel,
            to_merge_end,
            from_ramp: flags == 1,
        },
        ..Observation::default()
    };
    decode_neighbours(&mut r, &mut obs.neighbours)?;
    decode_cavs(&mut r, &mut obs.cavs)?;
    Ok(Sample {
        episode,
        step,
        subset,
        label: label == 1,
        weight,
        obs,
    })
}

/// Three finite values (relative s, lateral offset, speed) of one graph node.
fn finite_triple(r: &mut Reader, what: &str) -> Result<[f32; 3], String> {
    let v = [r.f32(), r.f32(), r.f32()];
    if v.iter().any(|x| !x.is_finite()) {
        return Err(format!("{what} values {v:?}"));
    }
    Ok(v)
}

/// The neighbour slots: a flag byte each (present, is a CAV), two bytes of padding, then
/// their values.
fn decode_neighbours(r: &mut Reader, neighbours: &mut [Neighbour]) -> Result<(), String> {
    let nflags: [u8; 6] = std::array::from_fn(|_| r.u8());
    r.take(2);
    for (n, f) in neighbours.iter_mut().zip(nflags) {
        if f > 3 {
            return Err(format!("neighbour flags {f}"));
        }
        let v = finite_triple(r, "neighbour")?;
        *n = Neighbour {
            present: f & 1 == 1,
            ds: v[0],
            dy: v[1],
            speed: v[2],
            is_cav: f & 2 == 2,
        };
    }
    Ok(())
}

/// The preview of the higher-priority CAVs: a presence byte per node, then their values.
fn decode_cavs(r: &mut Reader, cavs: &mut [[CavNode; CAV_NODES]; PREVIEW]) -> Result<(), String> {
    let present: [u8; PREVIEW * CAV_NODES] = std::array::from_fn(|_| r.u8());
    for (c, p) in cavs.iter_mut().flatten().zip(present) {
        if p > 1 {
            return Err(format!("CAV presence byte {p}"));
        }
        let v = finite_triple(r, "CAV")?;
        *c = CavNode {
            present: p == 1,
            ds: v[0],
            dy: v[1],
            speed: v[2],
        };
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(i: u32) -> Sample {
        let mut obs = Observation::default();
        obs.ego.speed = 20.0 + i as f32;
        obs.ego.lane = (i % 3) as u8;
        obs.neighbours[2] = Neighbour {
            present: true,
            ds: 12.5,
            dy: 4.5,
            speed: 30.0,
            is_cav: true,
        };
        obs.cavs[14][3] = CavNode {
            present: true,
            ds: -3.0,
            dy: 0.0,
            speed: 33.0,
        };
        Sample {
            episode: i / 10,
            step: i,
            subset: Subset::of_lane(obs.ego.lane as i32),
            label: i % 7 == 0,
            weight: 1.0 + (i % 2) as f32,
            obs,
        }
    }

    fn dataset() -> Dataset {
        Dataset {
            meta: "{\"test\":true}".into(),
            samples: (0..25).map(sample).collect(),
        }
    }

    #[test]
    fn round_trips() {
        let d = dataset();
        let bytes = d.to_bytes();
        let back = Dataset::from_bytes(Path::new("x.bin"), &bytes).unwrap();
        assert_eq!(back.meta, d.meta);
        assert_eq!(back.samples, d.samples);
    }

    #[test]
    fn truncated_and_corrupt_files_are_named_errors() {
        let bytes = dataset().to_bytes();
        let path = Path::new("data/some.bin");
        // Cut in the middle of the records, in the header, and after the magic.
        for cut in [bytes.len() - 1, bytes.len() - RECORD_BYTES - 3, 20, 4] {
            let e = Dataset::from_bytes(path, &bytes[..cut]).unwrap_err();
            assert!(matches!(e, DataError::Truncated { .. }), "{cut}: {e}");
            assert!(e.to_string().contains("data/some.bin"), "{e}");
        }
        let mut longer = bytes.clone();
        longer.push(0);
        let e = Dataset::from_bytes(path, &longer).unwrap_err().to_string();
        assert!(e.contains("corrupt") && e.contains("1 bytes follow"), "{e}");
        let mut bad = bytes.clone();
        bad[0] = b'X';
        let e = Dataset::from_bytes(path, &bad).unwrap_err();
        assert!(matches!(e, DataError::Magic { .. }), "{e}");
        let mut v2 = bytes.clone();
        v2[8] = 2;
        let e = Dataset::from_bytes(path, &v2).unwrap_err().to_string();
        assert!(e.contains("version 2"), "{e}");
        // A label byte of 7 in the first record.
        let header = 8 + 24 + dataset().meta.len() + 8;
        let mut lab = bytes.clone();
        lab[header + 9] = 7;
        let e = Dataset::from_bytes(path, &lab).unwrap_err().to_string();
        assert!(e.contains("record 0") && e.contains("label 7"), "{e}");
        // A NaN speed.
        let mut nan = bytes;
        nan[header + 12 + 8..header + 12 + 12].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = Dataset::from_bytes(path, &nan).unwrap_err().to_string();
        assert!(e.contains("ego values"), "{e}");
    }

    #[test]
    fn missing_file_names_the_file() {
        let e = Dataset::read(Path::new("no/such/data.bin"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("no/such/data.bin"), "{e}");
    }
}
