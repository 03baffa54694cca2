//! Semi-discretisation at a resolution chosen for accuracy: converged critical depths.
//!
//! The first-order semi-discretisation with m steps per tooth period τ errs in the critical
//! depth by about C·(c/m)², c = f·τ the vibration cycles per tooth period (C ≈ 4 on the
//! Insperger–Stépán benchmark, slotting and a_e/D = 0.05 alike): a fixed m is too coarse at
//! low speed, where a tooth period holds many vibration cycles (m = 40 at 5000 rpm: 8 % deep,
//! on the unsafe side), and wasteful at high speed.
//!
//! [`StepRule`] picks m per speed and checks it:
//! 1. a coarse resolution m₁ = max(`min_steps`, ⌈`steps_per_cycle`·f_max·τ⌉,
//!    ⌈`steps_per_cut`/w⌉), with f_max the highest retained natural frequency and w the
//!    fraction of the tooth period in which a tooth cuts (at small radial immersion the cut is
//!    short and its stiffness a_p·H/m raises the frequency inside it), and m₂ = 2m₁;
//! 2. every stability evaluation computes the spectral radius at m₁ and m₂ and extrapolates
//!    it (Richardson, the O(m⁻²) error): ρ = ρ₂ + (ρ₂ − ρ₁)/3 (see
//!    [`MillingSdm::at_speed_extrapolated`]); the boundary tracer's search (islands probed,
//!    bracket walked, ITP) runs on that ρ, so the critical depth is the root of the
//!    extrapolated radius, and an unstable band that only the converged model has (the
//!    tip of a lobe barely over 1) is seen at the coarse resolutions already;
//! 3. check: at the boundary found, |ρ₂ − ρ₁| must be at most `max_radius_change`, i.e. the
//!    two resolutions lie in the asymptotic range where the extrapolation holds; otherwise m
//!    doubles and the search repeats from the depth found, up to `max_steps` (a point at
//!    `max_steps` is returned although its check failed: a cap trades the check for time, e.g.
//!    for a structure whose highest retained mode is fast and stiff).
//!
//! Kind and chatter frequency are those of m₂, which [`LobePoint::steps_per_period`]
//! reports. [`Resolution::Fixed`] keeps the plain semi-discretisation at one m (the tracer of
//! [`MillingSdm::trace_block`]).
//!
//! The accuracy is pinned by `tests/converged.rs` against a converged reference computed by
//! an independent implementation (`tests/data/sdm_reference.py`); the figures and what was
//! tried are in the decision record on converged lobes.

use std::ops::Range;

use crate::milling::MillingSdm;
use crate::params::{positive, DynamicsError};
use crate::sdm::LobePoint;

/// How [`StepRule`] chooses and checks the steps per tooth period (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRule {
    /// Steps per vibration cycle of the highest retained mode at the coarse level (default 12;
    /// the fine level has twice as many).
    pub steps_per_cycle: f64,
    /// Steps per cut (the part of the tooth period a tooth is engaged) at the coarse level
    /// (default 8).
    pub steps_per_cut: f64,
    /// Fewest steps per tooth period at the coarse level (default 20; at least 4).
    pub min_steps: usize,
    /// Most steps per tooth period of any level (default 2560).
    pub max_steps: usize,
    /// Largest change of the spectral radius at the boundary between the two resolutions for
    /// which the extrapolated boundary is accepted (default 0.05); above it m doubles.
    pub max_radius_change: f64,
}

impl Default for StepRule {
    fn default() -> Self {
        Self {
            steps_per_cycle: 12.0,
            steps_per_cut: 8.0,
            min_steps: 20,
            max_steps: 2560,
            max_radius_change: 0.05,
        }
    }
}

impl StepRule {
    /// Checks the counts and that the ratios are positive and finite.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        positive("steps_per_cycle", self.steps_per_cycle)?;
        positive("steps_per_cut", self.steps_per_cut)?;
        positive("max_radius_change", self.max_radius_change)?;
        if self.min_steps < 4 {
            return Err(DynamicsError::TooFewSteps {
                name: "min_steps",
                min: 4,
                value: self.min_steps,
            });
        }
        if self.max_steps < 2 * self.min_steps {
            return Err(DynamicsError::TooFewSteps {
                name: "max_steps",
                min: 2 * self.min_steps,
                value: self.max_steps,
            });
        }
        Ok(())
    }

    /// The coarse level's steps per tooth period for a highest frequency `highest_hz`, a cut
    /// fraction `cut_fraction` of the period and a tooth period `period_s`, at most half of
    /// `max_steps`.
    pub fn coarse_steps(&self, highest_hz: f64, cut_fraction: f64, period_s: f64) -> usize {
        let cycles = highest_hz * period_s;
        let by_cycle = (self.steps_per_cycle * cycles).ceil();
        let by_cut = (self.steps_per_cut / cut_fraction.max(1e-9)).ceil();
        // The float maximum saturates on conversion, so a huge count only meets the cap.
        let m = by_cycle.max(by_cut).min(self.max_steps as f64) as usize;
        m.max(self.min_steps).min(self.max_steps / 2)
    }
}

/// Resolution of the semi-discretisation behind a lobe diagram.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Resolution {
    /// The same steps per tooth period at every speed, no check.
    Fixed(usize),
    /// Steps chosen per speed and checked by [`StepRule`].
    Converged(StepRule),
}

impl Default for Resolution {
    /// [`Resolution::Converged`] with the default rule.
    fn default() -> Self {
        Self::Converged(StepRule::default())
    }
}

impl From<usize> for Resolution {
    /// [`Resolution::Fixed`].
    fn from(steps_per_period: usize) -> Self {
        Self::Fixed(steps_per_period)
    }
}

impl Resolution {
    /// Checks the fixed count (at least 4) or the rule.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        match self {
            Self::Fixed(m) if *m < 4 => Err(DynamicsError::TooFewSteps {
                name: "steps_per_period",
                min: 4,
                value: *m,
            }),
            Self::Fixed(_) => Ok(()),
            Self::Converged(rule) => rule.validate(),
        }
    }
}

impl MillingSdm {
    /// The critical depth at one speed at the resolution `resolution`, searched from `guess_mm`
    /// (see [`SpeedSdm::critical_depth`]) in (0, `max_depth_mm`] to `tol_mm`.
    pub fn critical_depth_at(
        &self,
        spindle_rpm: f64,
        guess_mm: Option<f64>,
        (max_depth_mm, tol_mm): (f64, f64),
        resolution: &Resolution,
    ) -> Result<Option<LobePoint>, DynamicsError> {
        let rule = match resolution {
            Resolution::Fixed(m) => {
                return self.at_speed_with_steps(spindle_rpm, *m)?.critical_depth(
                    guess_mm,
                    max_depth_mm,
                    tol_mm,
                )
            }
            Resolution::Converged(rule) => rule,
        };
        let period_s = self.tool().tooth_period_s(spindle_rpm);
        let mut m = rule.coarse_steps(self.highest_frequency_hz(), self.cut_fraction(), period_s);
        let mut guess = guess_mm;
        loop {
            let s = self.at_speed_extrapolated(spindle_rpm, m)?;
            let Some(p) = s.critical_depth(guess, max_depth_mm, tol_mm)? else {
                return Ok(None);
            };
            // The two resolutions' spectral radii at the boundary: Richardson's correction is a
            // third of their difference.
            let change = 3.0 * s.stability(p.critical_depth_mm)?.extrapolation.abs();
            if change <= rule.max_radius_change || 4 * m > rule.max_steps {
                return Ok(Some(p));
            }
            (m, guess) = (2 * m, Some(p.critical_depth_mm));
        }
    }

    /// The lowest critical depth at one speed (see [`SpeedSdm::lowest_critical_depth`]: an even
    /// scan of `scan` depths over (0, `max_depth_mm`], then ITP to `tol_mm`) at the resolution
    /// `resolution`; with [`Resolution::Converged`] on the extrapolated spectral radius, the
    /// scan repeated at doubled steps while the check fails.
    ///
    /// [`SpeedSdm::lowest_critical_depth`]: crate::milling::SpeedSdm::lowest_critical_depth
    pub fn lowest_critical_depth_at(
        &self,
        spindle_rpm: f64,
        (max_depth_mm, tol_mm): (f64, f64),
        scan: usize,
        resolution: &Resolution,
    ) -> Result<Option<LobePoint>, DynamicsError> {
        resolution.validate()?;
        let rule = match resolution {
            Resolution::Fixed(m) => {
                return self
                    .at_speed_with_steps(spindle_rpm, *m)?
                    .lowest_critical_depth(max_depth_mm, scan, tol_mm)
            }
            Resolution::Converged(rule) => rule,
        };
        let period_s = self.tool().tooth_period_s(spindle_rpm);
        let mut m = rule.coarse_steps(self.highest_frequency_hz(), self.cut_fraction(), period_s);
        loop {
            let s = self.at_speed_extrapolated(spindle_rpm, m)?;
            let Some(p) = s.lowest_critical_depth(max_depth_mm, scan, tol_mm)? else {
                return Ok(None);
            };
            let change = 3.0 * s.stability(p.critical_depth_mm)?.extrapolation.abs();
            if change <= rule.max_radius_change || 4 * m > rule.max_steps {
                return Ok(Some(p));
            }
            m *= 2;
        }
    }

    /// [`MillingSdm::trace_block`] at the resolution `resolution`: the same runs of
    /// [`crate::milling::TRACE_RUN`] speeds, each speed's depth from
    /// [`MillingSdm::critical_depth_at`], so any split of the list gives the same bits.
    ///
    /// # Errors
    /// A block beyond the list, a bad speed, depth range, tolerance or resolution.
    pub fn trace_block_at(
        &self,
        speeds_rpm: &[f64],
        block: Range<usize>,
        start_mm: Option<f64>,
        (max_depth_mm, tol_mm): (f64, f64),
        resolution: &Resolution,
    ) -> Result<Vec<Option<LobePoint>>, DynamicsError> {
        positive("max_depth_mm", max_depth_mm)?;
        positive("tol_mm", tol_mm)?;
        if let Some(g) = start_mm {
            positive("start_mm", g)?;
        }
        resolution.validate()?;
        let range = (max_depth_mm, tol_mm);
        self.trace_runs(speeds_rpm, block, start_mm, |n, guess| {
            self.critical_depth_at(n, guess, range, resolution)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_coarse_steps_follow_the_cycles_and_the_cut_within_the_bounds() {
        let rule = StepRule::default();
        // 922 Hz at 2000 rpm with 2 teeth: τ = 15 ms, 13.83 cycles → 12 × 13.83 = 165.96 → 166.
        assert_eq!(rule.coarse_steps(922.0, 1.0, 0.015), 166);
        // A short cut (a_e/D = 0.05 down: w = 0.1436) needs 8 / 0.1436 = 55.7 → 56 steps.
        assert_eq!(rule.coarse_steps(922.0, 0.1436, 0.001), 56);
        // Few cycles and a full cut: the minimum.
        assert_eq!(rule.coarse_steps(922.0, 1.0, 0.001), 20);
        // Absurd inputs meet the cap (half the most steps, so the fine level fits).
        assert_eq!(rule.coarse_steps(1e12, 1.0, 1.0), 1280);
        assert_eq!(rule.coarse_steps(922.0, 0.0, 0.001), 1280);
    }

    #[test]
    fn bad_rules_are_refused_with_the_field_named() {
        let rule = StepRule {
            min_steps: 3,
            ..StepRule::default()
        };
        assert_eq!(
            rule.validate().unwrap_err().to_string(),
            "min_steps must be >= 4, got 3"
        );
        let rule = StepRule {
            max_radius_change: f64::NAN,
            ..StepRule::default()
        };
        assert_eq!(
            rule.validate().unwrap_err().to_string(),
            "max_radius_change is not finite"
        );
        let rule = StepRule {
            max_steps: 30,
            ..StepRule::default()
        };
        assert_eq!(
            rule.validate().unwrap_err().to_string(),
            "max_steps must be >= 40, got 30"
        );
        assert!(Resolution::Fixed(3).validate().is_err());
        assert_eq!(Resolution::from(160), Resolution::Fixed(160));
    }
}
