//! What the app's headless tests share.

use std::time::{Duration, Instant};

use crackbot_operator::OperatorApp;
use egui_kittest::Harness;

/// Steps the UI until `done` holds (missions run on their own threads meanwhile); fails with
/// the app's log after `limit`.
pub fn step_until(
    h: &mut Harness<'_, OperatorApp>,
    what: &str,
    limit: Duration,
    done: impl Fn(&OperatorApp) -> bool,
) {
    let t = Instant::now();
    while !done(h.state()) {
        assert!(
            t.elapsed() < limit,
            "timed out after {limit:?} waiting for {what}; log: {:?}",
            h.state().log
        );
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    h.step();
}
