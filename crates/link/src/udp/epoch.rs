//! The persisted epoch: a new one at every start, written to disk before the first packet.

use std::format;
use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

/// Largest clock-derived floor of a new epoch (leaves 2^28 starts of room above it).
const CLOCK_FLOOR_MAX: u32 = 0xF000_0000;
/// A start without an epoch file adds a random offset in `1..RANDOM_SPAN` to the clock's
/// floor (2^27: two such starts within one second repeat an epoch once in 1.3·10^8).
const RANDOM_SPAN: u32 = 1 << 27;

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
/// `max(n + 1, seconds since 1970)`, and writes the new value durably. Without a file (the
/// first start, or the file lost) it takes the seconds since 1970 plus a random offset in
/// `1..2^27` from the operating system's random source, so that two starts within one second
/// whose file was lost in between do not repeat an epoch (the clock alone would: issue 57,
/// "an epoch reused"); the offset only moves the epoch ahead of the clock, which never makes
/// an older epoch come back. It writes the new value durably (temporary file, `fsync`, rename,
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
        let last = self.last()?;
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0, |d| d.as_secs());
        let floor = u32::try_from(now)
            .unwrap_or(CLOCK_FLOOR_MAX)
            .min(CLOCK_FLOOR_MAX);
        let epoch = match last {
            Some(n) => n
                .checked_add(1)
                .ok_or_else(|| EpochError::Exhausted {
                    path: self.path.clone(),
                })?
                .max(floor),
            None => {
                let offset = random_u32().map_err(|source| EpochError::Io {
                    path: self.path.clone(),
                    source,
                })? % (RANDOM_SPAN - 1);
                floor + 1 + offset
            }
        };
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

/// Four bytes from the operating system's random source.
fn random_u32() -> io::Result<u32> {
    use std::io::Read;
    let mut b = [0u8; 4];
    fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut b))
        .map_err(|e| io::Error::new(e.kind(), format!("no random source for a new epoch: {e}")))?;
    Ok(u32::from_le_bytes(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starts_without_a_file_within_one_second_take_different_epochs() {
        let dir = tempfile::tempdir().expect("tempdir");
        let file = EpochFile::new(dir.path().join("e.epoch"));
        let mut seen = std::collections::HashSet::new();
        for _ in 0..50 {
            let e = file.advance().expect("epoch");
            std::fs::remove_file(file.path()).expect("lose the file");
            assert!(seen.insert(e), "epoch {e} repeated");
        }
    }

    #[test]
    fn with_the_file_each_start_takes_the_next_epoch() {
        let dir = tempfile::tempdir().expect("tempdir");
        let file = EpochFile::new(dir.path().join("e.epoch"));
        let a = file.advance().expect("epoch");
        let b = file.advance().expect("epoch");
        assert!(b > a, "{b} after {a}");
        assert_eq!(file.last().expect("read"), Some(b));
    }
}
