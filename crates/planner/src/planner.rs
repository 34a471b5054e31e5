//! The checked planner: settings validated once against the workspace and the limits, then
//! targeted plans and tactile-only scans.

use crate::candidate::{Candidate, CandidateId};
use crate::error::{non_negative, positive, PlanError};
use crate::geometry::{add, dist, dot, rectangles_overlap, scale, Limits, Point, Workspace};
use crate::order::{Ends, Order, Problem};
use crate::plan::{leaves_at, slide_time_s, Plan, PlanKind, Slide, Unreachable};
use crate::scan::scan_rows_count;
use crate::settings::{OnUnreachable, Overlap, Settings};
use crate::{MAX_BRUTE_FORCE, MAX_COORD_MM, MAX_SLIDES_PER_CANDIDATE};

/// A planner whose workspace, limits and settings have been checked together: everything it
/// plans lies inside the workspace and under the limits.
#[derive(Debug, Clone, PartialEq)]
pub struct Planner {
    workspace: Workspace,
    limits: Limits,
    settings: Settings,
    start: Point,
}

/// One place to slide across: a candidate or a merged group, as a rectangle.
#[derive(Debug, Clone)]
struct Target {
    ids: Vec<CandidateId>,
    centre: Point,
    axis: Point,
    length: f64,
    width: f64,
}

/// A slide fitted to the workspace: at `t` along the axis, from `s0` to `s1` across it.
#[derive(Debug, Clone, Copy)]
struct Fitted {
    t: f64,
    s0: f64,
    s1: f64,
    shifted: f64,
    clipped: bool,
    moved_along: f64,
}

impl Planner {
    /// Checks the workspace, the limits and every setting (speeds under the limits, the start
    /// pose inside the workspace).
    pub fn new(
        workspace: Workspace,
        limits: Limits,
        settings: Settings,
    ) -> Result<Self, PlanError> {
        workspace.validate()?;
        for (f, v) in [
            ("workspace.x_min_mm", workspace.x_min_mm),
            ("workspace.x_max_mm", workspace.x_max_mm),
            ("workspace.y_min_mm", workspace.y_min_mm),
            ("workspace.y_max_mm", workspace.y_max_mm),
        ] {
            if v.abs() > MAX_COORD_MM {
                return Err(PlanError::InvalidParam {
                    field: f.into(),
                    value: v,
                    expected: "within ±1e9 mm",
                });
            }
        }
        limits.validate()?;
        let s = &settings;
        positive("settings.slide_speed_mm_s", s.slide_speed_mm_s)?;
        positive("settings.travel_speed_mm_s", s.travel_speed_mm_s)?;
        if let Some(r) = s.raised_pass {
            positive("settings.raised_pass.speed_mm_s", r.speed_mm_s)?;
        }
        let raised_speed = s.raised_pass.map(|r| {
            (
                "settings.raised_pass.speed_mm_s",
                r.speed_mm_s,
                "limits.max_travel_speed_mm_s",
                limits.max_travel_speed_mm_s,
            )
        });
        for (field, v, limit_field, limit) in [
            (
                "settings.slide_speed_mm_s",
                s.slide_speed_mm_s,
                "limits.max_slide_speed_mm_s",
                limits.max_slide_speed_mm_s,
            ),
            (
                "settings.travel_speed_mm_s",
                s.travel_speed_mm_s,
                "limits.max_travel_speed_mm_s",
                limits.max_travel_speed_mm_s,
            ),
        ]
        .into_iter()
        .chain(raised_speed)
        {
            if v > limit {
                return Err(PlanError::AboveSpeedLimit {
                    field: field.into(),
                    value: v,
                    limit_field: limit_field.into(),
                    limit,
                });
            }
        }
        if let Some(a) = s.travel_accel_mm_s2 {
            positive("settings.travel_accel_mm_s2", a)?;
        }
        non_negative("settings.settle_s", s.settle_s)?;
        non_negative("settings.reversal_s", s.reversal_s)?;
        for (f, p) in [
            ("settings.passes", s.passes),
            ("settings.scan_passes", s.scan_passes),
        ] {
            if p == 0 {
                return Err(PlanError::InvalidParam {
                    field: f.into(),
                    value: 0.0,
                    expected: "at least 1",
                });
            }
        }
        for (f, v) in [
            ("settings.margin_mm", s.margin_mm),
            ("settings.min_margin_mm", s.min_margin_mm),
            ("settings.reach_mm", s.reach_mm),
            ("settings.min_stroke_mm", s.min_stroke_mm),
            ("settings.assumed_width_mm", s.assumed_width_mm),
        ]
        .into_iter()
        .chain(
            s.raised_pass
                .map(|r| ("settings.raised_pass.overrun_mm", r.overrun_mm)),
        ) {
            non_negative(f, v)?;
            if v > MAX_COORD_MM {
                return Err(PlanError::InvalidParam {
                    field: f.into(),
                    value: v,
                    expected: "at most 1e9 mm",
                });
            }
        }
        if s.min_margin_mm > s.margin_mm {
            return Err(PlanError::InvalidParam {
                field: "settings.min_margin_mm".into(),
                value: s.min_margin_mm,
                expected: "at most settings.margin_mm",
            });
        }
        if s.reach_mm + s.min_margin_mm <= 0.0 {
            return Err(PlanError::InvalidParam {
                field: "settings.reach_mm + settings.min_margin_mm".into(),
                value: s.reach_mm + s.min_margin_mm,
                expected: "> 0 (a slide must start and end off the crack)",
            });
        }
        if let Some(sp) = s.along_spacing_mm {
            positive("settings.along_spacing_mm", sp)?;
        }
        let start = s
            .start_mm
            .unwrap_or([workspace.x_min_mm, workspace.y_min_mm]);
        if !(start.iter().all(|v| v.is_finite()) && workspace.contains(start)) {
            return Err(PlanError::StartOutside {
                x: start[0],
                y: start[1],
                workspace: workspace.to_string(),
            });
        }
        Ok(Planner {
            workspace,
            limits,
            settings,
            start,
        })
    }

    /// The workspace.
    pub fn workspace(&self) -> &Workspace {
        &self.workspace
    }

    /// The limits.
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Where the finger starts, mm.
    pub fn start_mm(&self) -> Point {
        self.start
    }

    /// The targeted plan for `candidates`, ordered by [`Settings::order`].
    pub fn targeted(&self, candidates: &[Candidate]) -> Result<Plan, PlanError> {
        self.targeted_with(candidates, self.settings.order)
    }

    /// The targeted plan with another ordering (baselines, and the exact optimum of
    /// [`crate::brute_force_order`]).
    pub fn targeted_with(&self, candidates: &[Candidate], order: Order) -> Result<Plan, PlanError> {
        for (i, c) in candidates.iter().enumerate() {
            c.validate(i)?;
        }
        let mut seen = std::collections::HashMap::new();
        for (i, c) in candidates.iter().enumerate() {
            if let Some(&first) = seen.get(&c.id) {
                return Err(PlanError::DuplicateCandidate {
                    id: c.id,
                    first,
                    second: i,
                });
            }
            seen.insert(c.id, i);
        }
        let s = &self.settings;
        let groups = overlap_groups(candidates, s.assumed_width_mm);
        let overlapping: Vec<Vec<CandidateId>> = groups
            .iter()
            .filter(|g| g.len() > 1)
            .map(|g| g.iter().map(|&i| candidates[i].id).collect())
            .collect();
        let targets: Vec<Target> = match s.overlap {
            Overlap::SlideBoth => candidates.iter().map(|c| self.target_of(c)).collect(),
            Overlap::Merge => groups
                .iter()
                .map(|g| self.merged_target(candidates, g))
                .collect(),
        };
        let mut nodes: Vec<Vec<Vec<Slide>>> = Vec::new();
        let mut unreachable = Vec::new();
        for t in &targets {
            let fitted = self.fit_target(t);
            if fitted.is_empty() {
                let reason = format!(
                    "no slide across it fits in the workspace {} with at least {} mm of sound \
                     surface beyond the crack's edge and the finger's {} mm reach on both sides (centre \
                     ({:.3}, {:.3}) mm, axis {:.1}°, length {:.3} mm, width {:.3} mm)",
                    self.workspace,
                    s.min_margin_mm,
                    s.reach_mm,
                    t.centre[0],
                    t.centre[1],
                    t.axis[1].atan2(t.axis[0]).to_degrees(),
                    t.length,
                    t.width
                );
                if s.on_unreachable == OnUnreachable::Error {
                    return Err(PlanError::Unreachable {
                        ids: t.ids.clone(),
                        reason,
                    });
                }
                unreachable.push(Unreachable {
                    candidates: t.ids.clone(),
                    reason,
                });
                continue;
            }
            nodes.push(self.variants(t, &fitted));
        }
        if order == Order::BruteForce && nodes.len() > MAX_BRUTE_FORCE {
            return Err(PlanError::TooManyForBruteForce {
                n: nodes.len(),
                max: MAX_BRUTE_FORCE,
            });
        }
        let ends: Vec<Vec<Ends>> = nodes
            .iter()
            .map(|vars| {
                vars.iter()
                    .enumerate()
                    .map(|(v, sl)| ends_of(sl, vars, v, |x| leaves_at(x, s, &self.workspace)))
                    .collect()
            })
            .collect();
        let problem = Problem {
            start: self.start,
            ret: s.return_to_start,
            nodes: &ends,
        };
        let route = problem.solve(order);
        let slides: Vec<Slide> = route
            .iter()
            .flat_map(|&(n, v)| nodes[n][v].iter().cloned())
            .collect();
        Ok(Plan::assemble(
            PlanKind::Targeted {
                candidates: candidates.len(),
                order,
                overlap: s.overlap,
            },
            self.workspace,
            self.start,
            slides,
            s,
            unreachable,
            overlapping,
        ))
    }

    /// The tactile-only scan: `N_s` = [`scan_rows_count`]`(h, γ, L̄)` rows along x, spread evenly
    /// over the workspace height `h` from its bottom to its top edge (one row: across the
    /// middle), swept in alternate directions from the corner nearest the start pose.
    pub fn tactile_scan(&self, gamma: f64, mean_length_mm: f64) -> Result<Plan, PlanError> {
        let ws = &self.workspace;
        let s = &self.settings;
        let h = ws.height_mm();
        let rows = scan_rows_count(h, gamma, mean_length_mm)?;
        let spacing = if rows > 1 { h / (rows - 1) as f64 } else { h };
        let crossing_guaranteed = if rows > 1 {
            spacing <= mean_length_mm
        } else {
            h / 2.0 <= mean_length_mm
        };
        // The corner nearest the start decides where the sweep begins.
        let from_left = self.start[0] - ws.x_min_mm <= ws.x_max_mm - self.start[0];
        let from_bottom = self.start[1] - ws.y_min_mm <= ws.y_max_mm - self.start[1];
        let stroke = ws.width_mm();
        let duration = slide_time_s(stroke, s.slide_speed_mm_s, s.scan_passes, s.reversal_s);
        let mut left = from_left;
        let mut slides = Vec::with_capacity(rows);
        for k in 0..rows {
            let y = if rows == 1 {
                (ws.y_min_mm + ws.y_max_mm) / 2.0
            } else if k + 1 == rows {
                if from_bottom {
                    ws.y_max_mm
                } else {
                    ws.y_min_mm
                }
            } else if from_bottom {
                ws.y_min_mm + k as f64 * spacing
            } else {
                ws.y_max_mm - k as f64 * spacing
            };
            let (x0, x1) = if left {
                (ws.x_min_mm, ws.x_max_mm)
            } else {
                (ws.x_max_mm, ws.x_min_mm)
            };
            let slide = Slide {
                candidates: Vec::new(),
                row: Some(k),
                start_mm: ws.clamp([x0, y]),
                end_mm: ws.clamp([x1, y]),
                stroke_mm: stroke,
                passes: s.scan_passes,
                speed_mm_s: s.slide_speed_mm_s,
                duration_s: duration,
                sound_run_mm: None,
                shifted_mm: 0.0,
                clipped: false,
                moved_along_mm: 0.0,
            };
            if !s.scan_passes.is_multiple_of(2) {
                left = !left;
            }
            slides.push(slide);
        }
        Ok(Plan::assemble(
            PlanKind::TactileScan {
                gamma,
                mean_length_mm,
                rows,
                row_spacing_mm: spacing,
                crossing_guaranteed,
            },
            self.workspace,
            self.start,
            slides,
            s,
            Vec::new(),
            Vec::new(),
        ))
    }

    fn target_of(&self, c: &Candidate) -> Target {
        Target {
            ids: vec![c.id],
            centre: c.centre_mm,
            axis: c.axis(),
            length: c.length_mm,
            width: c.width_mm.unwrap_or(self.settings.assumed_width_mm),
        }
    }

    /// One rectangle covering a group of candidates, along the longest member's axis (ties: the
    /// higher score, then the first).
    fn merged_target(&self, all: &[Candidate], group: &[usize]) -> Target {
        if group.len() == 1 {
            return self.target_of(&all[group[0]]);
        }
        let lead = group.iter().copied().fold(group[0], |best, i| {
            let (a, b) = (&all[i], &all[best]);
            if a.length_mm > b.length_mm || (a.length_mm == b.length_mm && a.score > b.score) {
                i
            } else {
                best
            }
        });
        let axis = all[lead].axis();
        let normal = [-axis[1], axis[0]];
        let (mut a_lo, mut a_hi, mut n_lo, mut n_hi) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for &i in group {
            for p in all[i].rect(self.settings.assumed_width_mm).corners() {
                let (u, v) = (dot(p, axis), dot(p, normal));
                a_lo = a_lo.min(u);
                a_hi = a_hi.max(u);
                n_lo = n_lo.min(v);
                n_hi = n_hi.max(v);
            }
        }
        let (cu, cv) = ((a_lo + a_hi) / 2.0, (n_lo + n_hi) / 2.0);
        Target {
            ids: group.iter().map(|&i| all[i].id).collect(),
            centre: add(scale(axis, cu), scale(normal, cv)),
            axis,
            length: a_hi - a_lo,
            width: n_hi - n_lo,
        }
    }

    /// Half a slide's wanted length, and the least accepted on each side of the crack's centre.
    fn sides(&self, width: f64) -> (f64, f64) {
        let s = &self.settings;
        let hw = width / 2.0;
        let side = (hw + s.reach_mm + s.margin_mm).max(s.min_stroke_mm / 2.0);
        (side, hw + s.reach_mm + s.min_margin_mm)
    }

    /// The slide across `t` at `along` on its axis, fitted into the workspace: centred when it
    /// fits, else cut at the workspace's edge and lengthened on the other side (shifted), or
    /// left shorter (clipped); `None` when less than the minimum sound surface stays on a side.
    fn fit_at(&self, t: &Target, along: f64) -> Option<Fitted> {
        let (side, min_side) = self.sides(t.width);
        let p = add(t.centre, scale(t.axis, along));
        let n = [-t.axis[1], t.axis[0]];
        let [lo, hi] = self.workspace.line_interval(p, n)?;
        if lo <= -side && hi >= side {
            return Some(Fitted {
                t: along,
                s0: -side,
                s1: side,
                shifted: 0.0,
                clipped: false,
                moved_along: 0.0,
            });
        }
        let want = 2.0 * side;
        let (mut s0, mut s1) = ((-side).max(lo), side.min(hi));
        if s0 > -side {
            s1 = (s0 + want).min(hi);
        }
        if s1 < side {
            s0 = (s1 - want).max(lo);
        }
        (s0 <= -min_side && s1 >= min_side).then_some(Fitted {
            t: along,
            s0,
            s1,
            shifted: (s0 + s1) / 2.0,
            clipped: s1 - s0 < want * (1.0 - 1e-12),
            moved_along: 0.0,
        })
    }

    /// Every slide of a target, each moved along the crack (nearest first) when it does not
    /// fit where asked; empty when none fits.
    fn fit_target(&self, t: &Target) -> Vec<Fitted> {
        let half = t.length / 2.0;
        let count = match self.settings.along_spacing_mm {
            Some(sp) if t.length > 0.0 => {
                ((t.length / sp).ceil() as usize).clamp(1, MAX_SLIDES_PER_CANDIDATE)
            }
            _ => 1,
        };
        let mut out: Vec<Fitted> = Vec::with_capacity(count);
        for j in 0..count {
            let asked = -half + (j as f64 + 0.5) * t.length / count as f64;
            let fitted = self.fit_at(t, asked).or_else(|| {
                if t.length <= 0.0 {
                    return None;
                }
                const STEPS: usize = 64;
                let mut tries: Vec<f64> = (0..=STEPS)
                    .map(|i| -half + t.length * i as f64 / STEPS as f64)
                    .collect();
                tries.sort_by(|a, b| (a - asked).abs().total_cmp(&(b - asked).abs()));
                tries.into_iter().find_map(|along| {
                    self.fit_at(t, along).map(|f| Fitted {
                        moved_along: along - asked,
                        ..f
                    })
                })
            });
            if let Some(f) = fitted {
                if !out.iter().any(|o| (o.t - f.t).abs() < 1e-9) {
                    out.push(f);
                }
            }
        }
        out.sort_by(|a, b| a.t.total_cmp(&b.t));
        out
    }

    /// The ways to run a target's slides: along the crack one way or the other, starting on
    /// one side or the other. Each variant's slides in the order they run.
    fn variants(&self, t: &Target, fitted: &[Fitted]) -> Vec<Vec<Slide>> {
        let s = &self.settings;
        let n = [-t.axis[1], t.axis[0]];
        let (hw, tip) = (t.width / 2.0, s.reach_mm);
        let dirs: &[bool] = if fitted.len() > 1 {
            &[true, false]
        } else {
            &[true]
        };
        let mut out = Vec::new();
        for &ascending in dirs {
            for first_side in [-1.0, 1.0] {
                let order: Vec<&Fitted> = if ascending {
                    fitted.iter().collect()
                } else {
                    fitted.iter().rev().collect()
                };
                let mut side = first_side;
                let mut slides = Vec::with_capacity(order.len());
                for f in order {
                    let p = add(t.centre, scale(t.axis, f.t));
                    let at = |s: f64| self.workspace.clamp(add(p, scale(n, s)));
                    let (a, b) = (at(f.s0), at(f.s1));
                    let runs = [-f.s0 - hw - tip, f.s1 - hw - tip];
                    let (start, end, run) = if side < 0.0 {
                        (a, b, runs)
                    } else {
                        (b, a, [runs[1], runs[0]])
                    };
                    let stroke = dist(start, end);
                    slides.push(Slide {
                        candidates: t.ids.clone(),
                        row: None,
                        start_mm: start,
                        end_mm: end,
                        stroke_mm: stroke,
                        passes: s.passes,
                        speed_mm_s: s.slide_speed_mm_s,
                        duration_s: slide_time_s(
                            stroke,
                            s.slide_speed_mm_s,
                            s.passes,
                            s.reversal_s,
                        ),
                        sound_run_mm: Some(run),
                        shifted_mm: f.shifted,
                        clipped: f.clipped,
                        moved_along_mm: f.moved_along,
                    });
                    if !s.passes.is_multiple_of(2) {
                        side = -side;
                    }
                }
                out.push(slides);
            }
        }
        out
    }
}

/// Entry, exit, internal travel and the reverse of variant `v` among `vars`.
fn ends_of(
    slides: &[Slide],
    vars: &[Vec<Slide>],
    v: usize,
    leaves_at: impl Fn(&Slide) -> Point,
) -> Ends {
    let entry = slides[0].start_mm;
    let last_exit = slides[slides.len() - 1].exit_mm();
    let internal = slides
        .windows(2)
        .map(|w| dist(leaves_at(&w[0]), w[1].start_mm))
        .sum();
    // The reverse runs the same slides backwards: it enters where this one's strokes leave the
    // finger, and its strokes leave it where this one enters.
    let rev = vars
        .iter()
        .position(|o| {
            o[0].start_mm == last_exit
                && o[o.len() - 1].exit_mm() == entry
                && o.len() == slides.len()
        })
        .unwrap_or(v);
    Ends {
        entry,
        exit: leaves_at(&slides[slides.len() - 1]),
        internal,
        rev,
    }
}

/// Groups of candidates whose rectangles overlap or touch (transitively), each in list order,
/// in the order of their first member.
fn overlap_groups(candidates: &[Candidate], assumed_width_mm: f64) -> Vec<Vec<usize>> {
    let n = candidates.len();
    let rects: Vec<_> = candidates
        .iter()
        .map(|c| c.rect(assumed_width_mm))
        .collect();
    crate::geometry::connected_groups(n, |i, j| rectangles_overlap(&rects[i], &rects[j]))
}
