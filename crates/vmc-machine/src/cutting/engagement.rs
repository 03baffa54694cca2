//! Engagement of a flat-end tool along a path, and the removal of what it cuts.
//!
//! At each sample p of a path (equal steps of half a grid cell), with f the unit direction of
//! the motion in the XY plane and n its left normal, the tool's front half-periphery is probed
//! at the angles φ ∈ [0, π] measured clockwise from n (φ = 0 left, π/2 ahead, π right; the
//! angle of the stability model, whose tool turns clockwise and feeds along +x):
//! u(φ) = sin φ·f + cos φ·n. A direction is engaged when material stands more than
//! [`MIN_DEPTH_MM`] above the tip there. The engaged arc [φ_entry, φ_exit] runs from the first to
//! the last engaged direction, widened to the next probe that is not engaged (gaps inside count
//! as engaged), and the axial depth a_p is the highest material above the tip over it. Its
//! radial immersion, a_e/D, if the arc is read as a straight cut:
//!
//! ```text
//! from the left edge (φ = 0 to φ_exit):   a_e/D = (1 − cos φ_exit)/2
//! from the right edge (φ_entry to π):     a_e/D = (1 + cos φ_entry)/2
//! ```
//!
//! [`Side`] says which edge the arc reaches (both: slotting, a_e/D = 1). The samples' discs
//! are then removed from the stock.
//!
//! Probing the grid. Each probe must tell "material the tool meets" from "material this or an
//! earlier pass already removed" at a wall that the cells resolve only to a cell. Two rules do it:
//! - The last [`Sweep::lag_mm`] of removal (L = 2√(R g) + g with g the larger cell side) is kept
//!   as exact discs, not yet written to the grid, and tested exactly at the periphery point
//!   p + R·u: the front half-periphery lies outside every earlier disc of a straight or gently
//!   curved path, so the crescent the tool is cutting is seen down to the edges φ = 0 and π.
//! - The grid is probed at p + r′·u, r′ = R − (half a cell diagonal): the cell found has its
//!   centre inside the tool's disc, so material of a wall that an earlier pass left exactly at
//!   the tool's periphery (the same path again) is not counted. Beyond the lag distance, the
//!   path's own earlier discs have moved clear of these probes. Probing at r′ < R would narrow
//!   the arc; for a wall parallel to the feed direction the arc's inner end is moved back out to
//!   R (cos φ = (r′/R)·cos φ′), only ever widening it.
//!
//! So a radial engagement thinner than about one cell is not seen, and a_e/D is measured to about
//! one cell over D, rounded towards the larger immersion. A sample whose motion is vertical (a
//! plunge) reports a [`Contact`] of kind [`ContactKind::Plunge`] when material stands over its
//! disc. Material below the stock's bottom never exists; the tool's flutes are taken as long as
//! needed.

use std::collections::VecDeque;
use std::f64::consts::PI;

use super::{CuttingError, StockBox, ZMap};

/// Material standing less than this above the tool tip is not counted (mm); 1 µm.
pub const MIN_DEPTH_MM: f64 = 1e-3;

/// Horizontal speed share below which a motion is a plunge (|t_xy| of the unit tangent).
const PLUNGE_TANGENT: f64 = 1e-6;

/// A path of the tool tip, parametrised by its length.
pub trait ToolPath {
    /// Path length (mm).
    fn length_mm(&self) -> f64;
    /// Tool-tip position after `s_mm` along the path (mm).
    fn point_at(&self, s_mm: f64) -> [f64; 3];
    /// Unit tangent at `s_mm` (any finite vector for a path of zero length).
    fn tangent_at(&self, s_mm: f64) -> [f64; 3];
}

/// A straight path from `start_mm` to `end_mm`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// Start (mm).
    pub start_mm: [f64; 3],
    /// End (mm).
    pub end_mm: [f64; 3],
}

impl ToolPath for Line {
    fn length_mm(&self) -> f64 {
        let d = sub3(self.end_mm, self.start_mm);
        (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
    }

    fn point_at(&self, s_mm: f64) -> [f64; 3] {
        let l = self.length_mm();
        let f = if l > 0.0 { s_mm / l } else { 0.0 };
        let d = sub3(self.end_mm, self.start_mm);
        [
            self.start_mm[0] + f * d[0],
            self.start_mm[1] + f * d[1],
            self.start_mm[2] + f * d[2],
        ]
    }

    fn tangent_at(&self, _s_mm: f64) -> [f64; 3] {
        let l = self.length_mm();
        let d = sub3(self.end_mm, self.start_mm);
        if l > 0.0 {
            [d[0] / l, d[1] / l, d[2] / l]
        } else {
            [0.0; 3]
        }
    }
}

fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Which edge of the front half-periphery the engaged arc reaches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The left edge only (φ = 0): material on the left of the motion.
    Left,
    /// The right edge only (φ = π): material on the right of the motion.
    Right,
    /// Both edges: a slot.
    Both,
    /// Neither: material ahead only (entering a wall or a corner).
    Neither,
}

/// The engaged arc of a side-milling sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngagedArc {
    /// Direction of the motion in the XY plane, counter-clockwise from +X (rad).
    pub feed_angle_rad: f64,
    /// First engaged angle φ_entry, clockwise from the left normal (rad, in [0, π]).
    pub entry_rad: f64,
    /// Last engaged angle φ_exit (rad, in [0, π]).
    pub exit_rad: f64,
    /// Which edges it reaches.
    pub side: Side,
}

impl EngagedArc {
    /// a_e/D of the straight cut from the left edge to φ_exit: (1 − cos φ_exit)/2.
    pub fn immersion_from_left(&self) -> f64 {
        (0.5 * (1.0 - self.exit_rad.cos())).clamp(0.0, 1.0)
    }

    /// a_e/D of the straight cut from φ_entry to the right edge: (1 + cos φ_entry)/2.
    pub fn immersion_from_right(&self) -> f64 {
        (0.5 * (1.0 + self.entry_rad.cos())).clamp(0.0, 1.0)
    }
}

/// How the tool meets the material at a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactKind {
    /// Side milling: motion with a horizontal component.
    Side(EngagedArc),
    /// Vertical motion into material.
    Plunge,
}

/// The tool in material at one sample of a path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Distance along the path (mm).
    pub s_mm: f64,
    /// Tool-tip position (mm).
    pub position_mm: [f64; 3],
    /// Axial depth a_p: highest material above the tip over the engaged arc (mm).
    pub axial_depth_mm: f64,
    /// Side milling or plunge.
    pub kind: ContactKind,
}

/// A removal not yet written to the grid.
#[derive(Debug, Clone, Copy)]
struct Stamp {
    xy_mm: [f64; 2],
    z_mm: f64,
    at_mm: f64,
}

/// The stock being cut by one flat-end tool: the Z-map and the last discs removed.
#[derive(Debug, Clone)]
pub struct Sweep {
    zmap: ZMap,
    radius_mm: f64,
    probe_radius_mm: f64,
    step_mm: f64,
    lag_mm: f64,
    /// (sin φ, cos φ) of the probed directions, φ from 0 to π.
    directions: Vec<(f64, f64)>,
    pending: VecDeque<Stamp>,
    travelled_mm: f64,
}

impl Sweep {
    /// The stock box on a grid of at most `spacing_mm`, cut by a tool of `tool_diameter_mm`.
    ///
    /// # Errors
    /// See [`ZMap::new`]; a tool diameter that is not > 0; a grid too coarse for the tool
    /// (spacing above D/4).
    pub fn new(
        stock: &StockBox,
        spacing_mm: f64,
        tool_diameter_mm: f64,
    ) -> Result<Self, CuttingError> {
        if !(tool_diameter_mm > 0.0 && tool_diameter_mm.is_finite()) {
            return Err(CuttingError::ToolDiameter {
                diameter_mm: tool_diameter_mm,
            });
        }
        if spacing_mm > 0.25 * tool_diameter_mm {
            return Err(CuttingError::CoarseGrid {
                spacing_mm,
                diameter_mm: tool_diameter_mm,
            });
        }
        let zmap = ZMap::new(stock, spacing_mm)?;
        let [gx, gy] = zmap.spacing_mm();
        let g = gx.max(gy);
        let radius_mm = 0.5 * tool_diameter_mm;
        // Half a cell diagonal, and a hair more, so the probed cell's centre is inside the disc.
        let probe_radius_mm = radius_mm - 0.5 * gx.hypot(gy) * (1.0 + 1e-9);
        // Probes one cell apart along the periphery at most half a cell apart.
        let n = ((PI * radius_mm / (0.5 * gx.min(gy))).ceil() as usize).max(32);
        let directions = (0..=n)
            .map(|k| (PI * k as f64 / n as f64).sin_cos())
            .collect();
        Ok(Self {
            zmap,
            radius_mm,
            probe_radius_mm,
            step_mm: 0.5 * gx.min(gy),
            lag_mm: 2.0 * (radius_mm * g).sqrt() + g,
            directions,
            pending: VecDeque::new(),
            travelled_mm: 0.0,
        })
    }

    /// Step between samples along a path (mm): half the smaller cell side.
    pub fn step_mm(&self) -> f64 {
        self.step_mm
    }

    /// Length of path whose removal is kept as exact discs (mm).
    pub fn lag_mm(&self) -> f64 {
        self.lag_mm
    }

    /// The tool's radius (mm).
    pub fn radius_mm(&self) -> f64 {
        self.radius_mm
    }

    /// The Z-map (the last [`Sweep::lag_mm`] of removal not yet written: see [`Sweep::finish`]).
    pub fn zmap(&self) -> &ZMap {
        &self.zmap
    }

    /// Writes every removal to the grid and returns it.
    pub fn finish(mut self) -> ZMap {
        while let Some(s) = self.pending.pop_front() {
            self.zmap.cut_disc(s.xy_mm, self.radius_mm, s.z_mm);
        }
        self.zmap
    }

    /// Cuts along `path`: the contact of every sample in material (samples at equal steps of at
    /// most [`Sweep::step_mm`], both ends included), removing each sample's disc after probing it.
    pub fn cut(&mut self, path: &impl ToolPath) -> Vec<Contact> {
        let length_mm = path.length_mm();
        let n = ((length_mm / self.step_mm).ceil() as usize).max(1);
        let ds = length_mm / n as f64;
        let mut contacts: Vec<Contact> = Vec::new();
        for k in 0..=n {
            let s_mm = ds * k as f64;
            let p = path.point_at(s_mm);
            if let Some(mut c) = self.contact(s_mm, p, path.tangent_at(s_mm)) {
                // A plunge sees only the chip of its last step over its tip: the depth in
                // material grows by the descent while it stays in contact.
                if let (ContactKind::Plunge, Some(prev)) = (c.kind, contacts.last()) {
                    if prev.kind == ContactKind::Plunge && prev.s_mm + 1.5 * ds >= s_mm {
                        let descent = prev.position_mm[2] - p[2];
                        c.axial_depth_mm = c.axial_depth_mm.max(prev.axial_depth_mm + descent);
                    }
                }
                contacts.push(c);
            }
            self.remove(p, if k == 0 { 0.0 } else { ds });
        }
        contacts
    }

    /// Removes the disc at `p` after `ds_mm` of path; writes removals older than the lag.
    fn remove(&mut self, p: [f64; 3], ds_mm: f64) {
        self.travelled_mm += ds_mm;
        self.pending.push_back(Stamp {
            xy_mm: [p[0], p[1]],
            z_mm: p[2],
            at_mm: self.travelled_mm,
        });
        while let Some(s) = self.pending.front() {
            if s.at_mm >= self.travelled_mm - self.lag_mm {
                break;
            }
            let s = *s;
            self.pending.pop_front();
            self.zmap.cut_disc(s.xy_mm, self.radius_mm, s.z_mm);
        }
    }

    /// Material height at a point: the grid's top at `probe`, lowered by every pending disc
    /// that contains `exact`; `None` where there is no material.
    fn height_at(&self, probe: [f64; 2], exact: [f64; 2]) -> Option<f64> {
        let mut top = self.zmap.top_at(probe[0], probe[1])?;
        let r2 = self.radius_mm * self.radius_mm * (1.0 - 1e-9);
        for s in &self.pending {
            let (dx, dy) = (exact[0] - s.xy_mm[0], exact[1] - s.xy_mm[1]);
            if dx * dx + dy * dy < r2 {
                top = top.min(s.z_mm);
            }
        }
        Some(top)
    }

    /// Depth of material above the tip `z_mm` at a height `top` (0 when none).
    fn depth(&self, top: Option<f64>, z_mm: f64) -> f64 {
        top.map_or(0.0, |t| t - z_mm.max(self.zmap.bottom_mm()))
    }

    fn contact(&self, s_mm: f64, p: [f64; 3], t: [f64; 3]) -> Option<Contact> {
        let t_xy = t[0].hypot(t[1]);
        // A NaN tangent (never from a valid path) is a plunge too.
        if t_xy.is_nan() || t_xy < PLUNGE_TANGENT {
            return self.plunge(s_mm, p);
        }
        let f = [t[0] / t_xy, t[1] / t_xy];
        let n = [-f[1], f[0]];
        let (r, rp) = (self.radius_mm, self.probe_radius_mm);
        let mut first = None;
        let mut last = 0;
        let mut depth_mm: f64 = 0.0;
        for (k, &(sin, cos)) in self.directions.iter().enumerate() {
            let u = [sin * f[0] + cos * n[0], sin * f[1] + cos * n[1]];
            let probe = [p[0] + rp * u[0], p[1] + rp * u[1]];
            let exact = [p[0] + r * u[0], p[1] + r * u[1]];
            let d = self.depth(self.height_at(probe, exact), p[2]);
            if d > MIN_DEPTH_MM {
                first.get_or_insert(k);
                last = k;
                depth_mm = depth_mm.max(d);
            }
        }
        let first = first?;
        let n_dirs = self.directions.len() - 1;
        let angle = |k: usize| PI * k as f64 / n_dirs as f64;
        let ratio = rp / r;
        let side = match (first == 0, last == n_dirs) {
            (true, true) => Side::Both,
            (true, false) => Side::Left,
            (false, true) => Side::Right,
            (false, false) => Side::Neither,
        };
        // Widened to the next probe out, then moved out to the periphery (never narrowed).
        let entry_rad = if first == 0 {
            0.0
        } else {
            let a = angle(first - 1);
            a.min((ratio * a.cos()).acos())
        };
        let exit_rad = if last == n_dirs {
            PI
        } else {
            let b = angle(last + 1);
            b.max((ratio * b.cos()).acos())
        };
        Some(Contact {
            s_mm,
            position_mm: p,
            axial_depth_mm: depth_mm,
            kind: ContactKind::Side(EngagedArc {
                feed_angle_rad: f[1].atan2(f[0]),
                entry_rad,
                exit_rad,
                side,
            }),
        })
    }

    /// Material over the tool's disc during a vertical motion.
    fn plunge(&self, s_mm: f64, p: [f64; 3]) -> Option<Contact> {
        let [gx, gy] = self.zmap.spacing_mm();
        let [nx, ny] = self.zmap.cells();
        let r = self.radius_mm;
        let span = |c: f64, lo: f64, g: f64, n: usize| {
            let a = ((c - r - lo) / g - 0.5).ceil().max(0.0) as usize;
            let b = ((c + r - lo) / g - 0.5).floor().min(n as f64 - 1.0);
            (a, b)
        };
        let origin = self.zmap.cell_centre_mm(0, 0);
        let (i0, i1) = span(p[0], origin[0] - 0.5 * gx, gx, nx);
        let (j0, j1) = span(p[1], origin[1] - 0.5 * gy, gy, ny);
        if i1 < 0.0 || j1 < 0.0 {
            return None;
        }
        let mut depth_mm: f64 = 0.0;
        for j in j0..=j1 as usize {
            for i in i0..=i1 as usize {
                let c = self.zmap.cell_centre_mm(i, j);
                if (c[0] - p[0]).hypot(c[1] - p[1]) > r {
                    continue;
                }
                depth_mm = depth_mm.max(self.depth(self.height_at(c, c), p[2]));
            }
        }
        (depth_mm > MIN_DEPTH_MM).then_some(Contact {
            s_mm,
            position_mm: p,
            axial_depth_mm: depth_mm,
            kind: ContactKind::Plunge,
        })
    }
}

#[cfg(test)]
mod tests;
