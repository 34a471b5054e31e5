//! Cartesian motion for an arm driven by a stream of targets (the ROS 2 arm), as pure code:
//!
//! * [`frame`]: the surface frame in the arm's base frame ([`frame::SurfaceFrame`]).
//! * [`path`]: a command's straight legs, timed with a trapezoidal speed profile.
//! * [`guard`]: the checks on every target published and every pose reported, and the faults.
//! * [`cartesian`]: the arm's state machine: commands in, targets out, poses in, state out.
//! * [`register`]: finding the plate's plane and frame from touched points.

pub mod cartesian;
pub mod frame;
pub mod guard;
pub mod path;
pub mod register;
