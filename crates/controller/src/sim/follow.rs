//! The simulated finger and sensor following another arm: each 400 Hz sample, the world takes
//! the pose that arm reports and the slide it presses the finger along
//! ([`super::world::World::step_following`]). With the ROS 2 arm this is how a mission runs
//! through a real DDS peer with a simulated finger on it.

use crackbot_emulator::SignalSource;

use super::world::{Pressed, World};

/// Where the driving arm is now: its tip (mm, surface frame) and the slide it presses along.
pub type ArmNow = Option<([f64; 3], Option<Pressed>)>;

/// The world as the sensor's signal source, driven by another arm's pose.
pub struct FollowingSource<F> {
    world: World,
    arm: F,
    last_counts: [f64; 4],
    failed: bool,
}

impl<F: FnMut() -> ArmNow> FollowingSource<F> {
    /// The finger over `world`, following what `arm` says each sample.
    pub fn new(world: World, arm: F) -> Self {
        FollowingSource {
            world,
            arm,
            last_counts: [0.0; 4],
            failed: false,
        }
    }
}

impl<F: FnMut() -> ArmNow> SignalSource for FollowingSource<F> {
    fn sample(&mut self, _t: f64) -> [f64; 4] {
        let (pose, pressed) = (self.arm)().unwrap_or((self.world.pose(), None));
        match self.world.step_following(pose, pressed) {
            Ok(t) => self.last_counts = t.counts,
            Err(e) if !self.failed => {
                self.failed = true;
                tracing::error!("the simulated finger failed: {e}");
            }
            Err(_) => {}
        }
        self.last_counts
    }
}
