//! The cases, each a function of the host and what the controller should accept: it drives the
//! controller and says what it saw, or what went wrong.

use std::time::{Duration, Instant};

use crackbot_link::{Contact, ErrorCode, Message, Mode, MoveTo, Point2, Pose, Slide};

use crate::host::{Host, HostError};
use crate::Expect;

/// A case's verdict: `Ok(what it saw)` or `Err(what went wrong)`.
pub type Verdict = Result<String, String>;

#[expect(
    clippy::needless_pass_by_value,
    reason = "`map_err` hands the error over by value"
)]
fn io(e: HostError) -> String {
    e.to_string()
}

/// A move message.
pub fn move_to(p: [f64; 3], speed: f64, valid_until_us: u64) -> Message {
    Message::MoveTo(MoveTo {
        pose: Pose {
            x_mm: p[0] as f32,
            y_mm: p[1] as f32,
            z_mm: p[2] as f32,
        },
        speed_mm_s: speed as f32,
        valid_until_us,
    })
}

/// A slide message.
pub fn slide(
    id: u32,
    start: [f64; 2],
    end: [f64; 2],
    speed: f64,
    contact: Contact,
    valid_until_us: u64,
) -> Message {
    let p = |q: [f64; 2]| Point2 {
        x_mm: q[0] as f32,
        y_mm: q[1] as f32,
    };
    Message::Slide(Slide {
        id,
        start: p(start),
        end: p(end),
        speed_mm_s: speed as f32,
        contact,
        valid_until_us,
    })
}

const SOON: Duration = Duration::from_secs(1);

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// Brings the arm to `p` (lifted) and waits until it is idle there.
pub fn park(h: &mut Host, e: &Expect, p: [f64; 3]) -> Verdict {
    let m = move_to(p, e.travel_speed(), h.deadline(SOON));
    let seq = h.send(&m).map_err(io)?;
    let within = Duration::from_secs_f64(e.travel_time(h.pose(), p) + 15.0);
    let arrived = h
        .pump_until(within, |h| {
            h.mode() == Mode::Idle && distance(h.pose(), p) < 1.0
        })
        .map_err(io)?;
    if let Some(r) = h.refusal_of(seq, Duration::ZERO).map_err(io)? {
        return Err(format!(
            "the move to {p:?} was refused: {:?} {}",
            r.code, r.text
        ));
    }
    if arrived {
        Ok(format!("parked at ({:.1}, {:.1}, {:.1})", p[0], p[1], p[2]))
    } else {
        Err(format!(
            "not idle at {p:?} within {within:?}: mode {:?}, pose {:?}",
            h.mode(),
            h.pose()
        ))
    }
}

/// The state stream: at least 100 states a second, a clock that never goes back and keeps time.
pub fn state_stream(h: &mut Host, _: &Expect) -> Verdict {
    h.take_states();
    h.pump(Duration::from_secs(2)).map_err(io)?;
    let s = h.take_states();
    if s.len() < 2 {
        return Err(format!("{} states in 2 s", s.len()));
    }
    let span = s[s.len() - 1].at.duration_since(s[0].at).as_secs_f64();
    let rate = (s.len() - 1) as f64 / span;
    let mut gaps: Vec<f64> = s
        .windows(2)
        .map(|w| w[1].at.duration_since(w[0].at).as_secs_f64() * 1e3)
        .collect();
    gaps.sort_by(f64::total_cmp);
    let p99 = gaps[((gaps.len() as f64 * 0.99).ceil() as usize).clamp(1, gaps.len()) - 1];
    if let Some(w) = s
        .windows(2)
        .find(|w| w[1].state.controller_time_us < w[0].state.controller_time_us)
    {
        return Err(format!(
            "the clock went back: {} → {} µs",
            w[0].state.controller_time_us, w[1].state.controller_time_us
        ));
    }
    let ticked = (s[s.len() - 1].state.controller_time_us - s[0].state.controller_time_us) as f64;
    let clock_rate = ticked / (span * 1e6);
    let detail =
        format!("{rate:.1} states/s, p99 gap {p99:.1} ms, clock at {clock_rate:.4}× real time");
    if rate < 95.0 {
        return Err(format!("{detail}: under 100 states/s"));
    }
    if (clock_rate - 1.0).abs() > 0.02 {
        return Err(format!("{detail}: the clock does not keep time (±2 %)"));
    }
    Ok(detail)
}

/// A move inside the workspace: Moving, then Idle at the target.
pub fn legitimate_move(h: &mut Host, e: &Expect) -> Verdict {
    park(h, e, e.spot(0.2, 0.3, 10.0))?;
    let to = e.spot(0.6, 0.7, 8.0);
    let seq = h
        .send(&move_to(to, e.travel_speed(), h.deadline(SOON)))
        .map_err(io)?;
    let moving = h
        .pump_until(Duration::from_secs(2), |h| h.mode() == Mode::Moving)
        .map_err(io)?;
    if let Some(r) = h.refusal_of(seq, Duration::ZERO).map_err(io)? {
        return Err(format!("refused: {:?} {}", r.code, r.text));
    }
    if !moving {
        return Err(format!("never Moving (mode {:?})", h.mode()));
    }
    let started = Instant::now();
    let done = h
        .pump_until(Duration::from_secs(30), |h| {
            h.mode() == Mode::Idle && distance(h.pose(), to) < 1.0
        })
        .map_err(io)?;
    if !done {
        return Err(format!(
            "not idle at {to:?}: {:?} at {:?}",
            h.mode(),
            h.pose()
        ));
    }
    Ok(format!(
        "Moving, then Idle within {:.1} mm of the target after {:.1} s",
        distance(h.pose(), to),
        started.elapsed().as_secs_f64()
    ))
}

/// A slide: Sliding with its id, progress rising to 1, `Done`, the finger at the end.
pub fn legitimate_slide(h: &mut Host, e: &Expect) -> Verdict {
    let (a, b) = (e.spot(0.3, 0.5, 0.0), e.spot(0.3, 0.5, 0.0));
    let (start, end) = ([a[0], a[1]], [b[0] + 12.0, b[1]]);
    let id = 901;
    let speed = e.slide_speed();
    h.send(&slide(
        id,
        start,
        end,
        speed,
        Contact::DepthMm(1.0),
        h.deadline(SOON),
    ))
    .map_err(io)?;
    let mut progress: Vec<f32> = Vec::new();
    let within = Duration::from_secs_f64(e.travel_time(h.pose(), a) + 12.0 / speed + 20.0);
    let done = h
        .pump_until(within, |h| {
            if let Some(s) = h.last() {
                if s.mode == (Mode::Sliding { id }) {
                    progress.push(s.slide_progress);
                }
            }
            h.done(id)
        })
        .map_err(io)?;
    if !done {
        return Err(format!("no Done for slide {id} within {within:?}"));
    }
    if progress.is_empty() {
        return Err("never Sliding with the slide's id".into());
    }
    let most = progress.iter().copied().fold(0.0f32, f32::max);
    if progress.windows(2).any(|w| w[1] + 1e-3 < w[0]) || !(0.9..=1.0).contains(&most) {
        return Err(format!("slide_progress not rising to 1: reached {most}"));
    }
    h.pump(Duration::from_millis(100)).map_err(io)?;
    let p = h.pose();
    let off = (p[0] - end[0]).hypot(p[1] - end[1]);
    if off > 1.0 {
        return Err(format!(
            "Done, but the finger is {off:.1} mm from the slide's end"
        ));
    }
    Ok(format!(
        "Sliding, progress to {most:.2}, Done, {off:.2} mm from the end"
    ))
}

/// One command that must be refused with `code`, its text starting with `field`.
struct Bad {
    message: Message,
    code: ErrorCode,
    field: &'static str,
}

fn bad_commands(h: &Host, e: &Expect) -> Vec<Bad> {
    let ok = e.spot(0.5, 0.5, 10.0);
    let d = h.deadline(SOON);
    let outside = [e.max_mm[0] + 50.0, ok[1], 10.0];
    let a = [ok[0], ok[1]];
    let b = [ok[0] + 10.0, ok[1]];
    let bad = |message, code, field| Bad {
        message,
        code,
        field,
    };
    let depth = |v: f32| Contact::DepthMm(v);
    vec![
        bad(
            move_to(outside, 10.0, d),
            ErrorCode::OutsideWorkspace,
            "MoveTo.pose.x_mm",
        ),
        bad(
            move_to([ok[0], f64::NAN, 10.0], 10.0, d),
            ErrorCode::OutsideWorkspace,
            "MoveTo.pose.y_mm",
        ),
        bad(
            move_to([ok[0], ok[1], 0.1], 10.0, d),
            ErrorCode::InvalidCommand,
            "MoveTo.pose.z_mm",
        ),
        bad(
            move_to([ok[0], ok[1], f64::INFINITY], 10.0, d),
            ErrorCode::InvalidCommand,
            "MoveTo.pose.z_mm",
        ),
        bad(
            move_to(ok, e.max_travel_mm_s * 2.0, d),
            ErrorCode::OverSpeedLimit,
            "MoveTo.speed_mm_s",
        ),
        bad(
            move_to(ok, 1.4e-45, d),
            ErrorCode::OverSpeedLimit,
            "MoveTo.speed_mm_s",
        ),
        bad(
            move_to(ok, f64::NAN, d),
            ErrorCode::OverSpeedLimit,
            "MoveTo.speed_mm_s",
        ),
        bad(
            move_to(ok, 10.0, h.deadline(Duration::from_secs(60))),
            ErrorCode::InvalidCommand,
            "MoveTo.valid_until_us",
        ),
        bad(
            slide(7, [outside[0], outside[1]], b, 4.0, depth(1.0), d),
            ErrorCode::OutsideWorkspace,
            "Slide.start.x_mm",
        ),
        bad(
            slide(7, a, [b[0], f64::NAN], 4.0, depth(1.0), d),
            ErrorCode::OutsideWorkspace,
            "Slide.end.y_mm",
        ),
        bad(
            slide(7, a, [a[0] + 0.1, a[1]], 4.0, depth(1.0), d),
            ErrorCode::InvalidCommand,
            "Slide length",
        ),
        bad(
            slide(7, a, b, e.max_slide_mm_s * 2.0, depth(1.0), d),
            ErrorCode::OverSpeedLimit,
            "Slide.speed_mm_s",
        ),
        bad(
            slide(7, a, b, 4.0, depth(4.0), d),
            ErrorCode::InvalidCommand,
            "Slide.contact.DepthMm",
        ),
        bad(
            slide(7, a, b, 4.0, depth(-1.0), d),
            ErrorCode::InvalidCommand,
            "Slide.contact.DepthMm",
        ),
        bad(
            slide(7, a, b, 4.0, depth(f32::NAN), d),
            ErrorCode::InvalidCommand,
            "Slide.contact.DepthMm",
        ),
        bad(
            slide(7, a, b, 4.0, Contact::ForceN(10.0), d),
            ErrorCode::InvalidCommand,
            "Slide.contact.ForceN",
        ),
    ]
}

/// Every value a command carries, out of range or not finite: refused by field, nothing moves.
pub fn refusals(h: &mut Host, e: &Expect) -> Verdict {
    let home = e.spot(0.5, 0.5, 10.0);
    park(h, e, home)?;
    let cases = bad_commands(h, e);
    for c in &cases {
        let seq = h.send(&c.message).map_err(io)?;
        let Some(r) = h.refusal_of(seq, Duration::from_secs(2)).map_err(io)? else {
            return Err(format!("{}: not refused", c.field));
        };
        if r.code != c.code || !r.text.starts_with(c.field) {
            return Err(format!(
                "{}: refused with {:?} \"{}\", expected {:?} and a text starting with the field",
                c.field, r.code, r.text, c.code
            ));
        }
        h.pump(Duration::from_millis(100)).map_err(io)?;
        if matches!(h.mode(), Mode::Moving | Mode::Sliding { .. }) || distance(h.pose(), home) > 1.0
        {
            return Err(format!(
                "{}: refused, but the arm moved ({:?}, {:?})",
                c.field,
                h.mode(),
                h.pose()
            ));
        }
    }
    Ok(format!(
        "{} bad commands refused by field, nothing moved",
        cases.len()
    ))
}

/// A command whose deadline has passed: `Expired`, nothing moves.
pub fn expired(h: &mut Host, e: &Expect) -> Verdict {
    let home = e.spot(0.5, 0.5, 10.0);
    park(h, e, home)?;
    let late = h.controller_now_us().saturating_sub(300_000).max(1);
    let seq = h
        .send(&move_to(e.spot(0.1, 0.1, 10.0), 20.0, late))
        .map_err(io)?;
    let Some(r) = h.refusal_of(seq, Duration::from_secs(2)).map_err(io)? else {
        return Err("a move 300 ms past its deadline was not refused".into());
    };
    if r.code != ErrorCode::Expired || !r.text.starts_with("MoveTo.valid_until_us") {
        return Err(format!(
            "refused with {:?} \"{}\", expected Expired",
            r.code, r.text
        ));
    }
    h.pump(Duration::from_millis(300)).map_err(io)?;
    if distance(h.pose(), home) > 1.0 {
        return Err("refused, but the arm moved".into());
    }
    Ok("Expired, nothing moved".into())
}

/// Stops and checks that the state says Stopped within 250 ms and the arm stays put.
fn stop_now(h: &mut Host, when: &str) -> Result<f64, String> {
    let sent = Instant::now();
    h.send(&Message::Stop).map_err(io)?;
    let stopped = h
        .pump_until(Duration::from_millis(250), |h| h.mode() == Mode::Stopped)
        .map_err(io)?;
    if !stopped {
        return Err(format!(
            "{when}: not Stopped 250 ms after the Stop ({:?})",
            h.mode()
        ));
    }
    let took = sent.elapsed().as_secs_f64() * 1e3;
    let at = h.pose();
    h.pump(Duration::from_millis(500)).map_err(io)?;
    let drift = distance(h.pose(), at);
    if drift > 1.5 || h.mode() != Mode::Stopped {
        return Err(format!(
            "{when}: after the Stop the arm went on {drift:.1} mm ({:?})",
            h.mode()
        ));
    }
    Ok(took)
}

/// A stop while idle, while stopped, while moving and while sliding; a command after it runs.
pub fn stop_in_every_state(h: &mut Host, e: &Expect) -> Verdict {
    park(h, e, e.spot(0.1, 0.2, 10.0))?;
    let idle = stop_now(h, "idle")?;
    let again = stop_now(h, "stopped")?;
    h.send(&move_to(e.spot(0.9, 0.8, 10.0), 20.0, h.deadline(SOON)))
        .map_err(io)?;
    if !h
        .pump_until(Duration::from_secs(2), |h| h.mode() == Mode::Moving)
        .map_err(io)?
    {
        return Err(format!("after a stop, a move did not run ({:?})", h.mode()));
    }
    h.pump(Duration::from_millis(300)).map_err(io)?;
    let moving = stop_now(h, "moving")?;
    let a = e.spot(0.4, 0.4, 0.0);
    let id = 902;
    h.send(&slide(
        id,
        [a[0], a[1]],
        [a[0] + 15.0, a[1]],
        e.slide_speed(),
        Contact::DepthMm(1.0),
        h.deadline(SOON),
    ))
    .map_err(io)?;
    let pressed = h
        .pump_until(Duration::from_secs(20), |h| {
            h.mode() == (Mode::Sliding { id }) && h.pose()[2] < 0.5
        })
        .map_err(io)?;
    if !pressed {
        return Err(format!(
            "slide {id} never pressed the finger on ({:?}, {:?})",
            h.mode(),
            h.pose()
        ));
    }
    h.pump(Duration::from_millis(500)).map_err(io)?;
    let sliding = stop_now(h, "sliding")?;
    h.pump(Duration::from_secs(1)).map_err(io)?;
    if h.done(id) {
        return Err(format!("slide {id} was stopped, yet reported Done"));
    }
    park(h, e, e.spot(0.5, 0.5, 10.0))?;
    Ok(format!(
        "Stopped within {idle:.0} / {again:.0} / {moving:.0} / {sliding:.0} ms (idle / stopped / moving / sliding), then moves again"
    ))
}

/// The host falls silent while the arm moves: the controller stops it.
pub fn watchdog(h: &mut Host, e: &Expect) -> Verdict {
    park(h, e, e.spot(0.05, 0.5, 10.0))?;
    h.send(&move_to(e.spot(0.95, 0.5, 10.0), 10.0, h.deadline(SOON)))
        .map_err(io)?;
    if !h
        .pump_until(Duration::from_secs(2), |h| h.mode() == Mode::Moving)
        .map_err(io)?
    {
        return Err("the long move never started".into());
    }
    let silent = Instant::now();
    h.take_states();
    h.listen_silently(e.watchdog + Duration::from_millis(1500))
        .map_err(io)?;
    let states = h.take_states();
    let Some(first) = states.iter().find(|s| s.state.mode == Mode::Stopped) else {
        return Err(format!(
            "still {:?} after {:?} of silence",
            h.mode(),
            silent.elapsed()
        ));
    };
    let after = first.at.duration_since(silent).as_secs_f64();
    if after > e.watchdog.as_secs_f64() + 0.5 {
        return Err(format!("stopped only {after:.2} s into the silence"));
    }
    Ok(format!("stopped {after:.2} s into the host's silence"))
}
