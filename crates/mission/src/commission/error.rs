//! What stops a commissioning, each naming what is wrong.

use std::path::PathBuf;

use crate::MissionError;

/// Why a commissioning stopped or refused its result.
#[derive(Debug, thiserror::Error)]
pub enum CommissionError {
    /// The rig: the link, the sensor, a slide, the stop (boxed: the mission's error is large).
    #[error(transparent)]
    Rig(Box<MissionError>),
    /// Training or evaluating the models.
    #[error(transparent)]
    Tactile(#[from] crackbot_tactile::TactileError),
    /// Reading or writing a recording.
    #[error(transparent)]
    Recording(#[from] crackbot_recording::RecordingError),
    /// The proximity fibre's fit.
    #[error(transparent)]
    Fibre(#[from] crackbot_fibre::FibreError),
    /// A file of the session or the profile.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },
    /// A file of the session or the profile that does not read as one.
    #[error("{}: {message}", path.display())]
    BadFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        message: String,
    },
    /// A setting out of its range.
    #[error("commissioning: {field} = {value} is outside {allowed}")]
    Setting {
        /// The setting.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What it may be.
        allowed: &'static str,
    },
    /// The plates given leave a class of a model without slides.
    #[error("the plates given leave the {model} model's class \"{class}\" without a plate: mount {wanted}")]
    MissingClass {
        /// `recognition` or `width`.
        model: &'static str,
        /// The class.
        class: String,
        /// The plate(s) that would give it.
        wanted: String,
    },
    /// Too few slides per class for the models and their leave-one-repetition-out evaluation.
    #[error("{what}: at least {least} needed for the models and their evaluation")]
    TooFewSlides {
        /// What was asked.
        what: String,
        /// The least.
        least: u32,
    },
    /// A channel at the ends of its range: the sensor saturates.
    #[error("the sensor saturates on {plate}: {channel} read {counts:.0} counts on {share:.1} % of its samples (the ADC's range is 0–{full}); lower the amplifier's gain or move the fibre and commission again")]
    Saturated {
        /// Where.
        plate: String,
        /// Which channel.
        channel: &'static str,
        /// The value at the end of the range.
        counts: f64,
        /// Share of the samples there, %.
        share: f64,
        /// The ADC's full scale.
        full: u32,
    },
    /// The models failed their own evaluation: no profile was installed.
    #[error("the new {model} model reads {what} {value:.1} % on held-out repetitions, below the {least:.1} % a profile needs: no profile installed (recordings kept in {}; more slides or repetitions may help)", session.display())]
    FailsEvaluation {
        /// `recognition` or `width`.
        model: &'static str,
        /// Which figure.
        what: &'static str,
        /// Its value, %.
        value: f64,
        /// The least accepted, %.
        least: f64,
        /// The session folder.
        session: PathBuf,
    },
    /// The width model's error on held-out repetitions is above the least accepted.
    #[error("the new width model's slide error is {value:.2} mm on held-out repetitions, above the {most:.2} mm a profile accepts: no profile installed")]
    WidthError {
        /// Its value, mm.
        value: f64,
        /// The most accepted, mm.
        most: f64,
    },
    /// A plate name not in the reference set.
    #[error("no reference plate is called \"{name}\" (the set: {known})")]
    UnknownPlate {
        /// The name given.
        name: String,
        /// The set's names.
        known: String,
    },
    /// The session folder holds another commissioning's settings.
    #[error("{}: this session was started with other settings ({what}); resume it with the same ones or choose another --session folder", path.display())]
    OtherSession {
        /// The session's file.
        path: PathBuf,
        /// What differs.
        what: String,
    },
}

impl From<MissionError> for CommissionError {
    fn from(e: MissionError) -> Self {
        CommissionError::Rig(Box::new(e))
    }
}

/// An I/O error's wrapper naming `path`.
pub(crate) fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> CommissionError + '_ {
    move |source| CommissionError::Io {
        path: path.to_path_buf(),
        source,
    }
}
