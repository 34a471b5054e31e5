//! The application messages and the schema text whose hash every packet carries.

use serde::{Deserialize, Serialize};

/// Longest [`ErrorReport::text`], in UTF-8 bytes.
pub const ERROR_TEXT_MAX: usize = 64;

/// Bounded UTF-8 text of an [`ErrorReport`] (at most [`ERROR_TEXT_MAX`] bytes, no allocation).
pub type ErrorText = heapless::String<ERROR_TEXT_MAX>;

/// The message definitions, in the canonical form whose SHA-256 is the schema hash
/// ([`SCHEMA_HASH`], the first 8 bytes) carried by every packet. Peers whose definitions differ
/// refuse each other's packets. Any change to a message type (a field, its type or order, a
/// variant, its index) must change this text, which changes the hash; the golden vectors of
/// `golden/generate.py` (an independent encoder written from this text) catch a type changed
/// without it.
pub const SCHEMA: &str = "\
crackbot-link schema 2
Message = enum {
  0 Heartbeat
  1 MoveTo(MoveTo)
  2 Slide(Slide)
  3 Stop
  4 State(State)
  5 Error(ErrorReport)
  6 Done { slide_id: u32 }
}
MoveTo = struct { pose: Pose, speed_mm_s: f32, valid_until_us: u64 }
Slide = struct { id: u32, start: Point2, end: Point2, speed_mm_s: f32, contact: Contact, valid_until_us: u64 }
State = struct { controller_time_us: u64, pose: Pose, velocity: Velocity, mode: Mode, slide_progress: f32 }
ErrorReport = struct { seq: u32, code: ErrorCode, text: string<=64 }
Pose = struct { x_mm: f32, y_mm: f32, z_mm: f32 }
Point2 = struct { x_mm: f32, y_mm: f32 }
Velocity = struct { x_mm_s: f32, y_mm_s: f32, z_mm_s: f32 }
Contact = enum { 0 DepthMm(f32), 1 ForceN(f32) }
Mode = enum { 0 Idle, 1 Moving, 2 Sliding { id: u32 }, 3 Stopped, 4 Fault { code: u16 } }
ErrorCode = enum { 0 OutsideWorkspace, 1 OverSpeedLimit, 2 InvalidCommand, 3 Busy, 4 Faulted, 5 Unsupported, 6 Other, 7 Expired }
";

/// First 8 bytes of SHA-256([`SCHEMA`]) (checked by a unit test and by the golden vectors).
pub const SCHEMA_HASH: [u8; 8] = [0x6e, 0x48, 0x02, 0x0f, 0x29, 0x79, 0x25, 0x94];

/// A position of the finger tip in the surface frame, millimetres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Along the surface, mm.
    pub x_mm: f32,
    /// Along the surface, across x, mm.
    pub y_mm: f32,
    /// Normal to the surface, away from it, mm.
    pub z_mm: f32,
}

/// A point on the surface (surface frame), millimetres.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point2 {
    /// mm.
    pub x_mm: f32,
    /// mm.
    pub y_mm: f32,
}

/// A velocity in the surface frame, mm/s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Velocity {
    /// mm/s.
    pub x_mm_s: f32,
    /// mm/s.
    pub y_mm_s: f32,
    /// mm/s.
    pub z_mm_s: f32,
}

/// Host → controller: move (not in contact) to a pose.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MoveTo {
    /// Target pose.
    pub pose: Pose,
    /// Speed limit of the move, mm/s.
    pub speed_mm_s: f32,
    /// The controller's clock ([`State::controller_time_us`]) after which the move must not
    /// start: a command held back on the network is refused ([`ErrorCode::Expired`]) rather
    /// than run late. The host takes the newest state's time plus its allowed age.
    pub valid_until_us: u64,
}

/// How hard the finger presses while sliding.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Contact {
    /// Position control: tip this far below the surface, mm.
    DepthMm(f32),
    /// Force control: this normal force, newtons.
    ForceN(f32),
}

/// Host → controller: slide the finger in contact along a straight line.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Slide {
    /// Identifier of the slide, echoed in [`Mode::Sliding`] and [`Message::Done`].
    pub id: u32,
    /// Start of the line on the surface, mm.
    pub start: Point2,
    /// End of the line on the surface, mm.
    pub end: Point2,
    /// Sliding speed, mm/s.
    pub speed_mm_s: f32,
    /// Contact depth or force.
    pub contact: Contact,
    /// The controller's clock after which the slide must not start (as
    /// [`MoveTo::valid_until_us`]).
    pub valid_until_us: u64,
}

/// What the controller is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Mode {
    /// At rest, accepting commands.
    Idle,
    /// Executing a [`MoveTo`].
    Moving,
    /// Executing the [`Slide`] of this id.
    Sliding {
        /// The slide's id.
        id: u32,
    },
    /// Stopped by [`Message::Stop`]; a new command resumes.
    Stopped,
    /// Faulted (controller-specific code); needs attention.
    Fault {
        /// Controller-specific fault code.
        code: u16,
    },
}

/// Controller → host: the state, streamed at 100 Hz or more (unreliably: a lost one is
/// superseded by the next).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Controller clock, µs (monotonic; orders states regardless of packet order).
    pub controller_time_us: u64,
    /// Measured pose.
    pub pose: Pose,
    /// Measured velocity.
    pub velocity: Velocity,
    /// Current mode.
    pub mode: Mode,
    /// Fraction 0..=1 of the current slide done (0 when not sliding).
    pub slide_progress: f32,
}

/// Why the controller refused or aborted a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum ErrorCode {
    /// A target lies outside the workspace.
    OutsideWorkspace,
    /// A speed exceeds the controller's limit.
    OverSpeedLimit,
    /// A field is not finite or otherwise invalid.
    InvalidCommand,
    /// The controller cannot take this command now.
    Busy,
    /// The controller is in [`Mode::Fault`].
    Faulted,
    /// The controller does not implement this command.
    Unsupported,
    /// Anything else (see the text).
    Other,
    /// The command arrived after its `valid_until_us` (held back or delayed): not run.
    Expired,
}

/// Controller → host: a command was refused or failed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorReport {
    /// Sequence number of the packet of the command concerned (0: none).
    pub seq: u32,
    /// What went wrong.
    pub code: ErrorCode,
    /// Human-readable detail, at most [`ERROR_TEXT_MAX`] bytes.
    pub text: ErrorText,
}

impl ErrorReport {
    /// A report whose text is `text` cut to [`ERROR_TEXT_MAX`] bytes at a character boundary.
    pub fn new(seq: u32, code: ErrorCode, text: &str) -> Self {
        let mut end = text.len().min(ERROR_TEXT_MAX);
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        let mut t = ErrorText::new();
        // Cannot fail: `end` ≤ capacity.
        let _ = t.push_str(&text[..end]);
        Self { seq, code, text: t }
    }
}

/// An application message. The variant order is part of the wire format ([`SCHEMA`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Message {
    /// Either direction: liveness.
    Heartbeat,
    /// Host → controller.
    MoveTo(MoveTo),
    /// Host → controller.
    Slide(Slide),
    /// Host → controller: stop now.
    Stop,
    /// Controller → host, streamed.
    State(State),
    /// Controller → host.
    Error(ErrorReport),
    /// Controller → host: the slide of this id has finished.
    Done {
        /// The slide's id.
        slide_id: u32,
    },
}

impl Message {
    /// Short name of the variant (for logs).
    pub fn name(&self) -> &'static str {
        match self {
            Message::Heartbeat => "Heartbeat",
            Message::MoveTo(_) => "MoveTo",
            Message::Slide(_) => "Slide",
            Message::Stop => "Stop",
            Message::State(_) => "State",
            Message::Error(_) => "Error",
            Message::Done { .. } => "Done",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sha2::{Digest, Sha256};

    #[test]
    fn schema_hash_is_the_sha256_of_the_schema_text() {
        let h = Sha256::digest(SCHEMA.as_bytes());
        assert_eq!(
            h[..8],
            SCHEMA_HASH,
            "update SCHEMA_HASH to {:02x?} (and the Python generator's schema)",
            &h[..8]
        );
    }

    #[test]
    fn error_text_is_cut_at_a_char_boundary() {
        let long = "é".repeat(40); // 80 bytes
        let r = ErrorReport::new(3, ErrorCode::Other, &long);
        assert_eq!(r.text.len(), 64);
        assert!(r.text.chars().all(|c| c == 'é'));
    }
}
