//! One API for the stability lobes of the three methods.
//!
//! [`lobes`] returns, for each requested speed that has a boundary, the critical axial depth
//! (the smallest unstable depth), the chatter frequency and the kind of stability loss.
//! Depth search range: (0, 20 × the ZOA minimum depth]; tolerance 1e-3 × the ZOA minimum.
//! SDM uses the boundary tracer of [`crate::milling`] (speeds in the given order, runs of
//! [`crate::milling::TRACE_RUN`] speeds each starting from the ZOA minimum) at the converged
//! resolution of [`crate::converged`] unless told otherwise ([`lobes_block_at`]); ZOA the frequency scan of [`crate::zoa`] (always `Hopf`); the time
//! domain bisects the linear simulation of [`crate::time_domain`] (frequency from the spectrum).

use std::ops::Range;

use serde::{Deserialize, Serialize};

use crate::converged::Resolution;
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

/// The lowest SDM critical depth at one speed at the converged resolution
/// ([`Resolution::default`], see [`MillingSdm::lowest_critical_depth_at`]): an even scan of
/// [`LOWEST_DEPTH_SCAN`] depths over the range of [`lobes`] (0, 20 × the ZOA minimum], then
/// ITP to 1e-3 × the ZOA minimum. Slower than the tracer of [`lobes`] but it does not
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
    let range = (20.0 * min_mm, 1e-3 * min_mm);
    MillingSdm::new(tool, modes, immersion, milling, SdmOptions::default())?
        .lowest_critical_depth_at(
            spindle_rpm,
            range,
            LOWEST_DEPTH_SCAN,
            &Resolution::default(),
        )
}

/// Stability lobes at the given speeds (speeds without a boundary in range are omitted); SDM at
/// the converged resolution ([`Resolution::default`]).
pub fn lobes(
    method: Method,
    tool: &Tool,
    modes: &TipModes,
    immersion: f64,
    milling: Milling,
    speeds_rpm: &[f64],
) -> Result<Vec<LobePoint>, DynamicsError> {
    let all = 0..speeds_rpm.len();
    let points = lobes_block(method, tool, modes, immersion, milling, speeds_rpm, all)?;
    Ok(points.into_iter().flatten().collect())
}

/// The lobe points of the block `block` of `speeds_rpm`, one per speed (`None` without a
/// boundary in range), bit-identical to the same speeds' points of [`lobes`] over the whole
/// list: [`lobes_block_at`] at the converged resolution ([`Resolution::default`]).
pub fn lobes_block(
    method: Method,
    tool: &Tool,
    modes: &TipModes,
    immersion: f64,
    milling: Milling,
    speeds_rpm: &[f64],
    block: Range<usize>,
) -> Result<Vec<Option<LobePoint>>, DynamicsError> {
    let cut = (immersion, milling);
    let sdm = Resolution::default();
    lobes_block_at(method, tool, modes, cut, speeds_rpm, block, &sdm)
}

/// [`lobes_block`] with the semi-discretisation at `resolution` (ignored by ZOA and the time
/// domain): ZOA and the time domain treat each speed on its own, SDM traces the block with
/// [`MillingSdm::trace_block_at`] from the ZOA minimum depth. Every speed of the list is
/// checked, so a block fails where the whole list would.
pub fn lobes_block_at(
    method: Method,
    tool: &Tool,
    modes: &TipModes,
    (immersion, milling): (f64, Milling),
    speeds_rpm: &[f64],
    block: Range<usize>,
    resolution: &Resolution,
) -> Result<Vec<Option<LobePoint>>, DynamicsError> {
    for &n in speeds_rpm {
        crate::params::validate_speed(n)?;
    }
    let zoa = Zoa::new(tool, modes, immersion, milling)?;
    let (min_mm, _) = zoa.minimum_depth();
    let (max_mm, tol_mm) = (20.0 * min_mm, 1e-3 * min_mm);
    match method {
        Method::Sdm => MillingSdm::new(tool, modes, immersion, milling, SdmOptions::default())?
            .trace_block_at(
                speeds_rpm,
                block,
                Some(min_mm),
                (max_mm, tol_mm),
                resolution,
            ),
        Method::Zoa => speeds_of(speeds_rpm, block)?
            .iter()
            .map(|&n| zoa.critical_depth(n))
            .collect(),
        Method::Time => {
            let td = TimeDomain::new(tool, modes, immersion, milling, TimeOptions::default())?;
            speeds_of(speeds_rpm, block)?
                .iter()
                .map(|&n| td.critical_depth(n, max_mm, tol_mm))
                .collect()
        }
    }
}

/// The speeds of `block`, or the error of a block beyond the list.
fn speeds_of(speeds_rpm: &[f64], block: Range<usize>) -> Result<&[f64], DynamicsError> {
    let end = block.end;
    speeds_rpm.get(block).ok_or(DynamicsError::TooManySteps {
        name: "end of the block of speeds",
        max: speeds_rpm.len(),
        value: end,
    })
}
