//! Would this program crash the machine? Collision and travel checks of a motion plan
//!, on the rapier f64 geometry stack (parry3d-f64 0.31, the crate rapier3d-f64 0.36
//! builds its colliders from).
//!
//! # Frames
//! Everything is expressed in the **machine frame of the planner**: the commanded tool tip
//! relative to the table (ISO 841), mm, the frame the interpreter's canonical moves and the plan
//! are in. On the real machine X and Y move the table (workpiece side) and Z moves the head; in
//! this relative frame the table, the fixture and the stock are static, and the head's bodies
//! (tool, holder, spindle nose) translate with the commanded tip. The geometry is nominal: the
//! machine's geometric and thermal errors (tens of µm) are far below the 0.1 mm resolution of
//! the check. glam types (`DVec3`, `Pose`) are used inside this module only.
//!
//! # Bodies
//! - Moving, coaxial vertical cylinders on the spindle axis through the tip: the **tool** from
//!   the tip up to the holder (`|tool.offset_mm[2]| − holder.length_mm` long, `tool.diameter_mm`),
//!   the **holder** (`collision.holder`, below the gauge point) and the **spindle nose**
//!   (`collision.spindle_nose`, above the gauge point). The machine file has one tool; an M6
//!   loads that same tool.
//! - Static: boxes and vertical cylinders from the machine file's `[collision]` section (the
//!   table) and an optional fixture file (vise, clamps, stock), see [`spec`]. parry cylinders
//!   are Y-aligned, so every cylinder is rotated by 90° about X.
//!
//! # Method: dense sampling along the exact path
//! Every motion segment (G0, G1, and G2/G3 on the arc or helix itself, not on chords) is sampled
//! at equal path steps of at most [`SAMPLE_SPACING_MM`] = 0.2 mm, both ends included, and at each
//! sample every (moving, static) pair whose bounding boxes overlap is tested with parry's exact
//! `contact` query (GJK/EPA), which gives the penetration depth. Why nothing deeper than 0.1 mm
//! can be missed: the bodies only translate, and the penetration depth of a translated body is
//! 1-Lipschitz in the translation (moving it back by `d` separates it if it was `d` deep). Every
//! point of the path is within 0.1 mm of path length — hence of straight-line distance — of a
//! sample, so a contact absent at all samples is at most 0.1 mm deep anywhere. Contacts shallower
//! than [`CONTACT_TOLERANCE_MM`] (touching faces) are not reported.
//!
//! # What is a crash
//! - Any contact of the holder or the spindle nose with anything, and any contact with the table
//!   or a fixture, on any move.
//! - The tool in the stock on a rapid (G0) — except a pure retraction along +Z (X and Y
//!   unchanged, Z rising), which is the tool leaving its own cut — or on a feed move with the
//!   spindle stopped. The tool in the stock at feed (G1/G2/G3) with the spindle running is
//!   cutting, and is not reported.
//! - On a probe move (G38.2 … G38.5) the tool is the probe's stylus: its contact with anything
//!   is what the move is for (the move is planned to where it trips), and only the holder and
//!   the spindle nose can crash. The setup's artefacts (gauge blocks, spheres) are static
//!   bodies checked as fixtures ([`Scene::with_artefacts`]).
//! - Material removal: a stock box is cut by the program's feed moves and the head's bodies are
//!   checked against what is left ([`stock`]): a rapid back into a drilled hole or a cleared
//!   pocket is not a crash. A cylindrical stock stays whole.
//!
//! One [`Problem`] is reported per segment and pair of bodies in contact (with the first contact
//! and the deepest point), and one per segment and axis out of travel, move by move in plan
//! order, through a [`CheckObserver`] (the shape a recorder needs to draw them).

pub use crate::collision_spec as spec;
mod artefacts;
mod checker;
pub use checker::{check_plan, PlanChecker};
pub mod stock;
#[cfg(test)]
mod tests;

use parry3d_f64::math::{Pose, Vector};
use parry3d_f64::query;
use parry3d_f64::shape::{Cuboid, Cylinder, Shape};
use serde::Serialize;

use crate::machine::MachineSpec;
use crate::motion::{Geometry, MotionError, Segment, SegmentKind};
use crate::tools::ToolTable;
pub use spec::{BodyRole, BodySpec, CollisionSpec, FixtureSpec, ShapeKind, SpindleCylinder};
use stock::CutStock;
pub use stock::CUT_GRID_MM;

/// Largest path step between two samples of a segment, mm (0.2 mm: no contact deeper than
/// 0.1 mm can be missed, see the module doc).
pub const SAMPLE_SPACING_MM: f64 = 0.2;

/// Penetrations at or below this depth are touching, not contact (mm).
pub const CONTACT_TOLERANCE_MM: f64 = 1.0e-4;

/// The bodies that move with the head.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum HeadBody {
    /// The exposed tool, tip to holder.
    Tool,
    /// The tool holder.
    Holder,
    /// The spindle nose.
    SpindleNose,
}

impl HeadBody {
    /// Name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            HeadBody::Tool => "tool",
            HeadBody::Holder => "holder",
            HeadBody::SpindleNose => "spindle nose",
        }
    }
}

/// Kind of move during which a problem happened.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MoveKind {
    /// G0.
    Rapid,
    /// G1.
    Feed,
    /// G2/G3.
    Arc,
    /// G38.2 … G38.5.
    Probe,
}

impl MoveKind {
    fn label(self) -> &'static str {
        match self {
            MoveKind::Rapid => "G0 rapid",
            MoveKind::Feed => "G1 feed",
            MoveKind::Arc => "G2/G3 arc",
            MoveKind::Probe => "G38 probe move",
        }
    }
}

/// A contact that is a crash: plain data, so that a recorder can draw it at its time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Collision {
    /// Source line of the move.
    pub line: usize,
    /// Move kind.
    pub move_kind: MoveKind,
    /// The head body in contact.
    pub head_body: HeadBody,
    /// The static body it touches.
    pub other_body: String,
    /// That body's role.
    pub other_role: BodyRole,
    /// Why this contact is a crash (e.g. "rapid into the stock").
    pub reason: &'static str,
    /// Plan time of the first contact, s.
    pub first_contact_time_s: f64,
    /// Commanded tool tip at the first contact, mm.
    pub first_contact_tip_mm: [f64; 3],
    /// Plan time of the deepest penetration along the move, s.
    pub time_s: f64,
    /// Commanded tool tip at the deepest penetration, mm.
    pub tip_mm: [f64; 3],
    /// Contact point (on the static body's surface) at the deepest penetration, mm.
    pub contact_point_mm: [f64; 3],
    /// Deepest penetration along the move, mm.
    pub depth_mm: f64,
}

/// An axis beyond its travel on one segment.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TravelViolation {
    /// Source line of the move.
    pub line: usize,
    /// Plan time at the segment's start, s.
    pub time_s: f64,
    /// Axis letter.
    pub axis: char,
    /// Extreme position reached, mm.
    pub pos_mm: f64,
    /// Travel limits, mm.
    pub min_mm: f64,
    /// Travel limits, mm.
    pub max_mm: f64,
}

impl TravelViolation {
    /// The same message `run` and `campaign` refuse a program with.
    pub fn message(&self) -> String {
        MotionError::AxisOutOfTravel {
            line: self.line,
            axis: self.axis,
            pos_mm: self.pos_mm,
            min_mm: self.min_mm,
            max_mm: self.max_mm,
        }
        .to_string()
    }
}

/// One problem found by [`check_plan`].
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Problem {
    /// A crash.
    Collision(Collision),
    /// Out of travel.
    Travel(TravelViolation),
}

impl Problem {
    /// Source line.
    pub fn line(&self) -> usize {
        match self {
            Problem::Collision(c) => c.line,
            Problem::Travel(t) => t.line,
        }
    }
}

fn fmt_xyz(p: [f64; 3]) -> String {
    format!("X{:.3} Y{:.3} Z{:.3}", p[0], p[1], p[2])
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Problem::Travel(t) => f.write_str(&t.message()),
            Problem::Collision(c) => write!(
                f,
                "line {}: {}: {} hits {} ({}{}), {:.3} mm deep at tool tip {} (t = {:.3} s), contact point {}; first contact at tool tip {} (t = {:.3} s)",
                c.line,
                c.move_kind.label(),
                c.head_body.name(),
                c.other_body,
                c.other_role.name(),
                if c.other_role == BodyRole::Stock && c.head_body == HeadBody::Tool {
                    format!(": {}", c.reason)
                } else {
                    String::new()
                },
                c.depth_mm,
                fmt_xyz(c.tip_mm),
                c.time_s,
                fmt_xyz(c.contact_point_mm),
                fmt_xyz(c.first_contact_tip_mm),
                c.first_contact_time_s,
            ),
        }
    }
}

/// Receives each problem as it is found, move by move, in plan order.
pub trait CheckObserver {
    /// Called once per problem.
    fn on_problem(&mut self, problem: &Problem);
}

impl CheckObserver for Vec<Problem> {
    fn on_problem(&mut self, problem: &Problem) {
        self.push(problem.clone());
    }
}

/// Counts of a finished check.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct CheckSummary {
    /// Motion segments checked.
    pub segments: usize,
    /// Total path length, mm.
    pub path_mm: f64,
    /// Poses sampled (0 without collision geometry).
    pub samples: usize,
    /// Collisions reported.
    pub collisions: usize,
    /// Travel violations reported.
    pub travel_violations: usize,
}

impl CheckSummary {
    /// True when nothing was reported.
    pub fn is_clean(&self) -> bool {
        self.collisions == 0 && self.travel_violations == 0
    }
}

/// A moving body: a vertical cylinder whose centre sits `center_above_tip_mm` above the tip.
#[derive(Debug, Clone)]
struct Moving {
    body: HeadBody,
    shape: Cylinder,
    center_above_tip_mm: f64,
    radius_mm: f64,
    half_height_mm: f64,
}

/// A static body with its pose and bounding box.
struct Static {
    name: String,
    role: BodyRole,
    shape: Box<dyn Shape>,
    pose: Pose,
    lo_mm: [f64; 3],
    hi_mm: [f64; 3],
    /// A stock box whose material the tool removes (checked on its Z-map, see [`stock`]).
    cut: bool,
}

/// The collision scene of a machine and an optional fixture.
pub struct Scene {
    moving: Vec<Moving>,
    statics: Vec<Static>,
    /// The tools `M6` loads (empty: the machine file's own tool for every number).
    tools: ToolTable,
    /// The machine file's own tool length, mm: the commanded position is that tool's tip.
    master_length_mm: f64,
    /// The holder's length below the gauge point, mm.
    holder_length_mm: f64,
}

/// A check that could not be completed.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// The machine's travel range is invalid.
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// The geometry library has no contact query for this pair of shapes (a build defect: the
    /// shapes are boxes and cylinders, which parry supports with its `alloc` feature).
    #[error("no contact query between the {head} and {body}")]
    Unsupported {
        /// Head body.
        head: &'static str,
        /// Static body.
        body: String,
    },
    /// A stock box cannot be gridded for material removal.
    #[error("stock {body}: {message}")]
    StockGrid {
        /// The stock body.
        body: String,
        /// Why.
        message: String,
    },
}

/// A scene that cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The machine has no `[collision]` section.
    #[error("machine {0}: no [collision] section (holder, spindle nose, table): cannot check collisions")]
    NoGeometry(String),
}

/// A head body: a vertical cylinder of `diameter_mm` from `bottom_mm` above the commanded tip,
/// `length_mm` long.
fn cyl(body: HeadBody, diameter_mm: f64, bottom_mm: f64, length_mm: f64) -> Moving {
    Moving {
        body,
        shape: Cylinder::new(0.5 * length_mm, 0.5 * diameter_mm),
        center_above_tip_mm: bottom_mm + 0.5 * length_mm,
        radius_mm: 0.5 * diameter_mm,
        half_height_mm: 0.5 * length_mm,
    }
}

/// Parry cylinders are Y-aligned: this pose puts one on the Z axis at `center`.
fn vertical_pose(center: [f64; 3]) -> Pose {
    Pose::new(
        Vector::new(center[0], center[1], center[2]),
        Vector::new(std::f64::consts::FRAC_PI_2, 0.0, 0.0),
    )
}

impl Scene {
    /// The head bodies of `machine` (which must have a `[collision]` section) and the static
    /// bodies of its table plus `fixture`.
    pub fn new(machine: &MachineSpec, fixture: Option<&FixtureSpec>) -> Result<Self, SceneError> {
        let c = machine
            .collision
            .as_ref()
            .ok_or_else(|| SceneError::NoGeometry(machine.machine.name.clone()))?;
        let tool_len_mm = crate::tools::master_length_mm(machine);
        let exposed_mm = tool_len_mm - c.holder.length_mm;
        let moving = vec![
            cyl(HeadBody::Tool, machine.tool.diameter_mm, 0.0, exposed_mm),
            cyl(
                HeadBody::Holder,
                c.holder.diameter_mm,
                exposed_mm,
                c.holder.length_mm,
            ),
            cyl(
                HeadBody::SpindleNose,
                c.spindle_nose.diameter_mm,
                tool_len_mm,
                c.spindle_nose.length_mm,
            ),
        ];
        let statics = c
            .bodies
            .iter()
            .chain(fixture.iter().flat_map(|f| f.bodies.iter()))
            .map(Self::static_body)
            .collect();
        Ok(Scene {
            moving,
            statics,
            tools: ToolTable::default(),
            master_length_mm: tool_len_mm,
            holder_length_mm: c.holder.length_mm,
        })
    }

    /// The same scene where `M6` loads the tools of `tools` (the tool body follows the loaded
    /// tool: its diameter, and its tip `length − master length` below the commanded position,
    /// see [`crate::tools`]).
    #[must_use]
    pub fn with_tools(mut self, tools: ToolTable) -> Self {
        self.tools = tools;
        self
    }

    /// The tool body after `M6` with tool `number` (the current body when the table lacks it;
    /// the interpreter refuses such a program first).
    fn loaded_tool_body(&self, number: u32, machine: &MachineSpec, current: &Moving) -> Moving {
        match self.tools.loaded(number, machine) {
            Some(t) => cyl(
                HeadBody::Tool,
                t.diameter_mm,
                self.master_length_mm - t.length_mm,
                t.length_mm - self.holder_length_mm,
            ),
            None => current.clone(),
        }
    }

    fn static_body(b: &BodySpec) -> Static {
        // Validated specs have the fields of their shape.
        let (shape, pose, lo_mm, hi_mm): (Box<dyn Shape>, Pose, [f64; 3], [f64; 3]) = match b.shape
        {
            ShapeKind::Box => {
                let lo = b.min_mm.unwrap_or_default();
                let hi = b.max_mm.unwrap_or_default();
                let half = [0, 1, 2].map(|i| 0.5 * (hi[i] - lo[i]));
                let c = [0, 1, 2].map(|i| 0.5 * (hi[i] + lo[i]));
                (
                    Box::new(Cuboid::new(Vector::new(half[0], half[1], half[2]))),
                    Pose::from_translation(Vector::new(c[0], c[1], c[2])),
                    lo,
                    hi,
                )
            }
            ShapeKind::Cylinder => {
                let base = b.base_center_mm.unwrap_or_default();
                let r = b.radius_mm.unwrap_or(1.0);
                let h = b.height_mm.unwrap_or(1.0);
                (
                    Box::new(Cylinder::new(0.5 * h, r)),
                    vertical_pose([base[0], base[1], base[2] + 0.5 * h]),
                    [base[0] - r, base[1] - r, base[2]],
                    [base[0] + r, base[1] + r, base[2] + h],
                )
            }
        };
        Static {
            name: b.name.clone(),
            role: b.role,
            shape,
            pose,
            lo_mm,
            hi_mm,
            cut: b.role == BodyRole::Stock && b.shape == ShapeKind::Box,
        }
    }

    /// True when a stock box is checked with material removal ([`stock`]).
    pub fn has_cut_stock(&self) -> bool {
        self.statics.iter().any(|s| s.cut)
    }

    /// One line per body, for reports.
    pub fn describe(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .moving
            .iter()
            .map(|m| {
                format!(
                    "{}: Ø{} × {} mm, from {} mm above the tip",
                    m.body.name(),
                    2.0 * m.radius_mm,
                    2.0 * m.half_height_mm,
                    m.center_above_tip_mm - m.half_height_mm
                )
            })
            .collect();
        out.extend(self.statics.iter().map(|s| {
            format!(
                "{} ({}): {} … {} mm",
                s.name,
                s.role.name(),
                fmt_xyz(s.lo_mm),
                fmt_xyz(s.hi_mm)
            )
        }));
        out
    }

    /// Bounding box of moving body `m` with its tip anywhere in `[lo, hi]`.
    fn moving_box(m: &Moving, lo: [f64; 3], hi: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let zl = m.center_above_tip_mm - m.half_height_mm;
        let zh = m.center_above_tip_mm + m.half_height_mm;
        (
            [lo[0] - m.radius_mm, lo[1] - m.radius_mm, lo[2] + zl],
            [hi[0] + m.radius_mm, hi[1] + m.radius_mm, hi[2] + zh],
        )
    }

    /// Penetration depth (mm, > tolerance) and contact point on the static body, if any.
    fn penetration(
        &self,
        m: &Moving,
        s: &Static,
        tip_mm: [f64; 3],
    ) -> Result<Option<(f64, [f64; 3])>, CheckError> {
        let (lo, hi) = Self::moving_box(m, tip_mm, tip_mm);
        if !overlap(lo, hi, s.lo_mm, s.hi_mm) {
            return Ok(None);
        }
        let pose = vertical_pose([tip_mm[0], tip_mm[1], tip_mm[2] + m.center_above_tip_mm]);
        let c = query::contact(&pose, &m.shape, &s.pose, s.shape.as_ref(), 0.0).map_err(|_| {
            CheckError::Unsupported {
                head: m.body.name(),
                body: s.name.clone(),
            }
        })?;
        Ok(c.and_then(|c| {
            let depth = -c.dist;
            (depth > CONTACT_TOLERANCE_MM).then_some((depth, [c.point2.x, c.point2.y, c.point2.z]))
        }))
    }
}

fn overlap(alo: [f64; 3], ahi: [f64; 3], blo: [f64; 3], bhi: [f64; 3]) -> bool {
    (0..3).all(|i| alo[i] <= bhi[i] && blo[i] <= ahi[i])
}

/// Why a contact of `head` with a body of `role` on `seg` is a crash; `None` when it is allowed.
fn crash_reason(head: HeadBody, role: BodyRole, seg: &Segment) -> Option<&'static str> {
    match (head, role) {
        // On a probe move the tool is the probe's stylus: touching is its purpose, and the
        // move ends where it trips.
        (HeadBody::Tool, _) if seg.probe => None,
        (HeadBody::Tool, BodyRole::Stock) => match seg.kind {
            SegmentKind::Rapid => {
                let retract = matches!(seg.geometry, Geometry::Line { dir, .. }
                    if dir[0] == 0.0 && dir[1] == 0.0 && dir[2] > 0.0);
                (!retract).then_some("rapid into the stock")
            }
            _ if seg.spindle_rpm <= 0.0 => Some("cut with the spindle stopped"),
            _ => None,
        },
        (HeadBody::Tool, BodyRole::Table) => Some("tool contact with the table"),
        (HeadBody::Tool, BodyRole::Fixture) => Some("tool contact with a fixture"),
        (HeadBody::Holder, _) => Some("holder contact"),
        (HeadBody::SpindleNose, _) => Some("spindle-nose contact"),
    }
}

fn move_kind(seg: &Segment) -> Option<MoveKind> {
    match seg.kind {
        SegmentKind::Feed if seg.probe => Some(MoveKind::Probe),
        SegmentKind::Rapid => Some(MoveKind::Rapid),
        SegmentKind::Feed => Some(MoveKind::Feed),
        SegmentKind::Arc => Some(MoveKind::Arc),
        SegmentKind::Dwell | SegmentKind::ToolChange { .. } => None,
    }
}

/// For a line segment: the path interval `[s0, s1]` (mm) over which the bounding box of `m`
/// overlaps that of `st`; `None` when it never does (or for an arc, which is sampled whole).
fn line_window(seg: &Segment, m: &Moving, st: &Static) -> Option<(f64, f64)> {
    let Geometry::Line { dir, length_mm } = seg.geometry else {
        return None;
    };
    let (lo_off, hi_off) = Scene::moving_box(m, [0.0; 3], [0.0; 3]);
    let (mut s0, mut s1) = (0.0f64, length_mm);
    for i in 0..3 {
        // Need: p_i(s) + lo_off_i ≤ hi_i  and  lo_i ≤ p_i(s) + hi_off_i, p_i(s) = a_i + d_i·s.
        let a = seg.start_mm[i];
        let (lo, hi) = (st.lo_mm[i] - hi_off[i] - a, st.hi_mm[i] - lo_off[i] - a);
        if dir[i] == 0.0 {
            if lo > 0.0 || hi < 0.0 {
                return None;
            }
        } else {
            let (t0, t1) = (lo / dir[i], hi / dir[i]);
            s0 = s0.max(t0.min(t1));
            s1 = s1.min(t0.max(t1));
        }
    }
    (s0 <= s1).then_some((s0, s1))
}

/// Bounding box of a segment's tip path.
fn segment_bounds(seg: &Segment) -> ([f64; 3], [f64; 3]) {
    match &seg.geometry {
        Geometry::Arc(arc) => arc.bounds_mm(),
        _ => {
            let (a, b) = (seg.start_mm, seg.end_mm);
            (
                [0, 1, 2].map(|i| a[i].min(b[i])),
                [0, 1, 2].map(|i| a[i].max(b[i])),
            )
        }
    }
}

/// The contacts of one (head body, static body) pair along one segment.
struct PairHits {
    head: HeadBody,
    static_index: usize,
    reason: &'static str,
    found: Option<Collision>,
    /// Depth at the segment's start (0 when not in contact there).
    start_depth_mm: f64,
}

impl PairHits {
    fn new(head: HeadBody, static_index: usize, reason: &'static str) -> Self {
        Self {
            head,
            static_index,
            reason,
            found: None,
            start_depth_mm: 0.0,
        }
    }

    /// A contact `depth_mm` deep at sample `k` (path length `s_mm`, tip `tip`).
    #[allow(clippy::too_many_arguments)]
    fn add(
        &mut self,
        seg: &Segment,
        kind: MoveKind,
        s: &Static,
        k: usize,
        s_mm: f64,
        tip: [f64; 3],
        depth_mm: f64,
        point: [f64; 3],
    ) {
        if k == 0 {
            self.start_depth_mm = depth_mm;
        }
        let time_s = seg.t_start_s + seg.profile.time_at_distance(s_mm);
        let c = self.found.get_or_insert_with(|| Collision {
            line: seg.line,
            move_kind: kind,
            head_body: self.head,
            other_body: s.name.clone(),
            other_role: s.role,
            reason: self.reason,
            first_contact_time_s: time_s,
            first_contact_tip_mm: tip,
            time_s,
            tip_mm: tip,
            contact_point_mm: point,
            depth_mm: 0.0,
        });
        if depth_mm > c.depth_mm {
            c.depth_mm = depth_mm;
            c.time_s = time_s;
            c.tip_mm = tip;
            c.contact_point_mm = point;
        }
    }
}
