//! `crackbot-calib-target`: the printed calibration target.
//!
//! * [`spec`]: the target as a TOML table (a grid of tag36h11 AprilTags: columns, rows, tag size,
//!   gap, first id, margin), checked once; its frame (mm, origin at the bottom-left tag's outer
//!   corner, `x` right, `y` up the sheet) and what is printed at each point.
//! * [`print`]: the sheet as a PNG at true scale, its pixel size written into the file.
//! * [`detect`]: the tags found in a camera image by the AprilTag library, and their corners as a
//!   [`crackbot_calib::View`].
//! * `family` (private): the tag36h11 codes, read from the library that decodes them.
//!
//! The format is specified in `docs/target.md`.

pub mod detect;
mod error;
mod family;
pub mod print;
pub mod spec;

pub use detect::{Found, FoundTag, TagFinder};
pub use error::TargetError;
pub use spec::{TagPlace, TargetSpec};
