//! Heat sources compiled from [`HeatSourceSpec`]: node names resolved to indices, powers
//! evaluated from an [`Activity`] without allocation.

use super::spec::HeatSourceSpec;
use super::Activity;
use std::collections::HashMap;

/// 2π/60 000: converts rpm·N·mm to W (H = 1.047e-4·n·M).
const W_PER_RPM_N_MM: f64 = std::f64::consts::TAU / 60_000.0;
/// Motor formula constant: P (kW) = M (N·m)·n (rpm) / 9550.
const RPM_N_M_PER_KW: f64 = 9550.0;
/// mm/min → m/s.
const M_PER_S_PER_MM_PER_MIN: f64 = 1.0 / 60_000.0;

/// A heat source with resolved node indices.
#[derive(Debug, Clone)]
pub(crate) enum Source {
    SpindleBearing {
        node: usize,
        torque_n_mm: f64,
        torque_per_krpm_n_mm: f64,
    },
    SpindleMotor {
        node: usize,
        torque_n_m: f64,
        torque_per_krpm_n_m: f64,
        efficiency: f64,
    },
    AxisMotor {
        node: usize,
        axis: usize,
        lead_mm: f64,
        torque_n_m: f64,
        efficiency: f64,
        standstill_w: f64,
    },
    ScrewBearing {
        node: usize,
        axis: usize,
        lead_mm: f64,
        torque_n_mm: f64,
    },
    BallscrewNut {
        axis: usize,
        segments: Vec<usize>,
        travel_min_mm: f64,
        travel_max_mm: f64,
        lead_mm: f64,
        torque_n_mm: f64,
    },
    GuideFriction {
        node: usize,
        axis: usize,
        friction_force_n: f64,
    },
    Constant {
        node: usize,
        power_w: f64,
    },
}

/// Motor loss (W) for shaft torque `torque_n_m` at `rpm` and efficiency η:
/// input − output = P_out/η·(1−η), P_out = M·n/9550 kW.
fn motor_loss_w(torque_n_m: f64, rpm: f64, efficiency: f64) -> f64 {
    1000.0 * torque_n_m * rpm / (RPM_N_M_PER_KW * efficiency) * (1.0 - efficiency)
}

impl Source {
    /// Compiles a validated spec; `None` if a node name is unknown (validation prevents that).
    pub(crate) fn compile(spec: &HeatSourceSpec, index: &HashMap<&str, usize>) -> Option<Self> {
        let idx = |name: &String| index.get(name.as_str()).copied();
        Some(match spec {
            HeatSourceSpec::SpindleBearing {
                node,
                torque_n_mm,
                torque_per_krpm_n_mm,
            } => Source::SpindleBearing {
                node: idx(node)?,
                torque_n_mm: *torque_n_mm,
                torque_per_krpm_n_mm: *torque_per_krpm_n_mm,
            },
            HeatSourceSpec::SpindleMotor {
                node,
                torque_n_m,
                torque_per_krpm_n_m,
                efficiency,
            } => Source::SpindleMotor {
                node: idx(node)?,
                torque_n_m: *torque_n_m,
                torque_per_krpm_n_m: *torque_per_krpm_n_m,
                efficiency: *efficiency,
            },
            HeatSourceSpec::AxisMotor {
                node,
                axis,
                lead_mm,
                torque_n_m,
                efficiency,
                standstill_w,
            } => Source::AxisMotor {
                node: idx(node)?,
                axis: axis.index(),
                lead_mm: *lead_mm,
                torque_n_m: *torque_n_m,
                efficiency: *efficiency,
                standstill_w: *standstill_w,
            },
            HeatSourceSpec::ScrewBearing {
                node,
                axis,
                lead_mm,
                torque_n_mm,
            } => Source::ScrewBearing {
                node: idx(node)?,
                axis: axis.index(),
                lead_mm: *lead_mm,
                torque_n_mm: *torque_n_mm,
            },
            HeatSourceSpec::BallscrewNut {
                axis,
                segments,
                travel_min_mm,
                travel_max_mm,
                lead_mm,
                torque_n_mm,
            } => Source::BallscrewNut {
                axis: axis.index(),
                segments: segments.iter().map(idx).collect::<Option<Vec<_>>>()?,
                travel_min_mm: *travel_min_mm,
                travel_max_mm: *travel_max_mm,
                lead_mm: *lead_mm,
                torque_n_mm: *torque_n_mm,
            },
            HeatSourceSpec::GuideFriction {
                node,
                axis,
                friction_force_n,
            } => Source::GuideFriction {
                node: idx(node)?,
                axis: axis.index(),
                friction_force_n: *friction_force_n,
            },
            HeatSourceSpec::Constant { node, power_w } => Source::Constant {
                node: idx(node)?,
                power_w: *power_w,
            },
        })
    }

    /// Adds this source's power (W) for `activity` into `q_w` (one entry per node).
    pub(crate) fn add_power_w(&self, activity: &Activity, q_w: &mut [f64]) {
        let rpm = activity.spindle_rpm.abs();
        let speed = |axis: usize| activity.axis_speed_mm_per_min[axis].abs();
        match self {
            Source::SpindleBearing {
                node,
                torque_n_mm,
                torque_per_krpm_n_mm,
            } => {
                let m = torque_n_mm + torque_per_krpm_n_mm * rpm / 1000.0;
                q_w[*node] += W_PER_RPM_N_MM * rpm * m;
            }
            Source::SpindleMotor {
                node,
                torque_n_m,
                torque_per_krpm_n_m,
                efficiency,
            } => {
                let m = torque_n_m + torque_per_krpm_n_m * rpm / 1000.0;
                q_w[*node] += motor_loss_w(m, rpm, *efficiency);
            }
            Source::AxisMotor {
                node,
                axis,
                lead_mm,
                torque_n_m,
                efficiency,
                standstill_w,
            } => {
                let n = speed(*axis) / lead_mm;
                q_w[*node] += standstill_w + motor_loss_w(*torque_n_m, n, *efficiency);
            }
            Source::ScrewBearing {
                node,
                axis,
                lead_mm,
                torque_n_mm,
            } => {
                q_w[*node] += W_PER_RPM_N_MM * speed(*axis) / lead_mm * torque_n_mm;
            }
            Source::BallscrewNut {
                axis,
                segments,
                travel_min_mm,
                travel_max_mm,
                lead_mm,
                torque_n_mm,
            } => {
                let seg = segment_under_nut(
                    activity.axis_pos_mm[*axis],
                    *travel_min_mm,
                    *travel_max_mm,
                    segments.len(),
                );
                q_w[segments[seg]] += W_PER_RPM_N_MM * speed(*axis) / lead_mm * torque_n_mm;
            }
            Source::GuideFriction {
                node,
                axis,
                friction_force_n,
            } => {
                q_w[*node] += friction_force_n * speed(*axis) * M_PER_S_PER_MM_PER_MIN;
            }
            Source::Constant { node, power_w } => q_w[*node] += power_w,
        }
    }
}

/// Index of the equal-length segment containing `pos_mm`, clamped to the screw's ends.
pub(crate) fn segment_under_nut(pos_mm: f64, min_mm: f64, max_mm: f64, count: usize) -> usize {
    let frac = (pos_mm - min_mm) / (max_mm - min_mm);
    if frac.is_nan() || frac <= 0.0 {
        return 0;
    }
    // Truncation is the intent: segment k covers [k, k+1)·length/count.
    ((frac * count as f64) as usize).min(count - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nut_position_maps_to_equal_length_segments_clamped_at_the_ends() {
        assert_eq!(segment_under_nut(0.0, 0.0, 500.0, 5), 0);
        assert_eq!(segment_under_nut(99.9, 0.0, 500.0, 5), 0);
        assert_eq!(segment_under_nut(100.0, 0.0, 500.0, 5), 1);
        assert_eq!(segment_under_nut(499.0, 0.0, 500.0, 5), 4);
        assert_eq!(segment_under_nut(500.0, 0.0, 500.0, 5), 4);
        assert_eq!(segment_under_nut(-30.0, 0.0, 500.0, 5), 0);
        assert_eq!(segment_under_nut(900.0, 0.0, 500.0, 5), 4);
        assert_eq!(segment_under_nut(f64::NAN, 0.0, 500.0, 5), 0);
    }

    #[test]
    fn bearing_friction_follows_1_047e_4_n_m() {
        let s = Source::SpindleBearing {
            node: 0,
            torque_n_mm: 50.0,
            torque_per_krpm_n_mm: 10.0,
        };
        let mut q = [0.0];
        let a = Activity {
            spindle_rpm: 10_000.0,
            ..Activity::default()
        };
        s.add_power_w(&a, &mut q);
        // M = 50 + 10·10 = 150 N·mm; H = 1.047e-4·10000·150 = 157.1 W (0.01 W tolerance).
        assert!((q[0] - 157.08).abs() < 0.01, "{}", q[0]);
    }

    #[test]
    fn motor_loss_follows_m_n_over_9550_eta_times_one_minus_eta() {
        // 2 N·m at 6000 rpm: 1.2565 kW output; η = 0.8 → input 1.5707 kW, loss 314.1 W.
        assert!((motor_loss_w(2.0, 6000.0, 0.8) - 314.14).abs() < 0.01);
    }
}
