//! Every value a command carries, checked once, before anything moves, into a type the arm can
//! trust ([`Checked`]): finite, inside the workspace and the height range, speeds between a sane
//! minimum and the limits, contact depth or force within the finger's rating, and not past the
//! command's `valid_until_us` (nor unreasonably far ahead of it). A refusal names the field
//! ([`CommandError`]) and becomes the `Error` reply ([`CommandError::report`]).
//!
//! [`check`] is a pure function of the message, the limits and the controller's clock, so it is
//! tested without sockets; the server and the fuzz target call it alike.

use crackbot_link::{Contact, ErrorCode, ErrorReport, Message};

use crate::limits::{Limits, MAX_MOVE_HEIGHT_MM, MIN_MOVE_HEIGHT_MM};

/// Slowest speed a move or slide may ask, mm/s (slower reads as "stay Moving for ever": a
/// subnormal speed would keep the arm busy until the watchdog).
pub const MIN_SPEED_MM_S: f64 = 0.1;
/// Shortest slide, mm.
pub const MIN_STROKE_MM: f64 = 0.5;
/// Longest slide, mm (the wire format's §11; the simulator's `MAX_STROKE_MM` is the same).
pub const MAX_STROKE_MM: f64 = 2000.0;
/// Deepest position-controlled contact, mm below the surface.
pub const MAX_DEPTH_MM: f64 = 3.0;
/// Smallest and largest force-controlled contact, N (the fibre finger's rating).
pub const FORCE_RANGE_N: (f64, f64) = (0.05, 5.0);
/// Farthest a command's `valid_until_us` may lie ahead of the controller's clock, µs: a deadline
/// further out is no deadline (10 s).
pub const MAX_VALIDITY_US: u64 = 10_000_000;

/// A command with every value checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Checked {
    /// Liveness only.
    Heartbeat,
    /// Stop now.
    Stop,
    /// A checked move.
    Move(CheckedMove),
    /// A checked slide.
    Slide(CheckedSlide),
}

/// A move whose target, height and speed are within the limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckedMove {
    /// Target on the surface, mm.
    pub to: [f64; 2],
    /// Height of the tip above the plate, mm.
    pub z_mm: f64,
    /// Speed, mm/s.
    pub speed_mm_s: f64,
}

/// A slide whose ends, length, speed and contact are within the limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckedSlide {
    /// The slide's id.
    pub id: u32,
    /// Start on the surface, mm.
    pub start: [f64; 2],
    /// End on the surface, mm.
    pub end: [f64; 2],
    /// Speed, mm/s.
    pub speed_mm_s: f64,
    /// Contact depth (mm) or force (N).
    pub contact: Contact,
}

/// Why a command was refused: the field and what it held.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CommandError {
    /// A value is NaN or infinite.
    #[error("{field} is {value}, not a finite number")]
    NotFinite {
        /// The field, e.g. `MoveTo.speed_mm_s`.
        field: &'static str,
        /// What it held.
        value: f64,
    },
    /// A value is outside its range.
    #[error("{field} = {value} is outside [{min}, {max}]")]
    OutOfRange {
        /// The field.
        field: &'static str,
        /// What it held.
        value: f64,
        /// Smallest allowed.
        min: f64,
        /// Largest allowed.
        max: f64,
    },
    /// The command arrived after its deadline.
    #[error("{field} {valid_until_us} µs has passed (controller clock {now_us} µs)")]
    Expired {
        /// The field.
        field: &'static str,
        /// The deadline.
        valid_until_us: u64,
        /// The controller's clock.
        now_us: u64,
    },
    /// The deadline lies too far ahead to be one.
    #[error("{field} {valid_until_us} µs is more than {MAX_VALIDITY_US} µs after the controller clock {now_us} µs")]
    DeadlineTooFar {
        /// The field.
        field: &'static str,
        /// The deadline.
        valid_until_us: u64,
        /// The controller's clock.
        now_us: u64,
    },
    /// The message is not a command the controller takes.
    #[error("the controller does not take {0} messages")]
    NotACommand(&'static str),
}

impl CommandError {
    /// The link's error code for this refusal.
    /// A value out of range or not finite gets its field's own code (the wire format's §11): a
    /// speed `OverSpeedLimit`, a point `OutsideWorkspace`, any other `InvalidCommand`.
    pub fn code(&self) -> ErrorCode {
        match self {
            CommandError::OutOfRange { field, .. } | CommandError::NotFinite { field, .. } => {
                field_code(field)
            }
            CommandError::Expired { .. } => ErrorCode::Expired,
            CommandError::NotACommand(_) => ErrorCode::Unsupported,
            CommandError::DeadlineTooFar { .. } => ErrorCode::InvalidCommand,
        }
    }

    /// The `Error` reply to the command sent as packet `seq`.
    pub fn report(&self, seq: u32) -> ErrorReport {
        ErrorReport::new(seq, self.code(), &self.to_string())
    }
}

/// The code a bad value of `field` is refused with.
fn field_code(field: &str) -> ErrorCode {
    if field.contains("_mm_s") {
        ErrorCode::OverSpeedLimit
    } else if field.ends_with(".x_mm") || field.ends_with(".y_mm") {
        ErrorCode::OutsideWorkspace
    } else {
        ErrorCode::InvalidCommand
    }
}

fn in_range(field: &'static str, value: f32, min: f64, max: f64) -> Result<f64, CommandError> {
    let v = f64::from(value);
    if !v.is_finite() {
        return Err(CommandError::NotFinite { field, value: v });
    }
    if !(min..=max).contains(&v) {
        return Err(CommandError::OutOfRange {
            field,
            value: v,
            min,
            max,
        });
    }
    Ok(v)
}

fn deadline(field: &'static str, valid_until_us: u64, now_us: u64) -> Result<(), CommandError> {
    if valid_until_us < now_us {
        return Err(CommandError::Expired {
            field,
            valid_until_us,
            now_us,
        });
    }
    if valid_until_us - now_us > MAX_VALIDITY_US {
        return Err(CommandError::DeadlineTooFar {
            field,
            valid_until_us,
            now_us,
        });
    }
    Ok(())
}

fn point(
    limits: &Limits,
    (fx, fy): (&'static str, &'static str),
    x: f32,
    y: f32,
) -> Result<[f64; 2], CommandError> {
    Ok([
        in_range(fx, x, limits.min_mm[0], limits.max_mm[0])?,
        in_range(fy, y, limits.min_mm[1], limits.max_mm[1])?,
    ])
}

/// Checks `message` against `limits` at controller time `now_us`.
pub fn check(message: &Message, limits: &Limits, now_us: u64) -> Result<Checked, CommandError> {
    match message {
        Message::Heartbeat => Ok(Checked::Heartbeat),
        Message::Stop => Ok(Checked::Stop),
        Message::MoveTo(m) => {
            let p = m.pose;
            let to = point(
                limits,
                ("MoveTo.pose.x_mm", "MoveTo.pose.y_mm"),
                p.x_mm,
                p.y_mm,
            )?;
            let z_mm = in_range(
                "MoveTo.pose.z_mm",
                p.z_mm,
                MIN_MOVE_HEIGHT_MM,
                MAX_MOVE_HEIGHT_MM,
            )?;
            let speed_mm_s = in_range(
                "MoveTo.speed_mm_s",
                m.speed_mm_s,
                MIN_SPEED_MM_S,
                limits.max_travel_speed_mm_s,
            )?;
            deadline("MoveTo.valid_until_us", m.valid_until_us, now_us)?;
            Ok(Checked::Move(CheckedMove {
                to,
                z_mm,
                speed_mm_s,
            }))
        }
        Message::Slide(s) => check_slide(s, limits, now_us).map(Checked::Slide),
        other => Err(CommandError::NotACommand(other.name())),
    }
}

fn check_slide(
    s: &crackbot_link::Slide,
    limits: &Limits,
    now_us: u64,
) -> Result<CheckedSlide, CommandError> {
    let start = point(
        limits,
        ("Slide.start.x_mm", "Slide.start.y_mm"),
        s.start.x_mm,
        s.start.y_mm,
    )?;
    let end = point(
        limits,
        ("Slide.end.x_mm", "Slide.end.y_mm"),
        s.end.x_mm,
        s.end.y_mm,
    )?;
    let length = (end[0] - start[0]).hypot(end[1] - start[1]);
    if !(MIN_STROKE_MM..=MAX_STROKE_MM).contains(&length) {
        return Err(CommandError::OutOfRange {
            field: "Slide length (start to end)",
            value: length,
            min: MIN_STROKE_MM,
            max: MAX_STROKE_MM,
        });
    }
    let speed_mm_s = in_range(
        "Slide.speed_mm_s",
        s.speed_mm_s,
        MIN_SPEED_MM_S,
        limits.max_slide_speed_mm_s,
    )?;
    let contact = match s.contact {
        Contact::DepthMm(d) => {
            Contact::DepthMm(in_range("Slide.contact.DepthMm", d, 0.0, MAX_DEPTH_MM)? as f32)
        }
        Contact::ForceN(f) => {
            Contact::ForceN(
                in_range("Slide.contact.ForceN", f, FORCE_RANGE_N.0, FORCE_RANGE_N.1)? as f32,
            )
        }
        _ => return Err(CommandError::NotACommand("Slide with an unknown contact")),
    };
    deadline("Slide.valid_until_us", s.valid_until_us, now_us)?;
    Ok(CheckedSlide {
        id: s.id,
        start,
        end,
        speed_mm_s,
        contact,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crackbot_link::{MoveTo, Point2, Pose, Slide};

    fn limits() -> Limits {
        Limits {
            min_mm: [0.0, 0.0],
            max_mm: [200.0, 100.0],
            max_travel_speed_mm_s: 100.0,
            max_slide_speed_mm_s: 20.0,
        }
    }

    const NOW: u64 = 5_000_000;

    fn slide(f: impl FnOnce(&mut Slide)) -> Message {
        let mut s = Slide {
            id: 3,
            start: Point2 {
                x_mm: 10.0,
                y_mm: 10.0,
            },
            end: Point2 {
                x_mm: 60.0,
                y_mm: 10.0,
            },
            speed_mm_s: 3.89,
            contact: Contact::DepthMm(1.0),
            valid_until_us: NOW + 500_000,
        };
        f(&mut s);
        Message::Slide(s)
    }

    fn move_to(f: impl FnOnce(&mut MoveTo)) -> Message {
        let mut m = MoveTo {
            pose: Pose {
                x_mm: 50.0,
                y_mm: 50.0,
                z_mm: 5.0,
            },
            speed_mm_s: 20.0,
            valid_until_us: NOW + 500_000,
        };
        f(&mut m);
        Message::MoveTo(m)
    }

    fn field(r: Result<Checked, CommandError>) -> &'static str {
        match r {
            Err(
                CommandError::NotFinite { field, .. }
                | CommandError::OutOfRange { field, .. }
                | CommandError::Expired { field, .. }
                | CommandError::DeadlineTooFar { field, .. },
            ) => field,
            other => panic!("not a field refusal: {other:?}"),
        }
    }

    #[test]
    fn good_commands_pass_with_their_values() {
        let l = limits();
        assert!(matches!(
            check(&move_to(|_| {}), &l, NOW),
            Ok(Checked::Move(m)) if m.to == [50.0, 50.0] && m.z_mm == 5.0
        ));
        assert!(matches!(
            check(&slide(|_| {}), &l, NOW),
            Ok(Checked::Slide(s)) if s.id == 3 && s.end == [60.0, 10.0]
        ));
        assert_eq!(check(&Message::Stop, &l, NOW), Ok(Checked::Stop));
    }

    #[test]
    fn contact_depth_and_force_out_of_range_or_not_finite_are_refused_by_name() {
        let l = limits();
        for bad in [1e6_f32, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let r = check(&slide(|s| s.contact = Contact::DepthMm(bad)), &l, NOW);
            assert_eq!(field(r), "Slide.contact.DepthMm", "{bad}");
            let r = check(&slide(|s| s.contact = Contact::ForceN(bad)), &l, NOW);
            assert_eq!(field(r), "Slide.contact.ForceN", "{bad}");
        }
    }

    #[test]
    fn subnormal_zero_negative_and_excess_speeds_are_refused() {
        let l = limits();
        for bad in [1.4e-45_f32, 0.0, -5.0, 1e6, f32::NAN] {
            let r = check(&move_to(|m| m.speed_mm_s = bad), &l, NOW);
            assert_eq!(field(r.clone()), "MoveTo.speed_mm_s", "{bad}");
            let r = check(&slide(|s| s.speed_mm_s = bad), &l, NOW);
            assert_eq!(field(r), "Slide.speed_mm_s", "{bad}");
        }
        let e = check(&move_to(|m| m.speed_mm_s = 1e6), &l, NOW).unwrap_err();
        assert_eq!(e.code(), ErrorCode::OverSpeedLimit);
    }

    #[test]
    fn poses_outside_the_workspace_or_heights_are_refused() {
        let l = limits();
        let e = check(&move_to(|m| m.pose.x_mm = 250.0), &l, NOW).unwrap_err();
        assert_eq!(e.code(), ErrorCode::OutsideWorkspace);
        assert!(e.to_string().contains("MoveTo.pose.x_mm"), "{e}");
        for z in [0.0_f32, 0.2, 60.0, f32::NAN] {
            let r = check(&move_to(|m| m.pose.z_mm = z), &l, NOW);
            assert_eq!(field(r), "MoveTo.pose.z_mm", "{z}");
        }
        let r = check(&slide(|s| s.end.y_mm = f32::INFINITY), &l, NOW);
        assert_eq!(field(r), "Slide.end.y_mm");
        let r = check(&slide(|s| s.end.x_mm = 10.1), &l, NOW);
        assert_eq!(field(r), "Slide length (start to end)");
    }

    #[test]
    fn late_commands_expire_and_far_deadlines_are_refused() {
        let l = limits();
        let e = check(&move_to(|m| m.valid_until_us = NOW - 1), &l, NOW).unwrap_err();
        assert_eq!(e.code(), ErrorCode::Expired);
        assert_eq!(
            field(check(&slide(|s| s.valid_until_us = 0), &l, NOW)),
            "Slide.valid_until_us"
        );
        let r = check(&move_to(|m| m.valid_until_us = u64::MAX), &l, NOW);
        assert!(
            matches!(r, Err(CommandError::DeadlineTooFar { .. })),
            "{r:?}"
        );
        // The deadline itself is still in time.
        assert!(check(&move_to(|m| m.valid_until_us = NOW), &l, NOW).is_ok());
    }

    #[test]
    fn a_value_that_is_not_a_number_gets_its_fields_own_code() {
        let l = limits();
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let code = |m: Message| check(&m, &l, NOW).unwrap_err().code();
            assert_eq!(
                code(move_to(|m| m.speed_mm_s = bad)),
                ErrorCode::OverSpeedLimit
            );
            assert_eq!(
                code(slide(|s| s.speed_mm_s = bad)),
                ErrorCode::OverSpeedLimit
            );
            assert_eq!(
                code(move_to(|m| m.pose.x_mm = bad)),
                ErrorCode::OutsideWorkspace
            );
            assert_eq!(
                code(slide(|s| s.start.y_mm = bad)),
                ErrorCode::OutsideWorkspace
            );
            assert_eq!(
                code(move_to(|m| m.pose.z_mm = bad)),
                ErrorCode::InvalidCommand
            );
            assert_eq!(
                code(slide(|s| s.contact = Contact::DepthMm(bad))),
                ErrorCode::InvalidCommand
            );
        }
    }

    #[test]
    fn what_the_controller_sends_is_not_a_command() {
        let e = check(&Message::Done { slide_id: 1 }, &limits(), NOW).unwrap_err();
        assert_eq!(e, CommandError::NotACommand("Done"));
        assert_eq!(e.report(7).seq, 7);
        assert_eq!(e.report(7).code, ErrorCode::Unsupported);
    }
}
