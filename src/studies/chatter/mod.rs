//! The chatter check of a milling program: which cutting moves will chatter.
//!
//! It joins three parts that do not know each other: the program's canonical moves
//! ([`vmc_gcode::interp`]), the material-removal model ([`vmc_machine::cutting`]: a Z-map of the stock,
//! the engagement of each sample of each move) and the stability of milling (the
//! semi-discretisation of [`crate::dynamics`], through [`stability`]).
//!
//! For every feed move (G1, G2, G3) in material, with the spindle on:
//! 1. each sample's engaged arc becomes a cut of the stability model. The rule, for a clockwise
//!    spindle (M3) and the tool's periphery seen along the motion: material on the right only
//!    is **down** milling (climb: a tooth leaves the material at zero chip thickness), on the
//!    left only **up** milling, on both sides a **slot** (a_e/D = 1). Material ahead only
//!    (entering a wall or a corner: **entry**) lies inside both the window from the left edge
//!    (up) and the one from the right edge (down); the narrower is judged, and both — the worse
//!    kept — when they are within an immersion bin of each other (head on). M4 mirrors left and
//!    right. a_e/D is that of the straight cut from the engaged edge to the end
//!    of the arc (see [`vmc_machine::cutting::engagement`]);
//! 2. the critical depth a_p,lim at the spindle speed and immersion comes from
//!    [`stability::StabilityTable`] (immersion rounded up to its bin, computed once per key);
//! 3. the margin a_p,lim / a_p of each sample; the move reports its worst sample, and its
//!    verdict: **unstable** below 1, **marginal** from 1 to [`ChatterOptions::marginal_below`]
//!    (default 1.25: the model's uncertainty — cutting coefficients and modes measured to a
//!    few %, a linear force law; the semi-discretisation itself is converged to within 1 %),
//!    **stable** above.
//!
//! Vertical moves in material are reported as **plunge**, not judged (the model is side
//! milling). Rapids are taken to be in air (`check` finds those that are not) and remove
//! nothing. The feed does not enter the linear stability model; it is reported.

pub mod stability;
pub mod stock_file;

use thiserror::Error;

use crate::dynamics::{DynamicsError, Milling, Resolution};
use stability::{Key, StabilityTable};
use vmc_gcode::interp::{CanonKind, CanonMove, SpindleDir};
use vmc_machine::cutting::{Contact, ContactKind, CuttingError, EngagedArc, Side, StockBox, Sweep};
use vmc_machine::milling::ToolDynamics;
use vmc_machine::motion::{ArcGeometry, Geometry};

/// Settings of the chatter check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChatterOptions {
    /// Z-map grid spacing (mm); `None` (the default): the tool's diameter / 32 (0.5 mm for a
    /// 16 mm cutter), which resolves a_e/D to about 0.03.
    pub grid_mm: Option<f64>,
    /// Width of an immersion bin in a_e/D (default 0.025); a cut is judged at its bin's top.
    pub immersion_bin: f64,
    /// Margin below which a stable cut is called marginal (default 1.25).
    pub marginal_below: f64,
    /// Resolution of the semi-discretisation (default converged: steps per tooth period chosen
    /// per speed and checked, [`Resolution::default`]).
    pub resolution: Resolution,
    /// Tool-tip position when the program starts (mm; default the origin).
    pub start_mm: [f64; 3],
}

impl Default for ChatterOptions {
    fn default() -> Self {
        Self {
            grid_mm: None,
            immersion_bin: 0.025,
            marginal_below: 1.25,
            resolution: Resolution::default(),
            start_mm: [0.0; 3],
        }
    }
}

/// Most samples of a check (about 12 km of cutting path at the default 0.25 mm step for a
/// 16 mm cutter, minutes of work).
pub const MAX_SAMPLES: usize = 50_000_000;

/// Grid spacing over tool diameter when none is given.
pub const DEFAULT_GRID_PER_DIAMETER: f64 = 1.0 / 32.0;

/// Why a program cannot be checked.
#[derive(Debug, Error)]
pub enum ChatterError {
    /// The stock or the grid.
    #[error(transparent)]
    Cutting(#[from] CuttingError),
    /// Values the stability model refuses.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// An option out of range.
    #[error("{name} must be {range}, got {value}")]
    Option {
        /// The option.
        name: &'static str,
        /// The accepted range.
        range: &'static str,
        /// The value given.
        value: f64,
    },
    /// The program has no G1, G2 or G3.
    #[error("the program has no cutting move (G1, G2 or G3)")]
    NoCuttingMoves,
    /// No feed move reaches the stock's material.
    #[error("the program never touches the stock: none of its {feed_moves} feed moves reaches the material of the box X{:.3} Y{:.3} Z{:.3} … X{:.3} Y{:.3} Z{:.3} mm", .stock.min_mm[0], .stock.min_mm[1], .stock.min_mm[2], .stock.max_mm[0], .stock.max_mm[1], .stock.max_mm[2])]
    StockUntouched {
        /// Feed moves in the program.
        feed_moves: usize,
        /// The stock box.
        stock: StockBox,
    },
    /// A feed move cuts while the spindle is stopped.
    #[error("line {line}: {motion} cuts the stock with the spindle stopped, at X{:.3} Y{:.3} Z{:.3}", .at_mm[0], .at_mm[1], .at_mm[2])]
    SpindleOff {
        /// Program line.
        line: usize,
        /// `G1`, `G2` or `G3`.
        motion: &'static str,
        /// First tool-tip position in material (mm).
        at_mm: [f64; 3],
    },
    /// The cutting path in reach of the stock needs too many samples.
    #[error("line {line}: the cutting path within reach of the stock needs more than {max} samples: use a larger grid spacing or a shorter program")]
    TooManySamples {
        /// Program line where the limit is passed.
        line: usize,
        /// The limit.
        max: usize,
    },
    /// An arc whose radius is degenerate.
    #[error("line {line}: {motion} has a degenerate radius")]
    DegenerateArc {
        /// Program line.
        line: usize,
        /// `G2` or `G3`.
        motion: &'static str,
    },
}

/// How a cut engages, as judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Engagement {
    /// Up (conventional) milling.
    Up,
    /// Down (climb) milling.
    Down,
    /// Full slot (a_e/D = 1).
    Slot,
    /// Material ahead only: the worse of up and down milling.
    Entry,
    /// Vertical motion into material: not judged.
    Plunge,
}

impl Engagement {
    /// `up`, `down`, `slot`, `entry` or `plunge`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Up => "up",
            Self::Down => "down",
            Self::Slot => "slot",
            Self::Entry => "entry",
            Self::Plunge => "plunge",
        }
    }
}

/// The verdict on a cutting move.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    /// Margin ≥ [`ChatterOptions::marginal_below`].
    Stable,
    /// Margin in [1, [`ChatterOptions::marginal_below`]).
    Marginal,
    /// Margin < 1: chatter.
    Unstable,
    /// A plunge: not judged.
    Plunge,
}

impl Verdict {
    /// `stable`, `marginal`, `unstable` or `plunge`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Stable => "stable",
            Self::Marginal => "marginal",
            Self::Unstable => "unstable",
            Self::Plunge => "plunge",
        }
    }
}

/// One cutting move, judged at its worst sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Cut {
    /// Program line (1-based).
    pub line: usize,
    /// `G1`, `G2` or `G3`.
    pub motion: &'static str,
    /// Spindle speed (rpm).
    pub spindle_rpm: f64,
    /// Programmed feed (mm/min).
    pub feed_mm_per_min: f64,
    /// Tool tip at the worst sample (mm).
    pub position_mm: [f64; 3],
    /// Measured radial immersion a_e/D at the worst sample (1 for a plunge).
    pub immersion: f64,
    /// How it engages.
    pub engagement: Engagement,
    /// Axial depth a_p at the worst sample (mm).
    pub axial_depth_mm: f64,
    /// Critical depth a_p,lim (mm); the top of the searched range when
    /// `critical_depth_is_bound`; `None` for a plunge.
    pub critical_depth_mm: Option<f64>,
    /// True when no instability was found up to the searched range: the depth is a lower bound.
    pub critical_depth_is_bound: bool,
    /// a_p,lim / a_p (a lower bound with `critical_depth_is_bound`); `None` for a plunge.
    pub margin: Option<f64>,
    /// The verdict.
    pub verdict: Verdict,
    /// Samples of the move in material.
    pub samples: usize,
}

/// The whole check.
#[derive(Debug, Clone, PartialEq)]
pub struct ChatterReport {
    /// Every feed move in material, in program order.
    pub cuts: Vec<Cut>,
    /// Feed moves (G1, G2, G3) in the program.
    pub feed_moves: usize,
    /// Z-map grid spacing along X and Y (mm) and cell counts.
    pub grid_mm: [f64; 2],
    /// Z-map cells along X and Y.
    pub cells: [usize; 2],
    /// Samples along the feed moves.
    pub samples: usize,
    /// Top of the critical-depth search (mm): 4 × the deepest cut.
    pub max_depth_mm: f64,
    /// Distinct (speed, immersion bin, milling, direction) stability questions.
    pub stability_keys: usize,
    /// Stability evaluations of the semi-discretisation.
    pub stability_evaluations: usize,
    /// Material removed by the feed moves (mm³).
    pub removed_mm3: f64,
}

impl ChatterReport {
    /// Cuts with this verdict.
    pub fn count(&self, verdict: Verdict) -> usize {
        self.cuts.iter().filter(|c| c.verdict == verdict).count()
    }
}

/// A feed move's path: the motion planner's geometry from its start.
struct MovePath {
    start_mm: [f64; 3],
    geometry: Geometry,
}

impl vmc_machine::cutting::ToolPath for MovePath {
    fn length_mm(&self) -> f64 {
        self.geometry.length_mm()
    }
    fn point_at(&self, s_mm: f64) -> [f64; 3] {
        self.geometry.point_at(self.start_mm, s_mm)
    }
    fn tangent_at(&self, s_mm: f64) -> [f64; 3] {
        self.geometry.tangent_at(s_mm)
    }
}

/// A feed move and its samples in material.
struct Engaged {
    line: usize,
    motion: &'static str,
    spindle_rpm: f64,
    ccw: bool,
    feed_mm_per_min: f64,
    contacts: Vec<Contact>,
}

/// Checks a program's moves against a stock box with a tool.
///
/// # Errors
/// See [`ChatterError`].
pub fn check(
    moves: &[CanonMove],
    stock: &StockBox,
    tool: &ToolDynamics,
    options: &ChatterOptions,
) -> Result<ChatterReport, ChatterError> {
    validate(options)?;
    let grid = options
        .grid_mm
        .unwrap_or(tool.tool.diameter_mm * DEFAULT_GRID_PER_DIAMETER);
    let mut sweep = Sweep::new(stock, grid, tool.tool.diameter_mm)?;
    let volume_mm3 = sweep.zmap().volume_mm3();
    let (engaged, feed_moves, samples) = engage(moves, options.start_mm, stock, &mut sweep)?;
    if feed_moves == 0 {
        return Err(ChatterError::NoCuttingMoves);
    }
    if engaged.is_empty() {
        return Err(ChatterError::StockUntouched {
            feed_moves,
            stock: *stock,
        });
    }
    let deepest_mm = engaged
        .iter()
        .flat_map(|e| &e.contacts)
        .map(|c| c.axial_depth_mm)
        .fold(0.0, f64::max);
    let mut table = StabilityTable::new(
        tool,
        options.resolution,
        options.immersion_bin,
        4.0 * deepest_mm,
    );
    let keys: Vec<Key> = engaged
        .iter()
        .flat_map(|e| e.contacts.iter().map(move |c| (e, c)))
        .flat_map(|(e, c)| candidates(&table, e, c).into_iter().map(|(k, ..)| k))
        .collect();
    table.fill(keys)?;
    let cuts = engaged
        .iter()
        .map(|e| judge(&table, e, options.marginal_below))
        .collect();
    let (grid_mm, cells) = (sweep.zmap().spacing_mm(), sweep.zmap().cells());
    let removed_mm3 = volume_mm3 - sweep.finish().volume_mm3();
    Ok(ChatterReport {
        cuts,
        feed_moves,
        grid_mm,
        cells,
        samples,
        max_depth_mm: table.max_depth_mm(),
        stability_keys: table.len(),
        stability_evaluations: table.evaluations(),
        removed_mm3,
    })
}

fn validate(o: &ChatterOptions) -> Result<(), ChatterError> {
    let bad = |name, range, value| Err(ChatterError::Option { name, range, value });
    // A bin's top is the immersion its cuts are judged at: the smallest bin is the smallest
    // immersion the lobes accept.
    if !(crate::dynamics::params::MIN_IMMERSION..=1.0).contains(&o.immersion_bin) {
        return bad("the immersion bin", "in [0.01, 1]", o.immersion_bin);
    }
    if !(o.marginal_below >= 1.0 && o.marginal_below.is_finite()) {
        return bad("the marginal threshold", ">= 1", o.marginal_below);
    }
    if let Some(g) = o.grid_mm {
        if !(g > 0.0 && g.is_finite()) {
            return Err(CuttingError::Spacing { spacing_mm: g }.into());
        }
    }
    Ok(())
}

/// Runs the moves through the Z-map: the feed moves in material, the count of feed moves and
/// of samples.
fn engage(
    moves: &[CanonMove],
    start_mm: [f64; 3],
    stock: &StockBox,
    sweep: &mut Sweep,
) -> Result<(Vec<Engaged>, usize, usize), ChatterError> {
    // Where the tool tip can meet material: the box grown by the radius in X and Y, anywhere
    // below its top (the flutes are as long as needed).
    let r = sweep.radius_mm();
    let reach_lo = [stock.min_mm[0] - r, stock.min_mm[1] - r, f64::NEG_INFINITY];
    let reach_hi = [stock.max_mm[0] + r, stock.max_mm[1] + r, stock.max_mm[2]];
    let mut at = start_mm;
    let (mut rpm, mut dir) = (0.0, SpindleDir::Off);
    let (mut out, mut feed_moves, mut samples) = (Vec::new(), 0, 0);
    for m in moves {
        let (end_mm, geometry, motion, feed) = match &m.kind {
            CanonKind::Traverse { end_mm, .. } => {
                at = *end_mm;
                continue;
            }
            CanonKind::Spindle { dir: d, rpm: r } => {
                (dir, rpm) = (*d, *r);
                continue;
            }
            CanonKind::Feed {
                end_mm,
                feed_mm_per_min,
                ..
            } => (*end_mm, Geometry::line(at, *end_mm), "G1", *feed_mm_per_min),
            CanonKind::Arc {
                end_mm,
                center_mm,
                plane,
                clockwise,
                extra_turns,
                feed_mm_per_min,
                ..
            } => {
                let motion = if *clockwise { "G2" } else { "G3" };
                let arc =
                    ArcGeometry::new(at, *end_mm, *center_mm, *plane, *clockwise, *extra_turns)
                        .ok_or(ChatterError::DegenerateArc {
                            line: m.line,
                            motion,
                        })?;
                (*end_mm, Geometry::Arc(arc), motion, *feed_mm_per_min)
            }
            _ => continue,
        };
        feed_moves += 1;
        let start_mm = at;
        at = end_mm;
        // Only the part of the move within reach of the material is sampled.
        let path = match geometry {
            Geometry::Arc(arc) => {
                let (lo, hi) = arc.bounds_mm();
                let meets = (0..3).all(|k| lo[k] <= reach_hi[k] && hi[k] >= reach_lo[k]);
                meets.then_some(MovePath { start_mm, geometry })
            }
            _ => clip_line(start_mm, end_mm, reach_lo, reach_hi).map(|(a, b)| MovePath {
                start_mm: a,
                geometry: Geometry::line(a, b),
            }),
        };
        let Some(path) = path.filter(|p| p.geometry.length_mm() > 0.0) else {
            continue;
        };
        samples += ((path.geometry.length_mm() / sweep.step_mm()).ceil() as usize).max(1) + 1;
        if samples > MAX_SAMPLES {
            return Err(ChatterError::TooManySamples {
                line: m.line,
                max: MAX_SAMPLES,
            });
        }
        let contacts = sweep.cut(&path);
        let Some(first) = contacts.first() else {
            continue;
        };
        if dir == SpindleDir::Off || rpm <= 0.0 {
            return Err(ChatterError::SpindleOff {
                line: m.line,
                motion,
                at_mm: first.position_mm,
            });
        }
        out.push(Engaged {
            line: m.line,
            motion,
            spindle_rpm: rpm,
            ccw: dir == SpindleDir::Ccw,
            feed_mm_per_min: feed,
            contacts,
        });
    }
    Ok((out, feed_moves, samples))
}

/// The part of the segment a → b inside the box [lo, hi] (slab method), if any.
fn clip_line(a: [f64; 3], b: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> Option<([f64; 3], [f64; 3])> {
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for k in 0..3 {
        let d = b[k] - a[k];
        if d == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (u, v) = ((lo[k] - a[k]) / d, (hi[k] - a[k]) / d);
        t0 = t0.max(u.min(v));
        t1 = t1.min(u.max(v));
    }
    let at = |t: f64| [0, 1, 2].map(|k| a[k] + t * (b[k] - a[k]));
    (t0 <= t1).then(|| (at(t0), at(t1)))
}

/// The stability questions of a sample: (key, measured a_e/D, engagement); none for a plunge.
fn candidates(table: &StabilityTable<'_>, e: &Engaged, c: &Contact) -> Vec<(Key, f64, Engagement)> {
    let ContactKind::Side(arc) = c.kind else {
        return Vec::new();
    };
    let EngagedArc { side, .. } = arc;
    let (left, right) = (arc.immersion_from_left(), arc.immersion_from_right());
    // A counter-clockwise spindle is the mirror image (about the feed line) of a clockwise
    // one: left and right swap and the feed angle changes sign; the X/Y modes are unchanged.
    let (angle, left_is_up) = if e.ccw {
        (-arc.feed_angle_rad, false)
    } else {
        (arc.feed_angle_rad, true)
    };
    let (left_milling, right_milling) = if left_is_up {
        (Milling::Up, Milling::Down)
    } else {
        (Milling::Down, Milling::Up)
    };
    let key = |imm, milling| table.key(e.spindle_rpm, imm, milling, angle);
    let as_engagement = |m| match m {
        Milling::Up => Engagement::Up,
        Milling::Down => Engagement::Down,
    };
    match side {
        Side::Both => vec![(key(1.0, Milling::Down), 1.0, Engagement::Slot)],
        Side::Left => vec![(key(left, left_milling), left, as_engagement(left_milling))],
        Side::Right => vec![(
            key(right, right_milling),
            right,
            as_engagement(right_milling),
        )],
        // Material ahead only: the arc lies inside both the window from the left edge and the
        // one from the right edge, and the narrower covers it more tightly; when they are
        // within a bin of each other (head on), both are judged and the worse kept.
        Side::Neither if right - left > table.bin_width() => {
            vec![(key(left, left_milling), left, Engagement::Entry)]
        }
        Side::Neither if left - right > table.bin_width() => {
            vec![(key(right, right_milling), right, Engagement::Entry)]
        }
        Side::Neither => vec![
            (key(left, left_milling), left, Engagement::Entry),
            (key(right, right_milling), right, Engagement::Entry),
        ],
    }
}

/// The verdict on one move: its sample of smallest margin.
fn judge(table: &StabilityTable<'_>, e: &Engaged, marginal_below: f64) -> Cut {
    let mut worst: Option<(f64, &Contact, f64, Engagement, Option<f64>)> = None;
    for c in &e.contacts {
        for (key, immersion, engagement) in candidates(table, e, c) {
            let depth = table.depth(key);
            let limit = depth.unwrap_or(table.max_depth_mm());
            let margin = limit / c.axial_depth_mm;
            if worst.as_ref().is_none_or(|w| margin < w.0) {
                worst = Some((margin, c, immersion, engagement, depth));
            }
        }
    }
    let base = Cut {
        line: e.line,
        motion: e.motion,
        spindle_rpm: e.spindle_rpm,
        feed_mm_per_min: e.feed_mm_per_min,
        position_mm: e.contacts[0].position_mm,
        immersion: 1.0,
        engagement: Engagement::Plunge,
        axial_depth_mm: 0.0,
        critical_depth_mm: None,
        critical_depth_is_bound: false,
        margin: None,
        verdict: Verdict::Plunge,
        samples: e.contacts.len(),
    };
    let Some((margin, c, immersion, engagement, depth)) = worst else {
        let deepest = e
            .contacts
            .iter()
            .max_by(|a, b| a.axial_depth_mm.total_cmp(&b.axial_depth_mm))
            .unwrap_or(&e.contacts[0]);
        return Cut {
            position_mm: deepest.position_mm,
            axial_depth_mm: deepest.axial_depth_mm,
            ..base
        };
    };
    let verdict = if margin < 1.0 {
        Verdict::Unstable
    } else if margin < marginal_below {
        Verdict::Marginal
    } else {
        Verdict::Stable
    };
    Cut {
        position_mm: c.position_mm,
        immersion,
        engagement,
        axial_depth_mm: c.axial_depth_mm,
        critical_depth_mm: Some(depth.unwrap_or(table.max_depth_mm())),
        critical_depth_is_bound: depth.is_none(),
        margin: Some(margin),
        verdict,
        ..base
    }
}

/// The report as CSV, one row per cutting move.
pub fn report_csv(report: &ChatterReport) -> String {
    use std::fmt::Write as _;
    let mut s = String::from(
        "line,move,spindle_rpm,feed_mm_per_min,immersion_ae_over_d,milling,axial_depth_mm,critical_depth_mm,critical_depth_is_lower_bound,margin,verdict,x_mm,y_mm,z_mm\n",
    );
    let opt = |v: Option<f64>| v.map(|v| format!("{v:.4}")).unwrap_or_default();
    for c in &report.cuts {
        let _ = writeln!(
            s,
            "{},{},{},{},{:.4},{},{:.4},{},{},{},{},{:.4},{:.4},{:.4}",
            c.line,
            c.motion,
            c.spindle_rpm,
            c.feed_mm_per_min,
            c.immersion,
            c.engagement.name(),
            c.axial_depth_mm,
            opt(c.critical_depth_mm),
            c.critical_depth_is_bound,
            opt(c.margin),
            c.verdict.name(),
            c.position_mm[0],
            c.position_mm[1],
            c.position_mm[2]
        );
    }
    s
}

#[cfg(test)]
mod tests;
