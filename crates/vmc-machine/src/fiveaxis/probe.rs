//! The virtual touch probe: probing the reference sphere at one configuration.
//!
//! With the rotary axes at θ, the probe approaches each of the sphere's points along the
//! nominal normal `n` (bed frame): from `q_c + n·(R + r + clearance)` towards the nominal centre
//! `q_c`, `R` the sphere and `r` the stylus-ball radius. It triggers where the real tool tip
//! (the whole erroneous chain, [`vmc_identify::htm`]) is at `R + r` from the real sphere centre,
//! late or early by the trigger noise (Gaussian along the approach, σ = 2σ-value / 2), and
//! records the commanded linear axes there. The centre is then fitted to the recorded points
//! with the known radius `R + r` ([`vmc_identify::sphere`]); that is all a real probing cycle
//! gives.

use nalgebra::Vector3;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

use super::spec::FiveAxisSpec;
use super::truth::TrueMachine;
use vmc_identify::chain::Pose;
use vmc_identify::htm::tip_in_workpiece_mm;
use vmc_identify::inverse::nominal_linear_axes;
use vmc_identify::sphere::{default_directions, fit_centre, SphereError, SphereFit};

/// Probe settings, from the machine file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VirtualProbe {
    /// σ of the trigger position along the approach, mm.
    pub noise_sigma_mm: f64,
    /// Points per sphere.
    pub points: usize,
    /// Approach start outside the contact, mm.
    pub clearance_mm: f64,
    /// Sphere + stylus radius, mm.
    pub contact_radius_mm: f64,
}

impl VirtualProbe {
    /// The probe of a machine file, with its trigger noise (2σ, µm) overridden if given.
    #[must_use]
    pub fn of(spec: &FiveAxisSpec, noise_2sigma_um: Option<f64>) -> Self {
        let two_sigma_um = noise_2sigma_um.unwrap_or(spec.probe.trigger_noise_2sigma_um);
        VirtualProbe {
            noise_sigma_mm: two_sigma_um * 1e-3 / 2.0,
            points: spec.probe.points,
            clearance_mm: spec.probe.clearance_mm,
            contact_radius_mm: spec.sphere.radius_mm + spec.sphere.stylus_radius_mm,
        }
    }
}

/// Which sphere to probe and where it nominally is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeTarget {
    /// Which sphere of the artefact (0: the datum); 0 for a relocated sphere.
    pub sphere: usize,
    /// 0: the calibrated artefact; k ≥ 1: the k-th placement of a relocated sphere.
    pub placement: usize,
    /// Nominal centre in the workpiece frame, mm.
    pub target_w_mm: [f64; 3],
}

impl ProbeTarget {
    /// Sphere `sphere` of the calibrated artefact at its nominal centre.
    #[must_use]
    pub fn artefact(sphere: usize, target_w_mm: [f64; 3]) -> Self {
        ProbeTarget {
            sphere,
            placement: 0,
            target_w_mm,
        }
    }
}

/// What probing a sphere at one configuration gives.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbedSphere {
    /// Which sphere of the artefact (0: the datum).
    pub sphere: usize,
    /// 0: the calibrated artefact; k ≥ 1: the k-th placement of a relocated sphere.
    pub placement: usize,
    /// Its nominal centre in the workpiece frame, mm.
    pub target_w_mm: [f64; 3],
    /// Rotary angles, degrees.
    pub rotary_deg: [f64; 2],
    /// Nominal linear axes at the sphere centre, mm.
    pub nominal_mm: [f64; 3],
    /// Recorded linear axes at each trigger, mm.
    pub points_mm: Vec<Vector3<f64>>,
    /// The fitted centre.
    pub fit: SphereFit,
}

/// Why a sphere could not be probed.
#[derive(Debug, thiserror::Error)]
pub enum ProbeError {
    /// The probe never met the sphere (errors far beyond the clearance).
    #[error("no trigger at C/A {rotary_deg:?} along {direction:?}: the sphere is not where the probe looks")]
    NoTrigger {
        /// Rotary angles, degrees.
        rotary_deg: [f64; 2],
        /// Approach normal.
        direction: [f64; 3],
    },
    /// The centre could not be fitted.
    #[error(transparent)]
    Fit(#[from] SphereError),
}

/// Probes the sphere of `target` at `rotary_deg`, drawing the trigger noise from `rng`. An
/// artefact's sphere really is at its nominal centre (the artefact is calibrated); a relocated
/// sphere sits where the truth put it ([`TrueMachine::placement_offset_mm`]), and the probe
/// approaches its nominal centre as a user's cycle would.
///
/// # Errors
/// [`ProbeError`] when an approach does not trigger or the fit fails.
pub fn probe_sphere(
    machine: &TrueMachine,
    probe: &VirtualProbe,
    target: ProbeTarget,
    rotary_deg: [f64; 2],
    rng: &mut StdRng,
) -> Result<ProbedSphere, ProbeError> {
    let geom = machine.geometry();
    let ProbeTarget {
        sphere,
        placement,
        target_w_mm,
    } = target;
    let qc = Vector3::from(nominal_linear_axes(
        geom,
        rotary_deg,
        Vector3::from(target_w_mm),
    ));
    let real = Vector3::from(target_w_mm) + Vector3::from(machine.placement_offset_mm(placement));
    let noise = Normal::new(0.0, probe.noise_sigma_mm.max(0.0)).expect("σ ≥ 0");
    let rc = probe.contact_radius_mm;
    let mut points = Vec::with_capacity(probe.points);
    for n in default_directions().into_iter().take(probe.points) {
        let start = qc + n * (rc + probe.clearance_mm);
        // Distance from the contact sphere along the approach.
        let gap = |t: f64| {
            let q = start - n * t;
            let pose = Pose {
                linear_mm: q.into(),
                rotary_deg,
            };
            (tip_in_workpiece_mm(geom, &pose, &machine.state_at(&pose)) - real).norm() - rc
        };
        // d(gap)/dt ≈ −1 (the approach runs along the normal): fixed-point on t.
        let mut t = 0.0;
        let mut converged = false;
        for _ in 0..50 {
            let g = gap(t);
            t += g;
            if g.abs() < 1e-10 {
                converged = true;
                break;
            }
        }
        if !converged || t < 0.0 || t > 2.0 * (rc + probe.clearance_mm) {
            return Err(ProbeError::NoTrigger {
                rotary_deg,
                direction: n.into(),
            });
        }
        let t_trigger = t + noise.sample(rng);
        points.push(start - n * t_trigger);
    }
    let fit = fit_centre(&points, rc)?;
    Ok(ProbedSphere {
        sphere,
        placement,
        target_w_mm,
        rotary_deg,
        nominal_mm: qc.into(),
        points_mm: points,
        fit,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn machine() -> (FiveAxisSpec, TrueMachine) {
        let spec = FiveAxisSpec::load(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../machines/trunnion-ac.toml"),
        )
        .unwrap();
        let m = TrueMachine::new(&spec, 1).unwrap();
        (spec, m)
    }

    #[test]
    fn noise_free_probing_finds_the_exact_reading_within_a_fraction_of_a_micrometre() {
        let (spec, m) = machine();
        let probe = VirtualProbe::of(&spec, Some(0.0));
        let mut rng = StdRng::seed_from_u64(1);
        for rot in [[0.0, 0.0], [123.0, -75.0], [300.0, 20.0]] {
            let got = probe_sphere(
                &m,
                &probe,
                ProbeTarget::artefact(0, [0.0; 3]),
                rot,
                &mut rng,
            )
            .unwrap();
            let exact =
                vmc_identify::inverse::linear_axes_for(m.geometry(), rot, Vector3::zeros(), &|p| {
                    m.state_at(p)
                })
                .unwrap();
            // The local scale of the linear axes (a few µm/m) makes the probed sphere an
            // ellipsoid; probed over a hemisphere its fitted centre moves by ≈ R·scale ≈ 0.1 µm.
            let d = (got.fit.centre_mm - Vector3::from(exact)).norm();
            assert!(d < 3e-4, "{rot:?}: {d:e} mm");
            // And the machine's errors are visible: tens of µm.
            assert!((got.fit.centre_mm - Vector3::from(got.nominal_mm)).norm() > 0.005);
        }
    }

    #[test]
    fn the_trigger_noise_spreads_the_centre_as_its_covariance_says() {
        let (spec, m) = machine();
        let probe = VirtualProbe::of(&spec, Some(2.0));
        let mut rng = StdRng::seed_from_u64(2);
        let clean = probe_sphere(
            &m,
            &VirtualProbe::of(&spec, Some(0.0)),
            ProbeTarget::artefact(0, [0.0; 3]),
            [40.0, -30.0],
            &mut rng,
        )
        .unwrap();
        let n = 400;
        let mut z2 = 0.0;
        for _ in 0..n {
            let p = probe_sphere(
                &m,
                &probe,
                ProbeTarget::artefact(0, [0.0; 3]),
                [40.0, -30.0],
                &mut rng,
            )
            .unwrap();
            let d = p.fit.centre_mm - clean.fit.centre_mm;
            let cov = p.fit.cov_per_var * probe.noise_sigma_mm.powi(2);
            z2 += (d.transpose() * cov.try_inverse().unwrap() * d)[0];
        }
        // E[dᵀ Σ⁻¹ d] = 3; the mean of 400 is within ±0.4 of it (≈ 5σ).
        let mean = z2 / f64::from(n);
        assert!((mean - 3.0).abs() < 0.4, "{mean}");
    }
}
