//! The sliding anti-replay window (RFC 4303 §3.4.3 / RFC 6479 style), over 64-bit counters.

/// Width of the window: a counter up to `WINDOW - 1` below the highest accepted one is still
/// accepted once (a packet reordered by up to 127 packets).
pub const WINDOW: u64 = 128;

/// Default largest forward jump of a counter accepted directly ([`ReplayWindow::check`]); a
/// larger one needs a challenge (see the crate docs, "Replay protection").
pub const DEFAULT_MAX_JUMP: u64 = 1024;

/// What the window says about a counter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Not seen, inside the window or ahead of it by at most the jump limit: accept (then call
    /// [`ReplayWindow::accept`]).
    Fresh,
    /// Inside the window and already accepted.
    Replay,
    /// Below the window (`top - counter >= WINDOW`): too old to tell, refused.
    TooOld,
    /// More than the jump limit ahead of the highest accepted counter.
    TooFarAhead,
}

/// Which counters were accepted: the highest (`top`) and a bitmap of the [`WINDOW`] counters
/// ending at it (bit `i` set: counter `top - i` was accepted). The state only ever moves
/// forward, so a counter is accepted at most once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReplayWindow {
    top: u64,
    seen: u128,
}

impl Default for ReplayWindow {
    fn default() -> Self {
        Self::new()
    }
}

impl ReplayWindow {
    /// A window that has accepted counter 0 only (counters start at 1).
    pub const fn new() -> Self {
        Self { top: 0, seen: 1 }
    }

    /// A window after a resynchronisation at `counter`: that counter and everything below it
    /// count as accepted.
    pub const fn starting_at(counter: u64) -> Self {
        Self {
            top: counter,
            seen: u128::MAX,
        }
    }

    /// The highest accepted counter.
    pub const fn top(&self) -> u64 {
        self.top
    }

    /// The verdict on `counter`, changing nothing.
    pub fn check(&self, counter: u64, max_jump: u64) -> Verdict {
        if counter > self.top {
            if counter - self.top > max_jump {
                Verdict::TooFarAhead
            } else {
                Verdict::Fresh
            }
        } else {
            let back = self.top - counter;
            if back >= WINDOW {
                Verdict::TooOld
            } else if self.seen & (1u128 << back) != 0 {
                Verdict::Replay
            } else {
                Verdict::Fresh
            }
        }
    }

    /// Records `counter` as accepted (after its tag verified). Moving the window ahead forgets
    /// the counters that fall out of it (they are refused as [`Verdict::TooOld`] from then on).
    pub fn accept(&mut self, counter: u64) {
        if counter > self.top {
            let shift = counter - self.top;
            self.seen = if shift >= WINDOW {
                0
            } else {
                self.seen << shift
            };
            self.seen |= 1;
            self.top = counter;
        } else {
            let back = self.top - counter;
            if back < WINDOW {
                self.seen |= 1u128 << back;
            }
        }
    }

    /// Records the sequence number `seq` of a reliable message (a window over sequence numbers:
    /// no jump limit). Returns `Some(Verdict::Fresh)` when it is new (recorded), `None` when it
    /// was already recorded (a retry of a delivered message), and `Some(Verdict::TooOld)` when
    /// it lies a whole window or more below the highest one: the window then restarts at
    /// `seq`. A live peer never sends that (its packets inside the counter window are at most
    /// [`WINDOW`] − 1 messages apart), so the window's state is wrong, not the message: one
    /// wrong sequence number (a faulty peer's `u32::MAX`) must not silence the peer for ever.
    pub fn record_sequence(&mut self, seq: u64) -> Option<Verdict> {
        match self.check(seq, u64::MAX) {
            Verdict::Fresh => {
                self.accept(seq);
                Some(Verdict::Fresh)
            }
            Verdict::TooOld => {
                *self = Self { top: seq, seen: 1 };
                Some(Verdict::TooOld)
            }
            Verdict::Replay | Verdict::TooFarAhead => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reordered_counters_are_accepted_once() {
        let mut w = ReplayWindow::new();
        for c in [5u64, 3, 4, 1, 2] {
            assert_eq!(w.check(c, 1024), Verdict::Fresh, "{c}");
            w.accept(c);
        }
        for c in 0..=5 {
            assert_eq!(w.check(c, 1024), Verdict::Replay, "{c}");
        }
        assert_eq!(w.check(6, 1024), Verdict::Fresh);
    }

    #[test]
    fn window_edges() {
        let mut w = ReplayWindow::new();
        w.accept(1000);
        assert_eq!(w.check(1000 - 127, 1024), Verdict::Fresh);
        assert_eq!(w.check(1000 - 128, 1024), Verdict::TooOld);
        assert_eq!(w.check(1000 + 1024, 1024), Verdict::Fresh);
        assert_eq!(w.check(1000 + 1025, 1024), Verdict::TooFarAhead);
        assert_eq!(w.check(u64::MAX, 1024), Verdict::TooFarAhead);
        w.accept(1000 + 127);
        assert_eq!(w.check(1000, 1024), Verdict::Replay);
        w.accept(1000 + 128);
        assert_eq!(w.check(1000, 1024), Verdict::TooOld);
    }

    #[test]
    fn a_resync_takes_everything_below() {
        let w = ReplayWindow::starting_at(500);
        assert_eq!(w.check(500, 1024), Verdict::Replay);
        assert_eq!(w.check(499, 1024), Verdict::Replay);
        assert_eq!(w.check(372, 1024), Verdict::TooOld);
        assert_eq!(w.check(501, 1024), Verdict::Fresh);
    }
}
