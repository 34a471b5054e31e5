//! A commissioning's folder, from which an interrupted run resumes: `session.toml` (the
//! settings it was started with), `optics.toml` (the approach's readings and the fitted
//! optics), `recordings/PLATE-repR.csv` (one per plate and repetition, in the authors'
//! layout, written when its last slide ends), `rig/` (the link's state and each slide's own
//! recording) and `evaluation.json`.

use std::path::{Path, PathBuf};

use crackbot_plates::ReferencePlate;
use crackbot_recording::Recording;
use serde::{Deserialize, Serialize};

use super::approach::ApproachReadings;
use super::error::{io, CommissionError};
use super::optics::FingerOptics;
use super::settings::CommissionSettings;

/// What `optics.toml` holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OpticsFile {
    /// What the approach read.
    pub readings: ApproachReadings,
    /// What was fitted to it.
    pub optics: FingerOptics,
}

/// A session's folder.
#[derive(Debug, Clone)]
pub struct Session {
    dir: PathBuf,
}

fn read_toml<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Option<T>, CommissionError> {
    match std::fs::read_to_string(path) {
        Ok(text) => toml::from_str(&text)
            .map(Some)
            .map_err(|e| CommissionError::BadFile {
                path: path.to_path_buf(),
                message: e.to_string(),
            }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(io(path)(e)),
    }
}

fn write_toml<T: Serialize>(path: &Path, value: &T) -> Result<(), CommissionError> {
    let text = toml::to_string_pretty(value).map_err(|e| CommissionError::BadFile {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    // Written whole, then renamed: an interrupted write leaves no half file to resume from.
    let tmp = path.with_extension("toml.part");
    std::fs::write(&tmp, text).map_err(io(&tmp))?;
    std::fs::rename(&tmp, path).map_err(io(path))
}

impl Session {
    /// Opens (creating) the session in `dir` for `settings`; a folder started with other
    /// settings is refused naming what differs.
    pub fn open(dir: &Path, settings: &CommissionSettings) -> Result<Session, CommissionError> {
        std::fs::create_dir_all(dir.join("recordings")).map_err(io(dir))?;
        let path = dir.join("session.toml");
        match read_toml::<CommissionSettings>(&path)? {
            Some(old) if &old != settings => {
                let (a, b) = (toml::Table::try_from(&old), toml::Table::try_from(settings));
                let what = match (a, b) {
                    (Ok(a), Ok(b)) => a
                        .iter()
                        .filter(|(k, v)| b.get(*k) != Some(v))
                        .map(|(k, v)| format!("{k} was {v}"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    _ => "unreadable".into(),
                };
                return Err(CommissionError::OtherSession { path, what });
            }
            Some(_) => {}
            None => write_toml(&path, settings)?,
        }
        Ok(Session {
            dir: dir.to_path_buf(),
        })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Where the rig's link state and slides go while `plate` is mounted.
    pub fn rig_dir(&self, plate: &str) -> PathBuf {
        self.dir.join("rig").join(plate)
    }

    /// The optics, once measured.
    pub fn optics(&self) -> Result<Option<OpticsFile>, CommissionError> {
        read_toml(&self.dir.join("optics.toml"))
    }

    /// Keeps the optics.
    pub fn save_optics(&self, o: &OpticsFile) -> Result<(), CommissionError> {
        write_toml(&self.dir.join("optics.toml"), o)
    }

    fn recording_path(&self, plate: &ReferencePlate, rep: u32) -> PathBuf {
        self.dir
            .join("recordings")
            .join(format!("{}-rep{rep}.csv", plate.name))
    }

    /// Repetition `rep` of `plate`, once recorded.
    pub fn recording(
        &self,
        plate: &ReferencePlate,
        rep: u32,
    ) -> Result<Option<Recording>, CommissionError> {
        let path = self.recording_path(plate, rep);
        if !path.is_file() {
            return Ok(None);
        }
        Ok(Some(crackbot_recording::read_csv(&path)?))
    }

    /// Keeps repetition `rep` of `plate` (written whole, then renamed).
    pub fn save_recording(
        &self,
        plate: &ReferencePlate,
        rep: u32,
        r: &Recording,
    ) -> Result<(), CommissionError> {
        let path = self.recording_path(plate, rep);
        let tmp = path.with_extension("csv.part");
        crackbot_recording::write_csv(&tmp, r)?;
        std::fs::rename(&tmp, &path).map_err(io(&path))
    }

    /// Writes `name` as pretty JSON into the folder.
    pub fn save_json<T: Serialize>(&self, name: &str, value: &T) -> Result<(), CommissionError> {
        let path = self.dir.join(name);
        let text = serde_json::to_string_pretty(value).map_err(|e| CommissionError::BadFile {
            path: path.clone(),
            message: e.to_string(),
        })?;
        std::fs::write(&path, text + "\n").map_err(io(&path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_session_resumes_with_its_settings_only() {
        let dir = tempfile::tempdir().unwrap();
        let s = CommissionSettings::default();
        let session = Session::open(dir.path(), &s).unwrap();
        let plate = crackbot_plates::by_name("flat").unwrap();
        assert!(session.recording(&plate, 1).unwrap().is_none());
        let row = crackbot_recording::Row {
            x_mm: 1.0,
            d1: 650.0,
            d2: 430.0,
            d3: 700.0,
            p: 500.0,
            direction: 1,
            slide: 1,
            label: 0.0,
            repetition: 1,
        };
        let rec = Recording {
            rows: vec![row; 3],
            extra: None,
        };
        session.save_recording(&plate, 1, &rec).unwrap();
        // Opened again with the same settings: what was recorded is there.
        let again = Session::open(dir.path(), &s).unwrap();
        assert_eq!(again.recording(&plate, 1).unwrap().unwrap(), rec);
        let other = CommissionSettings { slides: 8, ..s };
        let e = Session::open(dir.path(), &other).unwrap_err().to_string();
        assert!(
            e.contains("session.toml") && e.contains("slides was 6"),
            "{e}"
        );
    }
}
