//! Reading (and writing) the key file: hex text, owner-only permissions.

use std::fs;
use std::io::{self, Read, Write};
use std::path::{Path, PathBuf};
use std::string::String;
use std::vec::Vec;

use crate::auth::{Key, KeyError, KEY_MAX_LEN};

/// Why a key file was refused. Never contains key material.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum KeyFileError {
    /// The file could not be read or written.
    #[error("key file {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: io::Error,
    },
    /// The file is readable or writable by its group or by others (Unix mode bits `0o077`).
    #[error(
        "key file {} has mode {mode:03o}: group or others may access it; \
         `chmod 600` it (and consider the key compromised)",
        path.display()
    )]
    Permissions {
        /// The file.
        path: PathBuf,
        /// Its permission bits.
        mode: u32,
    },
    /// Not a regular file.
    #[error("key file {} is not a regular file", path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
    },
    /// The content is not 64 to 128 hex digits (surrounding whitespace allowed).
    #[error(
        "key file {} must hold 64 to 128 hex digits (32 to 64 bytes) and nothing else",
        path.display()
    )]
    Format {
        /// The file.
        path: PathBuf,
    },
    /// The bytes are not a usable key (too short, too long, all zero).
    #[error("key file {}: {error}", path.display())]
    Key {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        error: KeyError,
    },
}

fn hex_value(c: u8) -> Option<u8> {
    match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        b'A'..=b'F' => Some(c - b'A' + 10),
        _ => None,
    }
}

/// Decodes hex text (surrounding ASCII whitespace allowed) into at most `KEY_MAX_LEN + 1`
/// bytes (one more, so that an over-long key is reported as such).
fn parse_hex(text: &[u8]) -> Option<Vec<u8>> {
    let t = text.trim_ascii();
    if !t.len().is_multiple_of(2) || t.len() > 2 * (KEY_MAX_LEN + 1) {
        return None;
    }
    t.chunks(2)
        .map(|p| Some(hex_value(p[0])? << 4 | hex_value(p[1])?))
        .collect()
}

fn check_permissions(path: &Path, meta: &fs::Metadata) -> Result<(), KeyFileError> {
    if !meta.is_file() {
        return Err(KeyFileError::NotAFile { path: path.into() });
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = meta.permissions().mode() & 0o7777;
        if mode & 0o077 != 0 {
            return Err(KeyFileError::Permissions {
                path: path.into(),
                mode,
            });
        }
    }
    Ok(())
}

impl Key {
    /// Reads the key file at `path`: 64 to 128 hex digits (32 to 64 key bytes), surrounding
    /// whitespace allowed, nothing else; on Unix the file must not be accessible to its group or
    /// others (mode `0600` or `0400`). Refuses a missing, empty, short, all-zero or malformed key;
    /// the error never contains key material.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Key, KeyFileError> {
        let path = path.as_ref();
        let io = |source| KeyFileError::Io {
            path: path.into(),
            source,
        };
        let mut file = fs::File::open(path).map_err(io)?;
        // Check the file opened, not the path again (no race with a rename in between).
        let meta = file.metadata().map_err(io)?;
        check_permissions(path, &meta)?;
        let mut text = Vec::new();
        // A key file is small; read a little more than the largest valid one.
        (&mut file)
            .take(4 * KEY_MAX_LEN as u64)
            .read_to_end(&mut text)
            .map_err(io)?;
        let bytes = parse_hex(&text);
        text.fill(0);
        let Some(mut bytes) = bytes else {
            return Err(KeyFileError::Format { path: path.into() });
        };
        let key = Key::from_bytes(&bytes);
        bytes.fill(0);
        key.map_err(|error| KeyFileError::Key {
            path: path.into(),
            error,
        })
    }

    /// Writes a new random 32-byte key to `path` (which must not exist) with mode `0600`, read
    /// from the operating system's random source (`/dev/urandom`; Unix only), and returns it.
    pub fn write_new_file(path: impl AsRef<Path>) -> Result<Key, KeyFileError> {
        let path = path.as_ref();
        let io = |source| KeyFileError::Io {
            path: path.into(),
            source,
        };
        let mut bytes = [0u8; 32];
        #[cfg(unix)]
        {
            fs::File::open("/dev/urandom")
                .and_then(|mut r| r.read_exact(&mut bytes))
                .map_err(io)?;
        }
        #[cfg(not(unix))]
        {
            return Err(io(io::Error::new(
                io::ErrorKind::Unsupported,
                "no random source: write the key file yourself",
            )));
        }
        let key = Key::from_bytes(&bytes).map_err(|error| KeyFileError::Key {
            path: path.into(),
            error,
        })?;
        let mut text = String::with_capacity(65);
        for b in bytes {
            text.push(char::from(b"0123456789abcdef"[usize::from(b >> 4)]));
            text.push(char::from(b"0123456789abcdef"[usize::from(b & 15)]));
        }
        text.push('\n');
        bytes.fill(0);
        let mut options = fs::OpenOptions::new();
        options.write(true).create_new(true);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            options.mode(0o600);
        }
        let written = options
            .open(path)
            .and_then(|mut f| f.write_all(text.as_bytes()).and_then(|()| f.sync_all()));
        // Overwrite the text before returning, whatever happened.
        let mut zeroed = text.into_bytes();
        zeroed.fill(0);
        written.map_err(io)?;
        Ok(key)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_parsing() {
        assert_eq!(parse_hex(b"  0aFf\n"), Some(std::vec![0x0a, 0xff]));
        assert_eq!(parse_hex(b"0a f"), None);
        assert_eq!(parse_hex(b"0g"), None);
        assert_eq!(parse_hex(b"abc"), None);
        assert_eq!(parse_hex(b""), Some(Vec::new()));
    }
}
