//! One API for the stability lobes of the three methods.
//!
//! [`lobes`] returns, for each requested speed that has a boundary, the critical axial depth
//! (the smallest unstable depth), the chatter frequency and the kind of stability loss.
//! Depth search range: (0, 20 × the ZOA minimum depth]; tolerance 1e-3 × the ZOA minimum.
//! SDM uses the boundary tracer of [`crate::milling`] (speeds in the given order, default
//! 40 steps per period); ZOA the frequency scan of [`crate::zoa`] (always `Hopf`); the time
//! domain bisects the linear simulation of [`crate::time_domain`] (frequency from the spectrum).

use serde::{Deserialize, Serialize};

use crate::milling::{MillingSdm, SdmOptions};
use crate::params::{DynamicsError, Milling, TipModes, Tool};
pub use crate::sdm::LobePoint;
use crate::time_domain::{TimeDomain, TimeOptions};
use crate::zoa::Zoa;

/// Stability method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Method {
    /// First-order semi-discretisation.
    Sdm,
    /// Zero-order analytic solution.
    Zoa,
    /// Time-domain simulation.
    Time,
}

/// Scanned depths of [`sdm_lowest_critical_depth`].
pub const LOWEST_DEPTH_SCAN: usize = 100;

/// The lowest SDM critical depth at one speed (default 40 steps per period): an even scan of
/// [`LOWEST_DEPTH_SCAN`] depths over the range of [`lobes`] (0, 20 × the ZOA minimum], then
/// bisection to 1e-3 × the ZOA minimum. Slower than the tracer of [`lobes`] but it does not
/// follow a boundary from speed to speed, so it finds an unstable island (e.g. of a helical
/// cutter) under a higher boundary when the island is wider than the scan's spacing.
pub fn sdm_lowest_critical_depth(
    tool: &Tool,
    modes: &TipModes,
    immersion: f64,
    milling: Milling,
    spindle_rpm: f64,
) -> Result<Option<LobePoint>, DynamicsError> {
    crate::params::validate_speed(spindle_rpm)?;
    let zoa = Zoa::new(tool, modes, immersion, milling)?;
    let (min_mm, _) = zoa.minimum_depth();
    MillingSdm::new(tool, modes, immersion, milling, SdmOptions::default())?
        .at_speed(spindle_rpm)?
        .lowest_critical_depth(20.0 * min_mm, LOWEST_DEPTH_SCAN, 1e-3 * min_mm)
}

/// Stability lobes at the given speeds (speeds without a boundary in range are omitted).
pub fn lobes(
    method: Method,
    tool: &Tool,
    modes: &TipModes,
    immersion: f64,
    milling: Milling,
    speeds_rpm: &[f64],
) -> Result<Vec<LobePoint>, DynamicsError> {
    for &n in speeds_rpm {
        crate::params::validate_speed(n)?;
    }
    let zoa = Zoa::new(tool, modes, immersion, milling)?;
    let (min_mm, _) = zoa.minimum_depth();
    let (max_mm, tol_mm) = (20.0 * min_mm, 1e-3 * min_mm);
    match method {
        Method::Zoa => speeds_rpm
            .iter()
            .filter_map(|&n| zoa.critical_depth(n).transpose())
            .collect(),
        Method::Sdm => MillingSdm::new(tool, modes, immersion, milling, SdmOptions::default())?
            .trace(speeds_rpm, max_mm, tol_mm),
        Method::Time => {
            let td = TimeDomain::new(tool, modes, immersion, milling, TimeOptions::default())?;
            speeds_rpm
                .iter()
                .filter_map(|&n| td.critical_depth(n, max_mm, tol_mm).transpose())
                .collect()
        }
    }
}
