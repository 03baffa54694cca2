//! Cutter radius compensation (G41 / G42, G41.1 / G42.1, G40) with LinuxCNC's semantics.
//!
//! Works in the active plane's coordinates (XY for G17, ZX for G18; G19 is refused), on the
//! tool centre's path, in machine mm:
//! - the side is +1 (left, G41) or −1 (right, G42); a negative G41.1/G42.1 diameter swaps it;
//! - the entry move (the first move after G41/G42) ends at the programmed end offset by the
//!   radius perpendicular to the entry move; it must be longer than the radius in the plane
//!   (so a move along the plane's axis alone cannot be the entry). An arc as the entry move is
//!   not supported (LinuxCNC moves its end off the offset circle);
//! - later moves are offset by the radius perpendicular to the programmed path (lines move
//!   sideways, arcs keep their centre and change radius by ± the tool radius, the end taken
//!   on the end radius; an arc that would shrink to nothing is refused);
//! - corners, from the programmed tangents: a turn away from the tool's side by more than
//!   [`CORNER_TOL_RAD`] (outside corner) inserts an arc of the tool radius around the
//!   programmed corner; a turn towards it by more than that (inside corner) moves the end of
//!   the previous compensated move to the intersection of the two offset paths (one move of
//!   look-ahead: the previous move, and the axis-only moves after it, are held until the next
//!   move in the plane is known; after an arc, the intersection is the last one before its
//!   end); smaller turns join the moves as they are. A turn within [`CORNER_TOL_RAD`] of a
//!   full reversal is an inside corner only if an arc's offset path meets the other one.
//!   Rapid moves take a straight line around an outside corner. Radius 0 joins nothing;
//! - an inside corner that would make the previous move run backwards is refused (gouging);
//! - moves along the plane's axis only keep the compensated plane position;
//! - G40: the held moves are final; the next move (the exit) goes straight from the
//!   compensated position to the programmed point; an arc there is refused.

use std::f64::consts::TAU;

use super::{CanonKind, CanonMove};

/// Turn angle (rad) below which a corner is treated as tangent (LinuxCNC's value).
pub(super) const CORNER_TOL_RAD: f64 = 0.05;

/// Angles closer than this (rad) are equal (rounding of intersections).
const ANGLE_EPS: f64 = 1e-6;

type P2 = [f64; 2];

fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}
fn add(a: P2, b: P2) -> P2 {
    [a[0] + b[0], a[1] + b[1]]
}
fn scale(a: P2, k: f64) -> P2 {
    [a[0] * k, a[1] * k]
}
fn dot(a: P2, b: P2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn cross(a: P2, b: P2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
fn norm(a: P2) -> f64 {
    a[0].hypot(a[1])
}
fn unit(a: P2) -> P2 {
    scale(a, 1.0 / norm(a))
}
/// `a` turned 90° counter-clockwise.
fn perp(a: P2) -> P2 {
    [-a[1], a[0]]
}

/// An offset path, for intersections at inside corners.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Path {
    Line { point: P2, dir: P2 },
    Circle { center: P2, radius: f64, ccw: bool },
}

/// The last compensated move in the plane (held until the next one is known).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Prev {
    /// Programmed tangent (unit) at its end.
    tangent: P2,
    path: Path,
    /// Start of the compensated move.
    start: P2,
    rapid: bool,
    /// The entry move (LinuxCNC does not check its direction).
    entry: bool,
}

/// Why a move cannot be compensated: the message, and whether the move is merely outside
/// what is supported (rather than invalid).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct CompError {
    pub msg: String,
    pub unsupported: bool,
}

impl From<&str> for CompError {
    fn from(msg: &str) -> Self {
        Self {
            msg: msg.to_string(),
            unsupported: false,
        }
    }
}

impl From<String> for CompError {
    fn from(msg: String) -> Self {
        Self {
            msg,
            unsupported: false,
        }
    }
}

/// Compensation while on.
#[derive(Debug, Clone, PartialEq)]
struct Active {
    /// +1: left of the path (G41), −1: right (G42).
    side: f64,
    radius_mm: f64,
    /// First and second plane axis, plane axis.
    axes: [usize; 3],
    /// The entry move is still to come.
    first_move: bool,
    prev: Option<Prev>,
}

/// The compensation state and the output it holds back (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct CutterComp {
    active: Option<Active>,
    /// Compensated tool position (machine mm) while it differs from the programmed one.
    tool_mm: Option<[f64; 3]>,
    /// G40 ran; the next move is the exit move.
    exit_pending: bool,
    /// Output not yet final, in order.
    held: Vec<CanonMove>,
    /// Indices in `held` of the moves whose plane end point follows the next inside corner.
    tail: Vec<usize>,
    /// The same for the current block's output (indices into it).
    block_tail: Vec<usize>,
    /// A, B, C of the moves compensation adds, degrees (the rotary axes do not move while
    /// compensation is on: the interpreter refuses such moves).
    abc_deg: [f64; 3],
}

impl CutterComp {
    /// True while G41/G42 is in effect.
    pub fn is_on(&self) -> bool {
        self.active.is_some()
    }

    /// True if moves must go through [`Self::motion`].
    pub fn takes_motion(&self) -> bool {
        self.active.is_some() || self.exit_pending
    }

    /// Turns compensation on: `side` +1 left / −1 right, `radius_mm` ≥ 0, plane axes.
    pub fn turn_on(&mut self, side: f64, radius_mm: f64, axes: [usize; 3]) {
        self.active = Some(Active {
            side,
            radius_mm,
            axes,
            first_move: true,
            prev: None,
        });
        self.exit_pending = false;
    }

    /// G40: the held moves become final; the next move is the exit move.
    pub fn turn_off(&mut self) -> Result<(), CompError> {
        if let Some(a) = self.active.take() {
            if let (Some(prev), Some(tool)) = (a.prev, self.tool_mm) {
                check_line_direction(&prev, [tool[a.axes[0]], tool[a.axes[1]]])?;
            }
            self.exit_pending = true;
        }
        self.tail.clear();
        Ok(())
    }

    /// The compensated tool position while it differs from the programmed one (machine mm).
    pub fn tool_position(&self) -> Option<[f64; 3]> {
        self.tool_mm
    }

    /// A tool change re-reads the machine position: the compensated point left by the last
    /// compensated move (if any) becomes the programmed one. Returns it.
    pub fn take_tool_position(&mut self) -> Option<[f64; 3]> {
        self.tool_mm.take()
    }

    /// Compensates one programmed move (`start_mm` → the move's end, machine mm) and pushes
    /// what the block emits for it onto `out` (the block's output so far). On error the
    /// message to report at the block's motion word.
    pub fn motion(
        &mut self,
        start_mm: [f64; 3],
        kind: &CanonKind,
        out: &mut Vec<CanonKind>,
    ) -> Result<(), CompError> {
        let Some(mut a) = self.active.take() else {
            if matches!(kind, CanonKind::Arc { .. }) {
                return Err(
                    "The move just after exiting cutter compensation mode must be straight, \
                            not an arc"
                        .into(),
                );
            }
            self.exit_pending = false;
            self.tool_mm = None;
            out.push(kind.clone());
            return Ok(());
        };
        if let CanonKind::Traverse { end_abc_deg, .. }
        | CanonKind::Feed { end_abc_deg, .. }
        | CanonKind::Arc { end_abc_deg, .. } = kind
        {
            self.abc_deg = *end_abc_deg;
        }
        let r = self.compensate(&mut a, start_mm, kind, out);
        self.active = Some(a);
        r
    }

    fn compensate(
        &mut self,
        a: &mut Active,
        start_mm: [f64; 3],
        kind: &CanonKind,
        out: &mut Vec<CanonKind>,
    ) -> Result<(), CompError> {
        let [a1, a2, ax] = a.axes;
        let plane = |p: [f64; 3]| [p[a1], p[a2]];
        let tool = self.tool_mm.unwrap_or(start_mm);
        let put = |p: P2, axis: f64| {
            let mut m = [0.0; 3];
            m[a1] = p[0];
            m[a2] = p[1];
            m[ax] = axis;
            m
        };
        let (s, r) = (a.side, a.radius_mm);
        let (p0, cur) = (plane(start_mm), plane(tool));
        match *kind {
            CanonKind::Traverse { end_mm, .. } | CanonKind::Feed { end_mm, .. } => {
                let rapid = matches!(kind, CanonKind::Traverse { .. });
                let p1 = plane(end_mm);
                if p1 == p0 && !a.first_move {
                    // Along the plane's axis only: stays at the compensated plane position.
                    let end = put(cur, end_mm[ax]);
                    self.block_tail.push(out.len());
                    out.push(with_end(kind, end));
                    self.tool_mm = Some(end);
                    return Ok(());
                }
                let (dir, start) = if a.first_move {
                    let d = norm(sub(p1, cur));
                    if d <= r {
                        return Err(
                            "Length of cutter compensation entry move is not greater than \
                             the tool radius"
                                .into(),
                        );
                    }
                    (unit(sub(p1, cur)), cur)
                } else {
                    let dir = unit(sub(p1, p0));
                    let s0 = add(p0, scale(perp(dir), s * r));
                    let path = Path::Line { point: s0, dir };
                    let feed = feed_of(kind);
                    let start = self.corner(a, p0, dir, path, s0, tool[ax], feed, out)?;
                    (dir, start)
                };
                let e = add(p1, scale(perp(dir), s * r));
                let end = put(e, end_mm[ax]);
                self.block_tail.push(out.len());
                out.push(with_end(kind, end));
                a.prev = Some(Prev {
                    tangent: dir,
                    path: Path::Line { point: e, dir },
                    start,
                    rapid,
                    entry: a.first_move,
                });
                a.first_move = false;
                self.tool_mm = Some(end);
                Ok(())
            }
            CanonKind::Arc {
                end_mm,
                center_mm,
                plane: arc_plane,
                clockwise,
                extra_turns,
                feed_mm_per_min,
                end_abc_deg,
            } => {
                let (p1, c) = (plane(end_mm), plane(center_mm));
                let ccw = !clockwise;
                let rot = if ccw { 1.0 } else { -1.0 };
                let big_r = norm(sub(p0, c));
                let off_r = big_r - s * r * rot;
                if off_r <= 0.0 {
                    return Err("Tool radius not less than arc radius with comp".into());
                }
                let u0 = unit(sub(p0, c));
                // The end radius may differ a little from the start's (accepted spirals).
                let off_r_end = norm(sub(p1, c)) - s * r * rot;
                let u1 = unit(sub(p1, c));
                let e = add(c, scale(u1, off_r_end));
                let (start, center) = if a.first_move {
                    return Err(CompError {
                        msg: "an arc as the cutter compensation entry move is not supported \
                              (LinuxCNC moves its centre; use a straight entry move)"
                            .into(),
                        unsupported: true,
                    });
                } else {
                    let t0 = scale(perp(u0), rot);
                    let s0 = add(c, scale(u0, off_r));
                    // LinuxCNC meets a line with the start radius, an arc with the end radius
                    // (they differ within the accepted spiral tolerance).
                    let after_arc = matches!(
                        a.prev,
                        Some(Prev {
                            path: Path::Circle { .. },
                            ..
                        })
                    );
                    let path = Path::Circle {
                        center: c,
                        radius: if after_arc { off_r_end } else { off_r },
                        ccw,
                    };
                    let start =
                        self.corner(a, p0, t0, path, s0, tool[ax], Some(feed_mm_per_min), out)?;
                    (start, c)
                };
                let end = put(e, end_mm[ax]);
                self.block_tail.push(out.len());
                out.push(CanonKind::Arc {
                    end_mm: end,
                    end_abc_deg,
                    center_mm: put(center, tool[ax]),
                    plane: arc_plane,
                    clockwise,
                    extra_turns,
                    feed_mm_per_min,
                });
                a.prev = Some(Prev {
                    tangent: scale(perp(u1), rot),
                    path: Path::Circle {
                        center: c,
                        radius: off_r_end,
                        ccw,
                    },
                    start,
                    rapid: false,
                    entry: false,
                });
                a.first_move = false;
                self.tool_mm = Some(end);
                Ok(())
            }
            _ => {
                out.push(kind.clone());
                Ok(())
            }
        }
    }

    /// Joins the previous compensated move to the next one, whose programmed start is the
    /// corner `p0`, start tangent `t2`, offset path `path` and offset start `s0`. Returns
    /// where the next move starts.
    #[allow(clippy::too_many_arguments)]
    fn corner(
        &mut self,
        a: &Active,
        p0: P2,
        t2: P2,
        path: Path,
        s0: P2,
        axis_mm: f64,
        feed_mm_per_min: Option<f64>,
        out: &mut Vec<CanonKind>,
    ) -> Result<P2, CompError> {
        let [a1, a2, ax] = a.axes;
        let tool = self.tool_mm.unwrap_or_default();
        let cur = [tool[a1], tool[a2]];
        let tail = std::mem::take(&mut self.tail);
        let Some(prev) = a.prev.filter(|_| a.radius_mm > 0.0) else {
            // Nothing to join (radius 0: the programmed path itself).
            return Ok(cur);
        };
        let t1 = prev.tangent;
        let turn = a.side * cross(t1, t2).atan2(dot(t1, t2));
        let outside = if turn.abs() > std::f64::consts::PI - CORNER_TOL_RAD {
            // The path (almost) reverses: an inside corner only where an arc's offset path
            // meets the other one.
            match (prev.path, path) {
                (Path::Line { .. }, Path::Line { .. }) => true,
                _ => intersect(prev.path, path, cur).is_none(),
            }
        } else if turn.abs() <= CORNER_TOL_RAD {
            return Ok(cur);
        } else {
            turn < 0.0
        };
        if outside {
            // Outside corner: around the programmed corner at the tool radius (a rapid move
            // goes straight).
            let mut end_mm = [0.0; 3];
            let mut center_mm = [0.0; 3];
            (end_mm[a1], end_mm[a2], end_mm[ax]) = (s0[0], s0[1], axis_mm);
            (center_mm[a1], center_mm[a2], center_mm[ax]) = (p0[0], p0[1], axis_mm);
            out.push(match feed_mm_per_min {
                None => CanonKind::Traverse {
                    end_mm,
                    end_abc_deg: self.abc_deg,
                },
                Some(feed_mm_per_min) => CanonKind::Arc {
                    end_mm,
                    end_abc_deg: self.abc_deg,
                    center_mm,
                    plane: plane_of(a.axes),
                    clockwise: a.side > 0.0,
                    extra_turns: 0,
                    feed_mm_per_min,
                },
            });
            return Ok(s0);
        }
        // Inside corner: both offset paths meet.
        let x = intersect(prev.path, path, cur).ok_or_else(|| {
            match (prev.path, path) {
                (Path::Circle { .. }, Path::Line { .. }) => {
                    "Arc to straight motion makes a corner the compensated tool can't fit in \
                     without gouging"
                }
                (Path::Circle { .. }, Path::Circle { .. }) => {
                    "Arc to arc motion makes a corner the compensated tool can't fit in \
                     without gouging"
                }
                _ => "Arc move in concave corner cannot be reached by the tool without gouging",
            }
            .to_string()
        })?;
        match prev.path {
            Path::Line { .. } => check_line_direction(&prev, x)?,
            Path::Circle { center, ccw, .. } => {
                // Going back from the end, the arc covers `len`; a point in the first half of
                // the rest lies before its start (the arc would turn the other way), one in
                // the second half a little past its end (radius rounding).
                let len = sweep(center, prev.start, cur, ccw);
                let back = sweep(center, x, cur, ccw);
                if len > ANGLE_EPS && back > len && back < len + (TAU - len) / 2.0 {
                    return Err("Arc move in concave corner cannot be reached by the tool \
                                without gouging"
                        .into());
                }
            }
        }
        for i in tail {
            if let Some(m) = self.held.get_mut(i) {
                set_plane_end(&mut m.kind, a1, a2, x);
            }
        }
        Ok(x)
    }

    /// Ends a block: its output (`kinds`, from line `line`) joins the held output, and what is
    /// final moves to `out`. `all` releases everything (end of program).
    pub fn finish_block(
        &mut self,
        line: usize,
        kinds: Vec<CanonKind>,
        all: bool,
        out: &mut Vec<CanonMove>,
    ) {
        let base = self.held.len();
        self.held
            .extend(kinds.into_iter().map(|kind| CanonMove { line, kind }));
        if self.active.is_some() {
            self.tail
                .extend(self.block_tail.drain(..).map(|i| base + i));
        } else {
            self.block_tail.clear();
            self.tail.clear();
        }
        if all {
            self.tail.clear();
        }
        let keep_from = self.tail.first().copied().unwrap_or(self.held.len());
        out.extend(self.held.drain(..keep_from));
        for i in &mut self.tail {
            *i -= keep_from;
        }
    }
}

/// A straight move, once its end `end` is final, must still run the programmed way (an inside
/// corner before it may have moved its start past its end).
fn check_line_direction(prev: &Prev, end: P2) -> Result<(), CompError> {
    let line = matches!(prev.path, Path::Line { .. }) && !prev.entry;
    if line && dot(sub(end, prev.start), prev.tangent) < -1e-9 {
        let what = if prev.rapid { "traverse" } else { "feed" };
        return Err(format!(
            "Straight {what} in concave corner cannot be reached by the tool without gouging"
        )
        .into());
    }
    Ok(())
}

fn plane_of(axes: [usize; 3]) -> super::Plane {
    match axes[2] {
        2 => super::Plane::Xy,
        1 => super::Plane::Zx,
        _ => super::Plane::Yz,
    }
}

/// The feed of a move, `None` for a rapid.
fn feed_of(kind: &CanonKind) -> Option<f64> {
    match *kind {
        CanonKind::Feed {
            feed_mm_per_min, ..
        }
        | CanonKind::Arc {
            feed_mm_per_min, ..
        } => Some(feed_mm_per_min),
        _ => None,
    }
}

fn with_end(kind: &CanonKind, end: [f64; 3]) -> CanonKind {
    let mut k = kind.clone();
    if let CanonKind::Traverse { end_mm, .. } | CanonKind::Feed { end_mm, .. } = &mut k {
        *end_mm = end;
    }
    k
}

fn set_plane_end(kind: &mut CanonKind, a1: usize, a2: usize, p: P2) {
    if let CanonKind::Traverse { end_mm, .. }
    | CanonKind::Feed { end_mm, .. }
    | CanonKind::Arc { end_mm, .. } = kind
    {
        end_mm[a1] = p[0];
        end_mm[a2] = p[1];
    }
}

/// Angle swept from `from` to `to` around `center` in the given direction, in [0, 2π).
fn sweep(center: P2, from: P2, to: P2, ccw: bool) -> f64 {
    let (u, v) = (sub(from, center), sub(to, center));
    let mut ang = cross(u, v).atan2(dot(u, v));
    if !ccw {
        ang = -ang;
    }
    if ang < 0.0 {
        ang += TAU;
    }
    ang
}

/// The intersection of two offset paths at an inside corner: the last one before the first
/// path's compensated end `end` (one a little past it if it is nearer).
fn intersect(a: Path, b: Path, end: P2) -> Option<P2> {
    let cands = match (a, b) {
        (Path::Line { point: p, dir: d }, Path::Line { point: q, dir: e }) => {
            let den = cross(d, e);
            if den.abs() < 1e-12 {
                return None;
            }
            let t = cross(sub(q, p), e) / den;
            return Some(add(p, scale(d, t)));
        }
        (Path::Line { point, dir }, Path::Circle { center, radius, .. })
        | (Path::Circle { center, radius, .. }, Path::Line { point, dir }) => {
            line_circle(point, dir, center, radius)
        }
        (
            Path::Circle {
                center: c1,
                radius: r1,
                ..
            },
            Path::Circle {
                center: c2,
                radius: r2,
                ..
            },
        ) => circle_circle(c1, r1, c2, r2),
    };
    let key = |p: &P2| match a {
        Path::Circle { center, ccw, .. } => {
            // Angle back from the end; a point past the end counts double.
            let back = sweep(center, *p, end, ccw);
            back.min(2.0 * (TAU - back))
        }
        Path::Line { dir, .. } => {
            // Distance back from the end along the line; past the end counts double.
            let back = dot(sub(end, *p), dir);
            back.max(-2.0 * back)
        }
    };
    cands.into_iter().min_by(|p, q| key(p).total_cmp(&key(q)))
}

fn line_circle(p: P2, d: P2, c: P2, r: f64) -> Vec<P2> {
    // |p + t d − c|² = r², |d| = 1.
    let w = sub(p, c);
    let b = dot(w, d);
    let disc = b * b - (dot(w, w) - r * r);
    if disc < 0.0 {
        return Vec::new();
    }
    let q = disc.sqrt();
    vec![add(p, scale(d, -b - q)), add(p, scale(d, -b + q))]
}

fn circle_circle(c1: P2, r1: f64, c2: P2, r2: f64) -> Vec<P2> {
    let v = sub(c2, c1);
    let d = norm(v);
    if d < 1e-12 || d > r1 + r2 || d < (r1 - r2).abs() {
        return Vec::new();
    }
    let a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d);
    let h = (r1 * r1 - a * a).max(0.0).sqrt();
    let u = scale(v, 1.0 / d);
    let m = add(c1, scale(u, a));
    vec![add(m, scale(perp(u), h)), add(m, scale(perp(u), -h))]
}
