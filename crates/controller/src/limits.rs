//! What the controller refuses: the arm's workspace and speed limits ([`Limits`]), the heights a
//! move may hold the finger at, and the refusals a command out of them gets ([`Refusal`]). The
//! command check (`command.rs`) and the arm (`world.rs`) both read them.

use serde::Serialize;

/// Lowest height a move may hold the finger's tip above the plate's plane, mm (lower would
/// drag it over the plate's roughness).
pub const MIN_MOVE_HEIGHT_MM: f64 = 0.5;
/// Highest height a move may take the finger to, mm.
pub const MAX_MOVE_HEIGHT_MM: f64 = 50.0;

/// What the controller refuses to do.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Refusal {
    /// A point lies outside the workspace.
    #[error("{what} ({x:.2}, {y:.2}) mm is outside the workspace [{x0}, {x1}] × [{y0}, {y1}] mm")]
    OutsideWorkspace {
        /// Which point.
        what: &'static str,
        /// x, mm.
        x: f64,
        /// y, mm.
        y: f64,
        /// Workspace x range, mm.
        x0: f64,
        /// Workspace x range, mm.
        x1: f64,
        /// Workspace y range, mm.
        y0: f64,
        /// Workspace y range, mm.
        y1: f64,
    },
    /// A speed is above its limit (or not a positive number).
    #[error("{what} speed {speed} mm/s is not in (0, {limit}] mm/s")]
    OverSpeed {
        /// Travel or slide.
        what: &'static str,
        /// Asked speed, mm/s.
        speed: f64,
        /// The limit, mm/s.
        limit: f64,
    },
    /// A value outside its allowed range (a move's height, a slide's length).
    #[error("{what} {value} mm is not in [{min}, {max}] mm")]
    OutOfRange {
        /// Which value.
        what: &'static str,
        /// The value asked, mm.
        value: f64,
        /// The least allowed, mm.
        min: f64,
        /// The most allowed, mm.
        max: f64,
    },
    /// The controller is stopped or faulted: it needs a new command after `Stop` is cleared.
    #[error("the controller is faulted: {0}")]
    Faulted(String),
}

/// The workspace and speed limits (from the scene's manipulator, see [`Limits::of_scene`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Limits {
    /// Lower corner of the reachable box, mm `[x, y]` in the plate frame.
    pub min_mm: [f64; 2],
    /// Upper corner, mm.
    pub max_mm: [f64; 2],
    /// Fastest travel between slides, mm/s.
    pub max_travel_speed_mm_s: f64,
    /// Fastest slide, mm/s.
    pub max_slide_speed_mm_s: f64,
}

impl Limits {
    /// The scene's workspace; travel up to twice the scene's travel speed, slides up to four
    /// times the scene's slide speed (the finger's contact is not rated for more).
    #[cfg(feature = "sim")]
    pub fn of_scene(scene: &crackbot_sim::Scene) -> Self {
        let m = &scene.manipulator;
        Limits {
            min_mm: [m.workspace_min_mm[0], m.workspace_min_mm[1]],
            max_mm: [m.workspace_max_mm[0], m.workspace_max_mm[1]],
            max_travel_speed_mm_s: 2.0 * m.travel_speed_mm_s,
            max_slide_speed_mm_s: 4.0 * m.slide_speed_mm_s,
        }
    }

    /// Refuses a point outside the workspace (or not finite), naming it `what`.
    pub fn check_point(&self, what: &'static str, p: [f64; 2]) -> Result<(), Refusal> {
        let inside = p.iter().all(|v| v.is_finite())
            && (self.min_mm[0]..=self.max_mm[0]).contains(&p[0])
            && (self.min_mm[1]..=self.max_mm[1]).contains(&p[1]);
        if inside {
            Ok(())
        } else {
            Err(Refusal::OutsideWorkspace {
                what,
                x: p[0],
                y: p[1],
                x0: self.min_mm[0],
                x1: self.max_mm[0],
                y0: self.min_mm[1],
                y1: self.max_mm[1],
            })
        }
    }

    /// Refuses a speed that is not in `(0, limit]`, naming it `what`.
    pub fn check_speed(what: &'static str, speed: f64, limit: f64) -> Result<(), Refusal> {
        if speed.is_finite() && speed > 0.0 && speed <= limit {
            Ok(())
        } else {
            Err(Refusal::OverSpeed { what, speed, limit })
        }
    }
}
