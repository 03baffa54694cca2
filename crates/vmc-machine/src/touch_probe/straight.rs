//! A straight probe move (G38.2 … G38.5) answered by the machine: the ball follows the
//! programmed straight path from the request's start toward its target until the probe changes
//! state, and the controller latches the axes.
//!
//! **Model.** At axis command `q` (machine coordinates, the commanded tip of the machine's own
//! tool) the ball's centre is `q + o + E(q)`: `o` the nominal offset of the ball from that tip
//! (`(0, 0, master length − stylus length)`), `E` the twin's whole error chain with the stylus
//! as tool (present temperatures, the axes' reversal, one non-repeatability draw per move).
//! The stylus deflects by the ball's overlap with the nearest solid (`r − signed distance`);
//! the probe reads *tripped* when that deflection reaches the pre-travel. G38.2/.3 seek the
//! first point of the path where it trips, G38.4/.5 the first where it no longer does (found
//! by marching at half the distance to the state change, which cannot step over it, then
//! bisection to 1e-7 mm). The latch lies past that point by the repeatability scatter and the
//! servo latency (as [`ProbeOnTwin::touch`]); the axes then stop after the braking distance
//! `v² / 2a` at the probe feed (`a` the path's acceleration limit), never past the target.
//! [`nominal_move`] is what the controller expects from the same move on the nominal machine
//! (no error, no scatter, no latency): what `check` and the run's first pass use.
//!
//! Units: mm, mm/min, mm/s².

use vmc_gcode::interp::{ProbeOutcome, ProbeRequest};

use super::{ProbeError, ProbeOnTwin, TouchProbe};
use crate::probe_setup::Solid;
use crate::twin::Twin;

/// Smallest marching step, mm: a feature thinner than 1 µm along the path may be stepped over.
const MIN_STEP_MM: f64 = 1e-3;
/// Bisection tolerance of the state change along the path, mm.
const BISECT_MM: f64 = 1e-7;

/// Where the probe's ball sits and how the axes stop, for one machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeMotion {
    /// Nominal ball centre minus the commanded tool tip, mm.
    pub ball_offset_mm: [f64; 3],
    /// Acceleration limit per axis X, Y, Z, mm/s² (the braking after the latch).
    pub max_accel_mm_per_s2: [f64; 3],
}

impl ProbeMotion {
    /// The probe of stylus length `stylus_length_mm` on `machine`: the ball's centre lies
    /// `master length − stylus length` above the commanded tip of the machine's own tool.
    pub fn of_machine(machine: &crate::machine::MachineSpec, stylus_length_mm: f64) -> Self {
        let t = machine.tool.offset_mm;
        ProbeMotion {
            ball_offset_mm: [-t[0], -t[1], -t[2] - stylus_length_mm],
            max_accel_mm_per_s2: machine.motion.max_accel_mm_per_s2,
        }
    }
}

/// The machine's answer to one probe move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeMove {
    /// What the controller hands the interpreter.
    pub outcome: ProbeOutcome,
    /// Index (into the solids given) of the solid whose contact changed the probe's state.
    pub touched: Option<usize>,
}

/// Where along the path the probe changes state.
enum Change {
    /// Already in the sought state at the start.
    AtStart,
    /// Nowhere within the move.
    Never,
    /// At `lambda_mm` from the start, against solid `solid`.
    At { lambda_mm: f64, solid: usize },
}

/// The straight path of a request: start, unit direction, length (XYZ), mm.
fn path(request: &ProbeRequest) -> ([f64; 3], [f64; 3], f64) {
    let d = [0, 1, 2].map(|a| request.end_mm[a] - request.start_mm[a]);
    let length_mm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let dir = if length_mm > 0.0 {
        d.map(|v| v / length_mm)
    } else {
        [0.0; 3]
    };
    (request.start_mm, dir, length_mm)
}

fn at(start: [f64; 3], dir: [f64; 3], lambda_mm: f64) -> [f64; 3] {
    [0, 1, 2].map(|a| start[a] + dir[a] * lambda_mm)
}

/// The first state change along the path. `ball(q)` is the real ball centre at axis command
/// `q`; the probe is tripped where the nearest solid's signed distance is at most
/// `r − pre-travel`.
fn find_change(
    request: &ProbeRequest,
    solids: &[Solid],
    trip_distance_mm: f64,
    ball: &dyn Fn([f64; 3]) -> [f64; 3],
) -> Change {
    let (start, dir, length_mm) = path(request);
    // h ≤ 0: in the sought state; |h| is the distance to the state change (1-Lipschitz).
    let sign = if request.kind.toward { 1.0 } else { -1.0 };
    let h = |lambda: f64| -> (f64, usize) {
        let c = ball(at(start, dir, lambda));
        let (i, d) = solids
            .iter()
            .map(|s| s.signed_distance_mm(c))
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |m, (i, d)| if d < m.1 { (i, d) } else { m },
            );
        (sign * (d - trip_distance_mm), i)
    };
    if h(0.0).0 <= 0.0 {
        return Change::AtStart;
    }
    let mut lo = 0.0;
    let mut h_lo = h(0.0).0;
    loop {
        let next = (lo + (0.5 * h_lo).max(MIN_STEP_MM)).min(length_mm);
        let (h_next, _) = h(next);
        if h_next <= 0.0 {
            let mut hi = next;
            while hi - lo > BISECT_MM {
                let mid = 0.5 * (lo + hi);
                if h(mid).0 <= 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return Change::At {
                lambda_mm: hi,
                solid: h(hi).1,
            };
        }
        if next >= length_mm {
            return Change::Never;
        }
        (lo, h_lo) = (next, h_next);
    }
}

/// The braking distance at feed `feed_mm_per_min` along `dir`, mm.
fn braking_mm(dir: [f64; 3], feed_mm_per_min: f64, accel: [f64; 3]) -> f64 {
    let a = (0..3)
        .filter(|&i| dir[i].abs() > 1e-12)
        .map(|i| accel[i] / dir[i].abs())
        .fold(f64::INFINITY, f64::min);
    let v = feed_mm_per_min / 60.0;
    if a.is_finite() && a > 0.0 {
        v * v / (2.0 * a)
    } else {
        0.0
    }
}

/// The outcome of a change at `change`, latched `extra_mm` further along the path.
fn outcome(
    request: &ProbeRequest,
    change: Change,
    extra_mm: f64,
    motion: &ProbeMotion,
) -> ProbeMove {
    let (start, dir, length_mm) = path(request);
    match change {
        Change::AtStart => ProbeMove {
            outcome: ProbeOutcome::AlreadyInState,
            touched: None,
        },
        Change::Never => ProbeMove {
            outcome: ProbeOutcome::NoContact,
            touched: None,
        },
        Change::At { lambda_mm, solid } => {
            let latch = (lambda_mm + extra_mm).clamp(0.0, length_mm);
            let brake = braking_mm(dir, request.feed_mm_per_min, motion.max_accel_mm_per_s2);
            let rest = (latch + brake).min(length_mm);
            ProbeMove {
                outcome: ProbeOutcome::Tripped {
                    trip_mm: at(start, dir, latch),
                    trip_abc_deg: request.end_abc_deg,
                    rest_mm: at(start, dir, rest),
                    rest_abc_deg: request.end_abc_deg,
                },
                touched: Some(solid),
            }
        }
    }
}

/// The probe at the feed of `request`.
fn at_feed(probe: &TouchProbe, request: &ProbeRequest) -> TouchProbe {
    TouchProbe {
        feed_mm_per_min: request.feed_mm_per_min,
        ..*probe
    }
}

/// What the controller expects of `request` on the nominal machine: the ball at `q + o`, the
/// trip at the pre-travel, no scatter, no latency (see the module documentation).
pub fn nominal_move(
    probe: &TouchProbe,
    solids: &[Solid],
    motion: &ProbeMotion,
    request: &ProbeRequest,
) -> ProbeMove {
    let o = motion.ball_offset_mm;
    let ball = |q: [f64; 3]| [q[0] + o[0], q[1] + o[1], q[2] + o[2]];
    let trip_distance_mm = probe.ball_radius_mm - probe.pretravel_mm();
    let change = find_change(request, solids, trip_distance_mm, &ball);
    outcome(request, change, 0.0, motion)
}

impl ProbeOnTwin {
    /// Runs the probe move `request` on `twin` at its present temperatures against `solids`
    /// (see the module documentation). The twin's tool is the stylus during the move and is
    /// restored after it; the axes' direction of motion is the move's from then on.
    ///
    /// # Errors
    /// [`ProbeError::Setting`] for a probe feed that is not a positive finite number.
    pub fn straight_move(
        &mut self,
        twin: &mut Twin,
        solids: &[Solid],
        motion: &ProbeMotion,
        request: &ProbeRequest,
    ) -> Result<ProbeMove, ProbeError> {
        let probe = at_feed(&self.probe, request);
        if !(probe.feed_mm_per_min.is_finite() && probe.feed_mm_per_min > 0.0) {
            return Err(ProbeError::Setting {
                field: "feed_mm_per_min",
                value: probe.feed_mm_per_min,
            });
        }
        let (_, dir, _) = path(request);
        twin.note_motion(dir);
        let approach = twin.draw_approach_mm();
        let saved = twin.set_tool_offset_mm([0.0, 0.0, -probe.stylus_length_mm]);
        let o = motion.ball_offset_mm;
        let change = {
            let twin_now: &Twin = twin;
            let ball = |q: [f64; 3]| {
                let e = twin_now.tool_error_mm(q, q, approach);
                [q[0] + o[0] + e.x, q[1] + o[1] + e.y, q[2] + o[2] + e.z]
            };
            find_change(
                request,
                solids,
                probe.ball_radius_mm - probe.pretravel_mm(),
                &ball,
            )
        };
        twin.set_tool_offset_mm(saved);
        let extra_mm = match change {
            Change::At { .. } => self.scatter_mm(&probe),
            _ => 0.0,
        };
        Ok(outcome(request, change, extra_mm, motion))
    }
}

#[cfg(test)]
#[path = "straight_tests.rs"]
mod tests;
