//! The touch probe of a three-axis machine: a stylus in the spindle that trips on contact with an
//! artefact on the table (a gauge block, a reference sphere) and latches the axis positions.
//!
//! **Model.** The probe is a tool of length `stylus_length_mm` (gauge line to ball centre) ending
//! in a ball of radius `ball_radius_mm`. A touch moves one axis in one direction from a start
//! axis position `q₀` at the probing feed. The ball's real centre at axis command `q` is
//! `q + E(q)`: the twin's whole error chain (kinematics × errors at the present temperatures,
//! the stylus as tool, the axis's reversal and one non-repeatability draw for the approach) —
//! the warm, drifted machine, not the nominal one. Contact is where the real ball first meets the
//! real artefact (found by bisection along the move, to 1e-7 mm). The kinematic trigger then
//! needs the stylus deflected by the **pre-travel** `trigger_force_n / stylus_stiffness_n_per_um`
//! before it trips; the trip scatters by the **repeatability** (Gaussian along the approach,
//! σ = `repeatability_2sigma_um / 2`, seeded); and the controller sees the trip signal at its
//! next servo tick, so the **latency** adds a travel uniform in `[0, feed · servo_period)`. The
//! latched axis position — what `#5061…#5063` receive, in machine coordinates here — is the
//! axis command at that instant.
//!
//! Pre-travel and the mean latency are constant for one probe, feed and direction: a controller
//! removes them by qualifying the probe on an artefact (they cancel in a difference against a
//! reference touch). Only the scatter remains: repeatability and the latency's spread.
//!
//! [`ProbeOnTwin::straight_move`] (module `straight`) answers a program's straight probe move
//! (G38.2 … G38.5) along any direction against the solids of a setup.
//!
//! Units: mm, µm where the name says so, N, s.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use thiserror::Error;

use crate::twin::Twin;

/// A touch probe's stylus, trigger and latch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TouchProbe {
    /// Gauge line to ball centre, mm (the stylus as a tool of this length).
    pub stylus_length_mm: f64,
    /// Stylus ball radius, mm.
    pub ball_radius_mm: f64,
    /// Force at which the kinematic seat trips, N.
    pub trigger_force_n: f64,
    /// Stylus bending stiffness at the ball, N/µm (with the trigger force: the pre-travel).
    pub stylus_stiffness_n_per_um: f64,
    /// Unidirectional repeatability, 2σ, µm (a probe's data-sheet figure).
    pub repeatability_2sigma_um: f64,
    /// The controller's servo period, s (the trip is latched at the next tick).
    pub servo_period_s: f64,
    /// Feed of the touching move, mm/min.
    pub feed_mm_per_min: f64,
}

impl TouchProbe {
    /// A typical spindle probe (kinematic trigger, 6 mm ball, 1 µm 2σ, 1 kHz servo, 50 mm/min
    /// touch) with a stylus of length `stylus_length_mm`.
    pub fn typical(stylus_length_mm: f64) -> Self {
        TouchProbe {
            stylus_length_mm,
            ball_radius_mm: 3.0,
            trigger_force_n: 0.75,
            stylus_stiffness_n_per_um: 0.25,
            repeatability_2sigma_um: 1.0,
            servo_period_s: 0.001,
            feed_mm_per_min: 50.0,
        }
    }

    /// Deflection of the stylus at the trip, mm.
    pub fn pretravel_mm(&self) -> f64 {
        self.trigger_force_n / self.stylus_stiffness_n_per_um * 1e-3
    }

    /// Largest travel past the trip before the controller latches it, mm.
    pub fn latency_travel_mm(&self) -> f64 {
        self.feed_mm_per_min / 60.0 * self.servo_period_s
    }

    /// σ of one touch's latched position, mm: repeatability and the latency's spread
    /// (uniform over one servo tick).
    pub fn sigma_mm(&self) -> f64 {
        let rep = 0.5 * self.repeatability_2sigma_um * 1e-3;
        let lat = self.latency_travel_mm() / 12f64.sqrt();
        (rep * rep + lat * lat).sqrt()
    }

    fn check(&self) -> Result<(), ProbeError> {
        let fields = [
            ("stylus_length_mm", self.stylus_length_mm, true),
            ("ball_radius_mm", self.ball_radius_mm, false),
            ("trigger_force_n", self.trigger_force_n, true),
            (
                "stylus_stiffness_n_per_um",
                self.stylus_stiffness_n_per_um,
                false,
            ),
            (
                "repeatability_2sigma_um",
                self.repeatability_2sigma_um,
                true,
            ),
            ("servo_period_s", self.servo_period_s, true),
            ("feed_mm_per_min", self.feed_mm_per_min, false),
        ];
        for (field, value, zero_ok) in fields {
            let ok = value.is_finite() && (value > 0.0 || (zero_ok && value == 0.0));
            if !ok {
                return Err(ProbeError::Setting { field, value });
            }
        }
        Ok(())
    }
}

/// Something on the table a probe touches, in workpiece coordinates (mm). It moves with the
/// table: its coordinates are fixed in the workpiece frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Artefact {
    /// A gauge block (or any flat top): its top face at `top_mm[2]`, centred at
    /// `top_mm[0..2]`, `half_width_mm` each way in X and Y.
    GaugeBlock {
        /// Centre of the top face, mm.
        top_mm: [f64; 3],
        /// Half the face's width in X and Y, mm.
        half_width_mm: f64,
    },
    /// A reference sphere.
    Sphere {
        /// Centre, mm.
        centre_mm: [f64; 3],
        /// Radius, mm.
        radius_mm: f64,
    },
}

impl Artefact {
    /// Gap between the ball (radius `r_mm`, centre `c_mm`) and the artefact, mm: > 0 apart,
    /// < 0 overlapping.
    fn gap_mm(&self, c_mm: [f64; 3], r_mm: f64) -> f64 {
        match *self {
            Artefact::GaugeBlock {
                top_mm,
                half_width_mm,
            } => {
                let inside = (0..2).all(|a| (c_mm[a] - top_mm[a]).abs() <= half_width_mm);
                if inside {
                    c_mm[2] - r_mm - top_mm[2]
                } else {
                    f64::INFINITY
                }
            }
            Artefact::Sphere {
                centre_mm,
                radius_mm,
            } => {
                let d2: f64 = (0..3).map(|a| (c_mm[a] - centre_mm[a]).powi(2)).sum();
                d2.sqrt() - radius_mm - r_mm
            }
        }
    }
}

/// One touching move: from axis position `start_mm`, axis `axis` (0 X, 1 Y, 2 Z) moving in
/// direction `sign` (±1) for at most `max_travel_mm`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touch {
    /// Axis command at the start, mm.
    pub start_mm: [f64; 3],
    /// Moving axis.
    pub axis: usize,
    /// +1 or −1.
    pub sign: f64,
    /// Longest travel, mm.
    pub max_travel_mm: f64,
}

/// A trip: the axis position the controller latched, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trip {
    /// Latched axis command, mm (machine coordinates of the probe's ball centre as the
    /// controller knows it).
    pub axis_mm: [f64; 3],
    /// Travel from the start to the latch, mm.
    pub travel_mm: f64,
}

/// A probe setting or move that cannot be simulated.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
pub enum ProbeError {
    /// A probe setting that is not a usable number.
    #[error("probe setting {field} = {value} is not a usable value")]
    Setting {
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// A touch without a usable axis, direction or travel.
    #[error("touch: axis {axis} (0..=2), sign {sign} (±1), travel {max_travel_mm} mm (> 0)")]
    Touch {
        /// Axis.
        axis: usize,
        /// Direction.
        sign: f64,
        /// Travel, mm.
        max_travel_mm: f64,
    },
    /// The ball already touches the artefact at the start.
    #[error("the probe already touches the artefact at the start of the move")]
    AlreadyTripped,
}

/// A touch probe in the spindle of a twin, with its own noise stream.
pub struct ProbeOnTwin {
    probe: TouchProbe,
    rng: StdRng,
}

impl ProbeOnTwin {
    /// `probe`, its trip scatter drawn from `seed`.
    ///
    /// # Errors
    /// [`ProbeError::Setting`] for a setting that is not a usable number.
    pub fn new(probe: TouchProbe, seed: u64) -> Result<Self, ProbeError> {
        probe.check()?;
        Ok(ProbeOnTwin {
            probe,
            rng: StdRng::seed_from_u64(seed ^ 0x7a0c_e9b0_be00_0001),
        })
    }

    /// The probe.
    pub fn probe(&self) -> &TouchProbe {
        &self.probe
    }

    /// Runs `touch` on `twin` against `artefact` at the twin's present temperatures: the
    /// latched trip, or `None` when the ball meets nothing within the travel. The twin's tool
    /// is the stylus during the touch and is restored after it; the axis's direction of motion
    /// is the touch's from then on.
    ///
    /// # Errors
    /// A bad touch, or a ball already in contact at the start.
    pub fn touch(
        &mut self,
        twin: &mut Twin,
        artefact: &Artefact,
        touch: &Touch,
    ) -> Result<Option<Trip>, ProbeError> {
        let bad = ProbeError::Touch {
            axis: touch.axis,
            sign: touch.sign,
            max_travel_mm: touch.max_travel_mm,
        };
        if touch.axis > 2
            || touch.sign.abs() != 1.0
            || !(touch.max_travel_mm > 0.0 && touch.max_travel_mm.is_finite())
        {
            return Err(bad);
        }
        let mut vel = [0.0; 3];
        vel[touch.axis] = touch.sign;
        twin.note_motion(vel);
        let approach = twin.draw_approach_mm();
        let saved = twin.set_tool_offset_mm([0.0, 0.0, -self.probe.stylus_length_mm]);
        let at = |lambda: f64| {
            let mut q = touch.start_mm;
            q[touch.axis] += touch.sign * lambda;
            q
        };
        let gap = |twin: &Twin, lambda: f64| {
            let q = at(lambda);
            let e = twin.tool_error_mm(q, q, approach);
            artefact.gap_mm(
                [q[0] + e.x, q[1] + e.y, q[2] + e.z],
                self.probe.ball_radius_mm,
            )
        };
        let g0 = gap(twin, 0.0);
        let g1 = gap(twin, touch.max_travel_mm);
        let contact = if g0 <= 0.0 {
            Err(ProbeError::AlreadyTripped)
        } else if g1 > 0.0 {
            Ok(None)
        } else {
            let (mut lo, mut hi) = (0.0, touch.max_travel_mm);
            while hi - lo > 1e-7 {
                let mid = 0.5 * (lo + hi);
                if gap(twin, mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            Ok(Some(hi))
        };
        twin.set_tool_offset_mm(saved);
        let Some(contact_mm) = contact? else {
            return Ok(None);
        };
        let probe = self.probe;
        let travel_mm = contact_mm + probe.pretravel_mm() + self.scatter_mm(&probe);
        Ok(Some(Trip {
            axis_mm: at(travel_mm),
            travel_mm,
        }))
    }

    /// One trip's travel past the nominal trip point, mm: the repeatability scatter (Gaussian)
    /// and the latency (uniform over one servo tick at `probe`'s feed).
    fn scatter_mm(&mut self, probe: &TouchProbe) -> f64 {
        let sigma_mm = 0.5 * probe.repeatability_2sigma_um * 1e-3;
        let scatter_mm = if sigma_mm > 0.0 {
            Normal::new(0.0, sigma_mm)
                .map(|n| n.sample(&mut self.rng))
                .unwrap_or(0.0)
        } else {
            0.0
        };
        scatter_mm + self.rng.random::<f64>() * probe.latency_travel_mm()
    }
}

mod station;
mod straight;
pub use station::ProbeStation;
pub use straight::{nominal_move, ProbeMotion, ProbeMove};

#[cfg(test)]
mod tests;
