//! The persisted epoch: a new one at every start, written to disk before the first packet.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

/// Largest clock-derived floor of a new epoch (leaves 2^28 starts of room above it).
const CLOCK_FLOOR_MAX: u32 = 0xF000_0000;

/// Why the epoch file could not give a new epoch.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EpochError {
    /// It could not be read or written.
    #[error("epoch file {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: io::Error,
    },
    /// It exists but does not hold `crackbot-link epoch <n>`: refused rather than guessed (a
    /// guessed epoch could repeat an old one).
    #[error(
        "epoch file {} is corrupt (expected `crackbot-link epoch <n>`); \
         delete it only together with changing the key",
        path.display()
    )]
    Format {
        /// The file.
        path: PathBuf,
    },
    /// The epoch space is used up (u32::MAX reached): change the key.
    #[error(
        "epoch file {}: epochs used up; change the key and delete the file",
        path.display()
    )]
    Exhausted {
        /// The file.
        path: PathBuf,
    },
}

/// The file that makes each start of an endpoint use a new epoch. It holds one line,
/// `crackbot-link epoch <n>`, the last epoch used. [`EpochFile::advance`] reads it, takes
/// `max(n + 1, seconds since 1970)` (so that a lost file still gives a new epoch while the
/// clock is right), and writes the new value durably (temporary file, `fsync`, rename,
/// `fsync` of the folder) before returning it, so no packet of the new epoch leaves before the
/// epoch is on disk. One endpoint per file: two processes sharing one would reuse epochs.
#[derive(Clone, Debug)]
pub struct EpochFile {
    path: PathBuf,
}

impl EpochFile {
    /// The epoch file at `path` (created at the first [`EpochFile::advance`]).
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self { path: path.into() }
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The last epoch written, `None` if there is no file yet.
    pub fn last(&self) -> Result<Option<u32>, EpochError> {
        let text = match fs::read_to_string(&self.path) {
            Ok(t) => t,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
            Err(source) => {
                return Err(EpochError::Io {
                    path: self.path.clone(),
                    source,
                })
            }
        };
        text.trim()
            .strip_prefix("crackbot-link epoch ")
            .and_then(|n| n.parse::<u32>().ok())
            .map(Some)
            .ok_or_else(|| EpochError::Format {
                path: self.path.clone(),
            })
    }

    /// Takes the next epoch and writes it durably.
    pub fn advance(&self) -> Result<u32, EpochError> {
        let last = self.last()?.unwrap_or(0);
        let next = last.checked_add(1).ok_or_else(|| EpochError::Exhausted {
            path: self.path.clone(),
        })?;
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0);
        let floor = u32::try_from(now)
            .unwrap_or(CLOCK_FLOOR_MAX)
            .min(CLOCK_FLOOR_MAX);
        let epoch = next.max(floor);
        self.write(epoch).map_err(|source| EpochError::Io {
            path: self.path.clone(),
            source,
        })?;
        Ok(epoch)
    }

    fn write(&self, epoch: u32) -> io::Result<()> {
        let mut tmp = self.path.clone().into_os_string();
        tmp.push(".tmp");
        let tmp = PathBuf::from(tmp);
        let mut options = fs::OpenOptions::new();
        options.write(true).create(true).truncate(true);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            options.mode(0o600);
        }
        let mut f = options.open(&tmp)?;
        writeln!(f, "crackbot-link epoch {epoch}")?;
        f.sync_all()?;
        drop(f);
        fs::rename(&tmp, &self.path)?;
        #[cfg(unix)]
        if let Some(dir) = self.path.parent() {
            let dir = if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            };
            fs::File::open(dir)?.sync_all()?;
        }
        Ok(())
    }
}
