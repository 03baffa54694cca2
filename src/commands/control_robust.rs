//! `vmc-twin control design --robustness`: the designed controller judged on perturbed
//! blades (frequencies, mass, damping; see [`crate::dynamics::control::robust`]) — per case
//! whether the loop is stable without cutting, the attenuation of each mode, and the open- and
//! closed-loop minimum critical depths over the speeds asked for.

use std::fmt::Write as _;
use std::io::Write;

use anyhow::Result;

use crate::dynamics::control::closed_loop::LobeCut;
use crate::dynamics::control::robust::{
    robustness_case, Perturbation, RobustnessCase, SampledController, SweepLobes,
};
use crate::dynamics::Resolution;
use vmc_machine::blade::Plant;

/// What the sweep computes.
#[derive(Debug, Clone)]
pub struct SweepConfig {
    /// The perturbed blades.
    pub cases: Vec<Perturbation>,
    /// Spindle speeds of the lobes, rpm (empty: stability and attenuation only).
    pub speeds_rpm: Vec<f64>,
    /// Resolution of the lobes.
    pub resolution: Resolution,
}

/// Deepest depth searched, mm, and the tolerance.
const DEPTH_RANGE_MM: (f64, f64) = (50.0, 1e-4);

/// Runs the sweep and prints one row per case and the worst closed/open ratio.
///
/// # Errors
/// A perturbation the models refuse, an output that cannot be written.
pub fn sweep(
    plant: &Plant,
    c: &SampledController<'_>,
    cfg: &SweepConfig,
    out: &mut dyn Write,
) -> Result<Vec<RobustnessCase>> {
    let lobes = (!cfg.speeds_rpm.is_empty()).then(|| SweepLobes {
        cut: lobe_cut(plant),
        speeds_rpm: cfg.speeds_rpm.clone(),
        depth_range_mm: DEPTH_RANGE_MM,
        resolution: cfg.resolution,
    });
    let mut text = String::new();
    writeln!(
        text,
        "robustness: the controller on {} perturbed blades{}",
        cfg.cases.len(),
        match &lobes {
            Some(l) => format!(
                ", minimum critical depth over {} speeds from {:.0} to {:.0} rpm ({})",
                l.speeds_rpm.len(),
                l.speeds_rpm.first().copied().unwrap_or(0.0),
                l.speeds_rpm.last().copied().unwrap_or(0.0),
                match l.resolution {
                    Resolution::Fixed(m) => format!("{m} steps per tooth period"),
                    Resolution::Converged(r) => super::lobes::converged_text(&r),
                }
            ),
            None => String::new(),
        }
    )?;
    writeln!(
        text,
        "  {:<28} {:>8} {:>7} {:>9} {:>9} {:>9} {:>11} {:>11} {:>7}",
        "blade",
        "mode1_hz",
        "stable",
        "max_re",
        "rho_samp",
        "att1_db",
        "open_mm",
        "closed_mm",
        "ratio"
    )?;
    out.write_all(text.as_bytes())?;
    let mut cases = Vec::new();
    for &p in &cfg.cases {
        let r = robustness_case(&plant.blade, c, p, lobes.as_ref())?;
        let mm = |v: Option<f64>| v.map_or_else(|| "-".to_string(), |v| format!("{v:.4}"));
        let line = format!(
            "  {:<28} {:>8.1} {:>7} {:>9.1} {:>9.5} {:>9} {:>11} {:>11} {:>7}\n",
            p.label(),
            r.frequencies_hz.first().copied().unwrap_or(0.0),
            if r.stable { "yes" } else { "NO" },
            r.max_pole_real_rad_per_s,
            r.sampled_spectral_radius,
            r.attenuation_db
                .first()
                .map_or_else(|| "-".to_string(), |d| format!("{d:.1}")),
            mm(r.open_min_depth_mm),
            mm(r.closed_min_depth_mm),
            r.depth_ratio()
                .map_or_else(|| "-".to_string(), |v| format!("{v:.2}"))
        );
        out.write_all(line.as_bytes())?;
        out.flush()?;
        cases.push(r);
    }
    let unstable = cases.iter().filter(|c| !c.stable).count();
    let worst = cases
        .iter()
        .filter_map(RobustnessCase::depth_ratio)
        .min_by(f64::total_cmp);
    let mut tail = format!("unstable without cutting: {unstable} of {}", cases.len());
    if let Some(w) = worst {
        write!(
            tail,
            "; worst closed/open minimum depth of the stable cases {w:.2}"
        )?;
    }
    writeln!(out, "{tail}")?;
    Ok(cases)
}

/// The cut of a plant file's lobes.
pub fn lobe_cut(p: &Plant) -> LobeCut {
    LobeCut {
        tool: p.tool,
        immersion: p.immersion,
        milling: p.milling,
    }
}
