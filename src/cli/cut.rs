//! Arguments of `cut`: one cut in the time domain.

use std::path::PathBuf;

use anyhow::{anyhow, bail, Result};

use super::{ForceArg, MillingArg};
use crate::commands;
use crate::dynamics::cut::{CutOptions, MAX_TOOTH_PERIODS};
use crate::dynamics::params::{readable, validate_immersion, validate_speed};
use crate::dynamics::{Cut, Milling};
use vmc_machine::milling::ToolDynamics;

/// Fewest tooth periods the verdict needs (four quarters of at least four).
const MIN_TOOTH_PERIODS: usize = 16;

/// Arguments of `cut`.
#[derive(clap::Args)]
pub struct CutArgs {
    /// Tool file (TOML: teeth, diameter, helix, cutting coefficients, tool-tip modes); default:
    /// the one-degree-of-freedom benchmark of the field (machines/benchmarks/insperger-1dof.toml).
    #[arg(long)]
    pub tool: Option<PathBuf>,
    /// Spindle speed, rpm (> 0).
    #[arg(long, allow_negative_numbers = true)]
    pub rpm: f64,
    /// Axial depth of cut a_p, mm (> 0).
    #[arg(long, allow_negative_numbers = true)]
    pub depth_mm: f64,
    /// Radial immersion a_e/D, in [0.01, 1] (1 = slotting).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub immersion: f64,
    /// Feed per tooth f_z, mm (> 0).
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    pub feed_per_tooth_mm: f64,
    /// Milling direction.
    #[arg(long, value_enum, default_value = "down")]
    pub milling: MillingArg,
    /// Simulated spindle revolutions; default: 400 tooth periods (200 revolutions of a
    /// two-tooth cutter).
    #[arg(long, conflicts_with = "duration_s", allow_negative_numbers = true)]
    pub revolutions: Option<f64>,
    /// Simulated time, s (instead of --revolutions).
    #[arg(long, allow_negative_numbers = true)]
    pub duration_s: Option<f64>,
    /// Write the time series as CSV (time_s, x_um, y_um, fx_n, fy_n).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write a Rerun recording: vibration and forces over time, the spectra, the report.
    #[arg(long, value_name = "FILE.rrd")]
    pub rrd: Option<PathBuf>,
    /// A controller file from `control design`: cut its blade without and with the controller
    /// (sampled, one-sample delay, saturation); the cutter, immersion and milling direction come
    /// from the file, --tool/--immersion/--milling do not apply.
    #[arg(long, conflicts_with_all = ["tool", "rrd"])]
    pub controller: Option<PathBuf>,
    /// With --controller: cut this plant file's blade with its cutter and cut (TOML, as for
    /// `control design`) instead of the plant the controller was designed on; the sampling
    /// stays the controller's.
    #[arg(long, requires = "controller")]
    pub plant: Option<PathBuf>,
    #[command(flatten)]
    pub force: ForceArg,
}

impl CutArgs {
    /// The config of `cut --controller`, when given.
    ///
    /// # Errors
    /// An unreadable or invalid controller file, a speed, depth or feed out of range, a
    /// horizon under 16 or over 100 000 tooth periods.
    pub fn controller_config(&self) -> Result<Option<commands::control::ControlCutConfig>> {
        let Some(path) = self.controller.as_deref() else {
            return Ok(None);
        };
        let file = vmc_machine::blade::ControllerFile::load(path)?;
        let judged = super::control::judged_on(&file, self.plant.as_deref())?;
        validate_speed(self.rpm).map_err(|e| anyhow!("--rpm: {e}"))?;
        positive("--depth-mm", self.depth_mm, "mm")?;
        positive("--feed-per-tooth-mm", self.feed_per_tooth_mm, "mm")?;
        let teeth = f64::from(judged.plant.tool.teeth);
        let period_s = judged.plant.tool.tooth_period_s(self.rpm);
        let periods = match (self.revolutions, self.duration_s) {
            (Some(r), _) => r * teeth,
            (None, Some(d)) => d / period_s,
            (None, None) => CutOptions::default().tooth_periods as f64,
        }
        .round();
        if !(MIN_TOOTH_PERIODS as f64..=MAX_TOOTH_PERIODS as f64).contains(&periods) {
            bail!("the horizon is {periods} tooth periods; {MIN_TOOTH_PERIODS} to {MAX_TOOTH_PERIODS} are simulated");
        }
        Ok(Some(commands::control::ControlCutConfig {
            file,
            source: path.display().to_string(),
            judged,
            spindle_rpm: self.rpm,
            depth_mm: self.depth_mm,
            feed_per_tooth_mm: self.feed_per_tooth_mm,
            tooth_periods: periods as usize,
            out: self.out.clone(),
            force: self.force.force,
        }))
    }

    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid tool file, a speed, depth, feed or immersion out of range, a
    /// horizon under 16 or over 100 000 tooth periods.
    pub fn config(self) -> Result<commands::cut::CutConfig> {
        let (tool, tool_source) = ToolDynamics::from_option(self.tool.as_deref())?;
        validate_speed(self.rpm).map_err(|e| anyhow!("--rpm: {e}"))?;
        positive("--depth-mm", self.depth_mm, "mm")?;
        positive("--feed-per-tooth-mm", self.feed_per_tooth_mm, "mm")?;
        validate_immersion(self.immersion).map_err(|e| anyhow!("--immersion: {e}"))?;
        within_tool(&tool.tool, self.depth_mm, self.feed_per_tooth_mm)?;
        let teeth = f64::from(tool.tool.teeth);
        let period_s = tool.tool.tooth_period_s(self.rpm);
        let periods = match (self.revolutions, self.duration_s) {
            (Some(r), _) => {
                positive("--revolutions", r, "")?;
                r * teeth
            }
            (None, Some(d)) => {
                positive("--duration-s", d, "s")?;
                d / period_s
            }
            (None, None) => CutOptions::default().tooth_periods as f64,
        };
        let periods = periods.round();
        let what = match (self.revolutions, self.duration_s) {
            (Some(r), _) => format!("--revolutions {}", readable(r)),
            (None, Some(d)) => format!("--duration-s {}", readable(d)),
            (None, None) => String::new(),
        };
        if periods < MIN_TOOTH_PERIODS as f64 {
            bail!(
                "{what} is {} tooth periods at {} rpm; at least {MIN_TOOTH_PERIODS} are needed ({:.4} s, {:.1} revolutions)",
                readable(periods),
                self.rpm,
                MIN_TOOTH_PERIODS as f64 * period_s,
                MIN_TOOTH_PERIODS as f64 / teeth
            );
        }
        if periods > MAX_TOOTH_PERIODS as f64 {
            bail!(
                "{what} is {} tooth periods at {} rpm; at most {MAX_TOOTH_PERIODS} are simulated ({:.3} s, {:.0} revolutions)",
                readable(periods),
                self.rpm,
                MAX_TOOTH_PERIODS as f64 * period_s,
                MAX_TOOTH_PERIODS as f64 / teeth
            );
        }
        Ok(commands::cut::CutConfig {
            tool,
            tool_source,
            cut: Cut {
                spindle_rpm: self.rpm,
                immersion: self.immersion,
                milling: match self.milling {
                    MillingArg::Up => Milling::Up,
                    MillingArg::Down => Milling::Down,
                },
                feed_per_tooth_mm: self.feed_per_tooth_mm,
                axial_depth_mm: self.depth_mm,
            },
            options: CutOptions {
                tooth_periods: periods as usize,
                ..CutOptions::default()
            },
            out: self.out,
            rrd: self.rrd,
            force: self.force.force,
        })
    }
}

/// Refuses a value that is not a finite number > 0.
/// Depth and feed a tool of this diameter can take: an axial depth of at most 10 diameters (a
/// long-reach end mill) and a feed per tooth of at most the radius. Beyond, the cut is not one a
/// tool makes, and its figures (a depth of 10³⁰⁰ % of the critical one) mean nothing.
fn within_tool(tool: &crate::dynamics::params::Tool, depth_mm: f64, feed_mm: f64) -> Result<()> {
    let d_mm = tool.diameter_mm;
    let show = crate::dynamics::params::readable;
    if depth_mm > 10.0 * d_mm {
        bail!(
            "--depth-mm {} is more than 10 tool diameters ({} mm for a {d_mm} mm tool)",
            show(depth_mm),
            10.0 * d_mm
        );
    }
    if feed_mm > 0.5 * d_mm {
        bail!(
            "--feed-per-tooth-mm {} is more than the tool's radius ({} mm)",
            show(feed_mm),
            0.5 * d_mm
        );
    }
    Ok(())
}

fn positive(option: &str, v: f64, unit: &str) -> Result<()> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        let unit = if unit.is_empty() {
            String::new()
        } else {
            format!(" {unit}")
        };
        bail!("{option} must be > 0{unit}, got {v}")
    }
}
