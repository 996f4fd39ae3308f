//! Which build of bkpbs this binary is: its package version and the git commit its sources
//! were built from (`BKPBS_COMMIT`, set by the build script). What a campaign cell and a
//! model file record of the code that produced them.

use serde::{Deserialize, Serialize};

/// A bkpbs build: its version and the commit its sources were built from (`unknown` when
/// built outside a git checkout; uncommitted edits are not seen).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Build {
    /// The package version.
    pub version: String,
    /// The git commit (full hash).
    pub commit: String,
}

impl Build {
    /// The build of this binary.
    pub fn this() -> Build {
        Build {
            version: env!("CARGO_PKG_VERSION").into(),
            commit: env!("BKPBS_COMMIT").into(),
        }
    }
}

impl std::fmt::Display for Build {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let short = self.commit.get(..12).unwrap_or(&self.commit);
        write!(f, "bkpbs {} (commit {short})", self.version)
    }
}
