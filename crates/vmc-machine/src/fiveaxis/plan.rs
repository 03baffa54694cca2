//! The plan of a five-axis program, with tool centre point control (G43.4).
//!
//! # Model
//! - **Frames.** Without G43.4 a move's `X Y Z` are the linear axes' positions (machine
//!   coordinates, work offsets added by the interpreter). Under G43.4 they are the tool tip's
//!   position in the part frame: the workpiece frame of the machine file (origin at the datum,
//!   `[sphere] centre_mm`, axes parallel to the bed's at zero angles, turning with the table),
//!   shifted by the active work offset. `A B C` are the rotary axes' angles in both.
//! - **Tool.** The machine carries one tool, number 1, of the length of its `[tool]` offset
//!   (`−offset_mm[2]`); G43 H1 / G43.4 H1 use it.
//! - **Pieces.** The program's moves are cut where G43.4 is switched on or off; each piece is
//!   planned on its own ([`crate::motion::plan_with_rotary`]: the linear and rotary speed and
//!   acceleration limits), from where the previous one ended expressed in the piece's frame
//!   (the nominal chain's forward kinematics of the axes, or its inverse). A G43.4 piece is
//!   thus interpolated in the part frame: the tip runs along the programmed line or arc at the
//!   programmed feed relative to the part while the rotary axes turn in step, and the axes
//!   follow from the nominal inverse kinematics at every instant ([`joints_for_tip`]). Their
//!   travel is checked every [`TRAVEL_CHECK_STEP_S`] of the programmed timing.
//! - **Axis limits under G43.4.** A move whose programmed timing would drive an axis beyond
//!   its speed or acceleration limit is retimed along the same path
//!   ([`super::tcp_timing`]): the tip slows where it must, as a real controller's does; the
//!   piece's [`Piece::timing`] holds the new timing and every reading over time (the
//!   commanded points, [`FivePlan::joints_at`], the durations) follows it. Pieces without
//!   G43.4 keep the planner's timing unchanged.
//!
//! The inverse kinematics is the nominal chain's: the controller's model without errors (the
//! compensation of [`super::run`] acts on top of it). Units: mm, degrees, s.

use thiserror::Error;

use crate::motion::{self, Plan, SegmentKind};
use crate::program::ProgramError;
use vmc_gcode::interp::{self, CanonMove, InterpConfig};
use vmc_identify::chain::{Geometry, Pose};
use vmc_identify::errors::ErrorState;
use vmc_identify::htm::tip_in_workpiece_mm;
use vmc_identify::inverse::nominal_linear_axes;

use super::tcp_timing::{self, JointLimits, LimitKind, Retimed};
use super::FiveAxisSpec;
use crate::machine::MachineError;
use vmc_identify::inverse::HtmError;

/// Time step of the linear-axis travel check along a G43.4 move, s (1 mm at 30 m/min).
pub const TRAVEL_CHECK_STEP_S: f64 = 0.002;

/// A linear axis leaves its travel along a G43.4 move.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("line {line}: under G43.4 axis {axis} reaches {value_mm:.3} mm, outside its travel [{min_mm}, {max_mm}] mm")]
pub struct TcpTravelError {
    /// Source line of the move.
    pub line: usize,
    /// `X`, `Y` or `Z`.
    pub axis: char,
    /// Where the axis would go, mm.
    pub value_mm: f64,
    /// Travel limits, mm.
    pub min_mm: f64,
    /// Travel limits, mm.
    pub max_mm: f64,
}

/// Why a program cannot be run on the five-axis machine.
#[derive(Debug, Error)]
pub enum FiveAxisRunError {
    /// The program cannot be interpreted or planned, or leaves a travel.
    #[error(transparent)]
    Program(#[from] ProgramError),
    /// The machine file lacks what running needs.
    #[error(transparent)]
    Machine(#[from] MachineError),
    /// A linear axis leaves its travel along a G43.4 move.
    #[error("{file}: {err}")]
    TcpTravel {
        /// The program file.
        file: String,
        /// Where and which axis.
        err: TcpTravelError,
    },
    /// The compensation could not be solved at a point.
    #[error("line {line}: compensation failed: {err}")]
    Compensation {
        /// Source line of the point.
        line: usize,
        /// The solver's error.
        err: HtmError,
    },
}

/// The pose of linear axes `q_mm` and G-code angles `abc_deg` (A, B, C) for `geom`'s rotary
/// axes.
#[must_use]
pub fn pose_of(geom: &Geometry, q_mm: [f64; 3], abc_deg: [f64; 3]) -> Pose {
    let mut rotary_deg = [0.0; 2];
    for (i, r) in geom.rotary.iter().enumerate().take(2) {
        rotary_deg[i] = abc_deg[r.axis.index()];
    }
    Pose {
        linear_mm: q_mm,
        rotary_deg,
    }
}

/// One planned piece: moves in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// The piece's plan (its positions in the piece's frame), from time 0.
    pub plan: Plan,
    /// Program time at the piece's start, s.
    pub t0_s: f64,
    /// The tool length under G43.4 (positions are tool tips in the part frame), `None` for
    /// machine positions.
    pub tcp_length_mm: Option<f64>,
    /// Under G43.4, the timing within the axes' limits; `None`: the plan's own timing.
    pub timing: Option<PieceTiming>,
}

/// The timing of a G43.4 piece's segments within the axes' limits.
#[derive(Debug, Clone, PartialEq)]
pub struct PieceTiming {
    /// Start of each segment from the piece's start, s.
    pub t_start_s: Vec<f64>,
    /// Each segment's retiming; `None` where the planned timing keeps within the limits.
    pub retimed: Vec<Option<Retimed>>,
}

impl PieceTiming {
    /// Retimes every moving segment of `plan` (under G43.4 with a tool of `length_mm`).
    fn new(plan: &Plan, geom: &Geometry, length_mm: f64, limits: &JointLimits) -> Self {
        let mut t_s = 0.0;
        let mut t_start_s = Vec::with_capacity(plan.segments().len());
        let mut retimed = Vec::with_capacity(plan.segments().len());
        for seg in plan.segments() {
            let moving = matches!(
                seg.kind,
                SegmentKind::Rapid | SegmentKind::Feed | SegmentKind::Arc
            );
            let ik = |p_mm, abc_deg| joints_for_tip(geom, Some(length_mm), p_mm, abc_deg);
            let r = if moving {
                tcp_timing::retime(seg, &ik, limits)
            } else {
                None
            };
            t_start_s.push(t_s);
            // The same sum as the planner's: unchanged segments keep their times exactly.
            t_s += r.as_ref().map_or(seg.duration_s, Retimed::duration_s);
            retimed.push(r);
        }
        Self { t_start_s, retimed }
    }
}

impl Piece {
    /// The piece's duration, s.
    #[must_use]
    pub fn duration_s(&self) -> f64 {
        match &self.timing {
            Some(t) => t.t_start_s.last().map_or(0.0, |t0| {
                t0 + self.segment_duration_s(t.t_start_s.len() - 1)
            }),
            None => self.plan.duration_s(),
        }
    }

    /// Start of segment `i` from the piece's start, s.
    #[must_use]
    pub fn segment_start_s(&self, i: usize) -> f64 {
        match &self.timing {
            Some(t) => t.t_start_s[i],
            None => self.plan.segments()[i].t_start_s,
        }
    }

    /// Duration of segment `i`, s.
    #[must_use]
    pub fn segment_duration_s(&self, i: usize) -> f64 {
        match self.timing.as_ref().and_then(|t| t.retimed[i].as_ref()) {
            Some(r) => r.duration_s(),
            None => self.plan.segments()[i].duration_s,
        }
    }

    /// Position (tool tip in the part frame under G43.4, axes otherwise; mm) and A, B, C
    /// (degrees) at local time `t_local_s` of segment `i`.
    #[must_use]
    pub fn segment_state_at(&self, i: usize, t_local_s: f64) -> ([f64; 3], [f64; 3]) {
        let seg = &self.plan.segments()[i];
        match self.timing.as_ref().and_then(|t| t.retimed[i].as_ref()) {
            None => (
                seg.position_at_local(t_local_s),
                seg.abc_at_local(t_local_s),
            ),
            Some(r) => {
                if t_local_s >= r.duration_s() {
                    return (seg.end_mm, seg.end_abc_deg);
                }
                let sigma = r.distance_at(t_local_s);
                let f = sigma / seg.profile.length_mm;
                let abc = [0, 1, 2].map(|k| {
                    seg.start_abc_deg[k] + f * (seg.end_abc_deg[k] - seg.start_abc_deg[k])
                });
                (seg.geometry.point_at(seg.start_mm, sigma), abc)
            }
        }
    }

    /// Position and A, B, C at time `t_s` from the piece's start (see
    /// [`Self::segment_state_at`]); the start before 0, the end after the piece.
    #[must_use]
    pub fn state_at(&self, t_s: f64) -> ([f64; 3], [f64; 3]) {
        let Some(timing) = &self.timing else {
            return (self.plan.position_at(t_s), self.plan.abc_at(t_s));
        };
        match timing
            .t_start_s
            .partition_point(|&t0| t0 <= t_s)
            .checked_sub(1)
        {
            Some(i) => self.segment_state_at(i, t_s - timing.t_start_s[i]),
            None => (
                self.plan.start_mm(),
                self.plan
                    .segments()
                    .first()
                    .map_or([0.0; 3], |s| s.start_abc_deg),
            ),
        }
    }
}

/// How the axes' limits slowed a program's G43.4 moves.
#[derive(Debug, Clone, PartialEq)]
pub struct TcpLimitReport {
    /// Moves retimed.
    pub moves: usize,
    /// Lowest admissible path speed over the programmed one, over all retimed moves (1 when
    /// only their ramps were made gentler).
    pub slowest_ratio: f64,
    /// Source line of the move with the lowest ratio.
    pub slowest_line: usize,
    /// The axis and the kind of limit there.
    pub binding: (char, LimitKind),
    /// Time the retimed moves take beyond their programmed timing, s.
    pub added_s: f64,
}

/// A five-axis program planned: its pieces in time order and the nominal geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct FivePlan {
    /// The pieces.
    pub pieces: Vec<Piece>,
    geom: Geometry,
}

impl FivePlan {
    /// The machine's nominal geometry.
    #[must_use]
    pub fn geometry(&self) -> &Geometry {
        &self.geom
    }

    /// The program's duration, s.
    #[must_use]
    pub fn duration_s(&self) -> f64 {
        self.pieces.last().map_or(0.0, |p| p.t0_s + p.duration_s())
    }

    /// How the axes' limits slowed the G43.4 moves; `None` when none had to be.
    #[must_use]
    pub fn tcp_limits(&self) -> Option<TcpLimitReport> {
        let mut report: Option<TcpLimitReport> = None;
        for piece in &self.pieces {
            let Some(timing) = &piece.timing else {
                continue;
            };
            for (seg, r) in piece.plan.segments().iter().zip(&timing.retimed) {
                let Some(r) = r else { continue };
                let added_s = r.duration_s() - r.programmed_s;
                let rep = report.get_or_insert(TcpLimitReport {
                    moves: 0,
                    slowest_ratio: f64::INFINITY,
                    slowest_line: seg.line,
                    binding: r.binding,
                    added_s: 0.0,
                });
                rep.moves += 1;
                rep.added_s += added_s;
                if r.slowest_ratio < rep.slowest_ratio {
                    rep.slowest_ratio = r.slowest_ratio;
                    rep.slowest_line = seg.line;
                    rep.binding = r.binding;
                }
            }
        }
        report
    }

    /// The commanded axes (linear mm, A B C degrees) at program time `t_s`.
    #[must_use]
    pub fn joints_at(&self, t_s: f64) -> ([f64; 3], [f64; 3]) {
        let piece = self
            .pieces
            .iter()
            .rev()
            .find(|p| p.t0_s <= t_s)
            .or(self.pieces.first());
        match piece {
            Some(p) => {
                let (pos_mm, abc) = p.state_at(t_s - p.t0_s);
                let q = joints_for_tip(&self.geom, p.tcp_length_mm, pos_mm, abc);
                (q, abc)
            }
            None => ([0.0; 3], [0.0; 3]),
        }
    }
}

/// `geom` with a tool of length `length_mm` along the spindle (the offset's X and Y kept).
#[must_use]
pub fn with_tool_length(geom: &Geometry, length_mm: f64) -> Geometry {
    let mut g = geom.clone();
    g.tool_offset_mm[2] = -length_mm;
    g
}

/// The linear axes for position `p_mm` at angles `abc_deg`: under G43.4 (`length_mm` given)
/// `p_mm` is the tool tip in the part frame and the nominal inverse kinematics gives the axes;
/// otherwise `p_mm` are the axes.
#[must_use]
pub fn joints_for_tip(
    geom: &Geometry,
    length_mm: Option<f64>,
    p_mm: [f64; 3],
    abc_deg: [f64; 3],
) -> [f64; 3] {
    let Some(l) = length_mm else {
        return p_mm;
    };
    let g = with_tool_length(geom, l);
    let rotary = pose_of(&g, [0.0; 3], abc_deg).rotary_deg;
    // The nominal model is affine in the linear axes: the first step is exact up to the
    // Jacobian's rounding, a second removes that.
    let target = nalgebra::Vector3::from(p_mm);
    let q = nominal_linear_axes(&g, rotary, target);
    let pose = Pose {
        linear_mm: q,
        rotary_deg: rotary,
    };
    let miss = target - tip_in_workpiece_mm(&g, &pose, &ErrorState::default());
    let dq = nominal_linear_axes(&g, rotary, miss);
    let dq0 = nominal_linear_axes(&g, rotary, nalgebra::Vector3::zeros());
    [0, 1, 2].map(|k| q[k] + dq[k] - dq0[k])
}

/// The tool tip in the part frame for axes `q_mm`, `abc_deg` and a tool of `length_mm`
/// (nominal forward kinematics).
#[must_use]
pub fn tip_for_joints(
    geom: &Geometry,
    length_mm: f64,
    q_mm: [f64; 3],
    abc_deg: [f64; 3],
) -> [f64; 3] {
    let g = with_tool_length(geom, length_mm);
    let tip = tip_in_workpiece_mm(&g, &pose_of(&g, q_mm, abc_deg), &ErrorState::default());
    [tip[0], tip[1], tip[2]]
}

/// The interpreter's configuration for a five-axis machine: its work offsets, its one tool and
/// tool centre point control over its rotary axes.
#[must_use]
pub fn interp_config(spec: &FiveAxisSpec) -> InterpConfig {
    let mut work_offsets_mm = [[0.0; 3]; interp::WORK_OFFSETS];
    work_offsets_mm[..6].copy_from_slice(&spec.axes.work_offsets_mm);
    let mut tcp_axes = [false; 3];
    for r in &spec.geometry().rotary {
        tcp_axes[r.axis.index()] = true;
    }
    InterpConfig {
        start_mm: spec.axes.home_mm,
        work_offsets_mm,
        tool_lengths_mm: vec![(1, -spec.tool.offset_mm[2])],
        tcp_axes: Some(tcp_axes),
        ..InterpConfig::default()
    }
}

/// Interprets and plans `text` (named `file` in errors) on `spec` (read from `machine_file`),
/// checking the linear and rotary travels.
///
/// # Errors
/// Syntax or semantic errors (G43.4's with line and column), a machine file without rotary
/// speed limits, a move beyond a travel limit (with its line).
pub fn plan_program(
    text: &str,
    file: &str,
    spec: &FiveAxisSpec,
    machine_file: &str,
) -> Result<FivePlan, FiveAxisRunError> {
    let rotary = spec.rotary_limits(machine_file)?;
    let (moves, tcp) =
        interp::run_program_tcp(text, &interp_config(spec)).map_err(|err| ProgramError::Gcode {
            file: file.to_string(),
            err,
        })?;
    let motion_err = |err| ProgramError::Motion {
        file: file.to_string(),
        err,
        unit: interp::LengthUnit::Mm,
    };
    let geom = spec.geometry();
    let joint_limits = JointLimits::new(&spec.motion, &rotary);
    let (mut q_mm, mut abc_deg, mut t0_s) = (spec.axes.home_mm, [0.0; 3], 0.0);
    let mut pieces = Vec::new();
    for (moves, length_mm) in runs(&moves, &tcp) {
        let start_mm = match length_mm {
            Some(l) => tip_for_joints(&geom, l, q_mm, abc_deg),
            None => q_mm,
        };
        let plan = motion::plan_with_rotary(moves, start_mm, abc_deg, &spec.motion, &rotary)
            .map_err(motion_err)?;
        match length_mm {
            None => motion::check_travel(&plan, spec.axes.travel_min_mm, spec.axes.travel_max_mm)
                .map_err(motion_err)?,
            Some(l) => check_tcp_travel(&geom, l, &plan, spec).map_err(|e| {
                FiveAxisRunError::TcpTravel {
                    file: file.to_string(),
                    err: e,
                }
            })?,
        }
        motion::check_rotary_travel(&plan, &spec.rotary_travel_abc_deg()).map_err(motion_err)?;
        let end = plan.end_state();
        abc_deg = end.abc_deg;
        q_mm = joints_for_tip(&geom, length_mm, end.pos_mm, abc_deg);
        let timing = length_mm.map(|l| PieceTiming::new(&plan, &geom, l, &joint_limits));
        let piece = Piece {
            plan,
            t0_s,
            tcp_length_mm: length_mm,
            timing,
        };
        t0_s += piece.duration_s();
        pieces.push(piece);
    }
    Ok(FivePlan { pieces, geom })
}

/// The moves cut into runs of one frame.
fn runs<'a>(moves: &'a [CanonMove], tcp: &[Option<f64>]) -> Vec<(&'a [CanonMove], Option<f64>)> {
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..=moves.len() {
        if i == moves.len() || tcp[i] != tcp[start] {
            out.push((&moves[start..i], tcp[start]));
            start = i;
        }
    }
    out
}

/// The linear axes along every move of a G43.4 piece stay within their travel.
fn check_tcp_travel(
    geom: &Geometry,
    length_mm: f64,
    plan: &Plan,
    spec: &FiveAxisSpec,
) -> Result<(), TcpTravelError> {
    let (min, max) = (spec.axes.travel_min_mm, spec.axes.travel_max_mm);
    for seg in plan.segments() {
        if !matches!(
            seg.kind,
            SegmentKind::Rapid | SegmentKind::Feed | SegmentKind::Arc
        ) {
            continue;
        }
        let n = (seg.duration_s / TRAVEL_CHECK_STEP_S).ceil().max(1.0) as usize;
        for k in 0..=n {
            let t_s = seg.duration_s * k as f64 / n as f64;
            let q = joints_for_tip(
                geom,
                Some(length_mm),
                seg.position_at_local(t_s),
                seg.abc_at_local(t_s),
            );
            for i in 0..3 {
                // 1 nm: the rounding of the kinematics at a limit the program reaches exactly.
                if q[i] < min[i] - 1e-6 || q[i] > max[i] + 1e-6 {
                    return Err(TcpTravelError {
                        line: seg.line,
                        axis: ['X', 'Y', 'Z'][i],
                        value_mm: q[i],
                        min_mm: min[i],
                        max_mm: max[i],
                    });
                }
            }
        }
    }
    Ok(())
}
