//! Critical depths for the chatter check: semi-discretisation at each (spindle speed, radial
//! immersion bin, milling direction, feed-direction bin), each computed once.
//!
//! - Immersion: a_e/D is rounded **up** to the next multiple of the bin width (default 0.025),
//!   so a cut is judged at the larger immersion of its bin: more teeth in the cut, the safe side.
//! - Feed direction: the tool file's modes are in the machine's X and Y. A tip with the same
//!   modes in X and Y is the same in every direction; otherwise the feed direction is rounded to
//!   the nearest [`DIRECTION_BIN_DEG`] (modulo 180°, where the model repeats) and the window is
//!   turned into the modes' frame (exact for moves along X or Y).
//! - Depth: the lowest unstable depth on (0, `max_depth_mm`] — a scan of [`SCAN_DEPTHS`] equal
//!   steps from the bottom (so an unstable island between stable depths is found if it is wider
//!   than a step), then ITP to [`RELATIVE_TOL`] of a step
//!   ([`MillingSdm::lowest_critical_depth_at`]) at the table's resolution (default the converged
//!   one of [`crate::dynamics::converged`]: steps per tooth period chosen per speed, the spectral
//!   radius extrapolated from two resolutions, within 1 % of a converged reference); the stable
//!   end of the last bracket is returned, the side that does not overstate the margin.

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::dynamics::milling::{MillingSdm, SdmOptions};
use crate::dynamics::{DynamicsError, Milling, Resolution};
use vmc_machine::milling::ToolDynamics;

/// Width of a feed-direction bin when the tip differs in X and Y (degrees).
pub const DIRECTION_BIN_DEG: f64 = 5.0;
/// Depths scanned from the bottom of the range before bisecting.
pub const SCAN_DEPTHS: usize = 16;
/// Width of the last bracket of the critical depth, relative to a scan step (0.5 % of the
/// depth wherever it is above a tenth of a step, i.e. at any margin above 1/40 of the
/// deepest cut's).
pub const RELATIVE_TOL: f64 = 0.0005;

/// One stability question: which SDM to build and at which speed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Key {
    /// Spindle speed (rpm), as its bits (speeds are compared exactly).
    rpm_bits: u64,
    /// Immersion bin: a_e/D evaluated = bin × width.
    immersion_bin: u32,
    /// Up (false) or down (true) milling.
    down: bool,
    /// Feed-direction bin (0 for a tip that is the same in X and Y).
    direction_bin: u32,
}

/// Critical depths of one tool, computed on demand and kept.
#[derive(Debug)]
pub struct StabilityTable<'a> {
    tool: &'a ToolDynamics,
    resolution: Resolution,
    bin_width: f64,
    max_depth_mm: f64,
    isotropic: bool,
    depths: HashMap<Key, Option<f64>>,
    evaluations: AtomicUsize,
}

impl<'a> StabilityTable<'a> {
    /// A table for `tool` at the semi-discretisation's `resolution`, immersion bins of
    /// `bin_width`, depths searched up to `max_depth_mm`.
    pub fn new(
        tool: &'a ToolDynamics,
        resolution: Resolution,
        bin_width: f64,
        max_depth_mm: f64,
    ) -> Self {
        Self {
            tool,
            resolution,
            bin_width,
            max_depth_mm,
            isotropic: tool.modes.x == tool.modes.y,
            depths: HashMap::new(),
            evaluations: AtomicUsize::new(0),
        }
    }

    /// The key of a cut: speed, a_e/D (rounded up to its bin), milling, feed angle (rad, from +X).
    pub fn key(
        &self,
        spindle_rpm: f64,
        immersion: f64,
        milling: Milling,
        feed_angle_rad: f64,
    ) -> Key {
        // A hair under the bin edge stays in its bin (0.15/0.025 is 6.000000000000001).
        let bins = (1.0 / self.bin_width).ceil() as u32;
        let immersion_bin = ((immersion / self.bin_width - 1e-9).ceil().max(1.0) as u32).min(bins);
        let direction_bin = if self.isotropic {
            0
        } else {
            let n = (180.0 / DIRECTION_BIN_DEG).round() as i64;
            ((feed_angle_rad.to_degrees() / DIRECTION_BIN_DEG).round() as i64).rem_euclid(n) as u32
        };
        Key {
            rpm_bits: spindle_rpm.to_bits(),
            immersion_bin,
            down: milling == Milling::Down,
            direction_bin,
        }
    }

    /// a_e/D at which a key is evaluated (the upper edge of its bin, at most 1).
    pub fn immersion_of(&self, key: Key) -> f64 {
        (f64::from(key.immersion_bin) * self.bin_width).min(1.0)
    }

    /// Computes the critical depths of the keys not yet known, in parallel (each key alone, so
    /// the result does not depend on the order or the number of threads).
    ///
    /// # Errors
    /// Values the dynamics refuses.
    pub fn fill(&mut self, keys: impl IntoIterator<Item = Key>) -> Result<(), DynamicsError> {
        let mut todo: Vec<Key> = keys
            .into_iter()
            .filter(|k| !self.depths.contains_key(k))
            .collect();
        todo.sort_unstable();
        todo.dedup();
        let this = &*self;
        let found: Vec<(Key, Option<f64>)> = todo
            .par_iter()
            .map(|&k| Ok((k, this.compute(k)?)))
            .collect::<Result<_, DynamicsError>>()?;
        self.depths.extend(found);
        Ok(())
    }

    /// The critical depth of a key computed by [`StabilityTable::fill`] (mm); `None` when no
    /// depth up to the search range is unstable, or the key was not filled.
    pub fn depth(&self, key: Key) -> Option<f64> {
        self.depths.get(&key).copied().flatten()
    }

    /// Width of an immersion bin in a_e/D.
    pub fn bin_width(&self) -> f64 {
        self.bin_width
    }

    /// Top of the searched depth range (mm).
    pub fn max_depth_mm(&self) -> f64 {
        self.max_depth_mm
    }

    /// Distinct stability questions answered so far.
    pub fn len(&self) -> usize {
        self.depths.len()
    }

    /// True when nothing was computed.
    pub fn is_empty(&self) -> bool {
        self.depths.is_empty()
    }

    /// Stability evaluations (monodromy + eigenvalues) done so far.
    pub fn evaluations(&self) -> usize {
        self.evaluations.load(Ordering::Relaxed)
    }

    fn compute(&self, key: Key) -> Result<Option<f64>, DynamicsError> {
        let t = self.tool;
        let milling = if key.down { Milling::Down } else { Milling::Up };
        let immersion = self.immersion_of(key);
        let angle_rad = (f64::from(key.direction_bin) * DIRECTION_BIN_DEG).to_radians();
        // The resolution chooses the steps per speed; the options' count is not used.
        let sdm = MillingSdm::with_feed_angle(
            &t.tool,
            &t.modes,
            immersion,
            milling,
            angle_rad,
            SdmOptions::default(),
        )?;
        let step_mm = self.max_depth_mm / SCAN_DEPTHS as f64;
        let tol_mm = RELATIVE_TOL * step_mm;
        let found = sdm.lowest_critical_depth_at(
            f64::from_bits(key.rpm_bits),
            (self.max_depth_mm, tol_mm),
            SCAN_DEPTHS,
            &self.resolution,
        )?;
        // The point is the middle of a last bracket at most tol_mm wide: its stable end is at
        // least half a tolerance below.
        let result = found.map(|p| p.critical_depth_mm - 0.5 * tol_mm);
        self.evaluations
            .fetch_add(sdm.evaluations(), Ordering::Relaxed);
        Ok(result)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::{lobes, Method};

    #[test]
    fn immersions_round_up_to_their_bin_and_directions_to_theirs() {
        let tool = ToolDynamics::benchmark();
        let t = StabilityTable::new(&tool, Resolution::default(), 0.025, 5.0);
        let k = |imm| t.immersion_of(t.key(10_000.0, imm, Milling::Down, 0.0));
        assert!((k(0.15) - 0.15).abs() < 1e-12);
        assert!((k(0.1501) - 0.175).abs() < 1e-12);
        assert!((k(0.001) - 0.025).abs() < 1e-12);
        assert!((k(1.0) - 1.0).abs() < 1e-12);
        // The benchmark tip is flexible in X only: the direction counts, modulo 180°.
        let d = |deg: f64| {
            t.key(10_000.0, 0.5, Milling::Up, deg.to_radians())
                .direction_bin
        };
        assert_eq!(d(0.0), d(180.0));
        assert_eq!(d(-90.0), d(90.0));
        assert_eq!(d(2.4), d(0.0));
        assert_ne!(d(2.6), d(0.0));
    }

    #[test]
    fn a_critical_depth_agrees_with_the_lobes_and_lies_on_the_stable_side() {
        let tool = ToolDynamics::benchmark();
        let mut t = StabilityTable::new(&tool, Resolution::default(), 0.025, 4.0);
        let key = t.key(10_000.0, 1.0, Milling::Down, 0.0);
        t.fill([key]).unwrap();
        let got = t.depth(key).unwrap();
        let want = lobes(
            Method::Sdm,
            &tool.tool,
            &tool.modes,
            1.0,
            Milling::Down,
            &[10_000.0],
        )
        .unwrap()[0]
            .critical_depth_mm;
        // Both search the same converged model: to 1e-3 of the ZOA minimum there, to
        // 2.5e-4 × 0.25 mm here, the table on the stable side of its bracket.
        let tol_mm = RELATIVE_TOL * 4.0 / SCAN_DEPTHS as f64;
        assert!(
            got <= want + 1e-3 * 0.3 && got > want * 0.995,
            "{got} vs {want}"
        );
        let sdm = MillingSdm::new(
            &tool.tool,
            &tool.modes,
            1.0,
            Milling::Down,
            SdmOptions::default(),
        )
        .unwrap();
        let rule = match Resolution::default() {
            Resolution::Converged(rule) => rule,
            Resolution::Fixed(_) => unreachable!("the default is converged"),
        };
        let period_s = tool.tool.tooth_period_s(10_000.0);
        let m = rule.coarse_steps(sdm.highest_frequency_hz(), sdm.cut_fraction(), period_s);
        let at = sdm.at_speed_extrapolated(10_000.0, m).unwrap();
        assert!(at.stability(got).unwrap().is_stable(), "{got}");
        assert!(!at.stability(got + tol_mm).unwrap().is_stable(), "{got}");
        assert_eq!(t.len(), 1);
        assert!(t.evaluations() > SCAN_DEPTHS / 4);
    }

    #[test]
    fn a_fixed_resolution_gives_the_fixed_step_depth() {
        let tool = ToolDynamics::benchmark();
        let mut fixed = StabilityTable::new(&tool, Resolution::Fixed(40), 0.025, 4.0);
        let mut conv = StabilityTable::new(&tool, Resolution::default(), 0.025, 4.0);
        // 5000 rpm slotting: 40 steps put the boundary 8 % deep (0.441 against 0.409 mm).
        let key = fixed.key(5000.0, 1.0, Milling::Down, 0.0);
        fixed.fill([key]).unwrap();
        conv.fill([key]).unwrap();
        let (f, c) = (fixed.depth(key).unwrap(), conv.depth(key).unwrap());
        assert!((f - 0.4411).abs() < 0.001, "{f}");
        assert!((c - 0.4086).abs() < 0.001, "{c}");
    }
}
