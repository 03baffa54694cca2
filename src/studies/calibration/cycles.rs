//! Thermal cycles: the calibration plan, designed to separate the heat sources, and the held-out
//! evaluation cycles, atypical duties and stress duties the plan never runs.

use vmc_machine::machine::MachineSpec;
use vmc_machine::thermal::AmbientProfile;
use vmc_machine::twin::{sub_seed, Twin, TwinError};

/// One duty phase of a thermal cycle.
#[derive(Debug, Clone, PartialEq)]
pub struct Phase {
    /// Duration, s.
    pub duration_s: f64,
    /// Spindle speed, rpm (0 = stopped).
    pub spindle_rpm: f64,
    /// Axis feed speeds while shuttling, mm/min (0 = parked).
    pub axis_speed_mm_per_min: [f64; 3],
}

/// A thermal cycle: phases under an ambient profile (time from the cycle's start).
#[derive(Debug, Clone, PartialEq)]
pub struct ThermalCycle {
    /// Short name (used as the dataset's `cycle` column and in reports).
    pub name: String,
    /// What the cycle is for (printed with the calibration plan).
    pub purpose: String,
    /// Ambient temperature over the cycle.
    pub ambient: AmbientProfile,
    /// The machine starts soaked at this uniform temperature, °C, as after a night in a shop
    /// at that temperature (None: at the machine file's ambient at t = 0).
    pub soak_degc: Option<f64>,
    /// Duty phases in order.
    pub phases: Vec<Phase>,
}

pub(super) fn phase(hours: f64, rpm: f64, speeds: [f64; 3]) -> Phase {
    Phase {
        duration_s: hours * 3600.0,
        spindle_rpm: rpm,
        axis_speed_mm_per_min: speeds,
    }
}

pub(super) const AMBIENT_20: AmbientProfile = AmbientProfile::Constant { temp_degc: 20.0 };

fn cycle(name: &str, purpose: &str, ambient: AmbientProfile, phases: Vec<Phase>) -> ThermalCycle {
    ThermalCycle {
        name: name.into(),
        purpose: purpose.into(),
        ambient,
        soak_degc: None,
        phases,
    }
}

/// A cycle in a shop held at `temp_degc`, the machine soaked at it.
fn shop(name: &str, purpose: &str, temp_degc: f64, phases: Vec<Phase>) -> ThermalCycle {
    ThermalCycle {
        soak_degc: Some(temp_degc),
        ..cycle(
            name,
            purpose,
            AmbientProfile::Constant { temp_degc },
            phases,
        )
    }
}

fn cool(hours: f64) -> Phase {
    phase(hours, 0.0, [0.0; 3])
}

impl ThermalCycle {
    /// Total duration, s.
    pub fn duration_s(&self) -> f64 {
        self.phases.iter().map(|p| p.duration_s).sum()
    }

    /// Sets the twin up for the cycle's start: its ambient profile and, for a soaked start,
    /// every temperature at the soak temperature.
    ///
    /// # Errors
    /// An invalid ambient profile or soak temperature.
    pub fn prepare(&self, twin: &mut Twin) -> Result<(), TwinError> {
        twin.set_ambient(self.ambient.clone())?;
        if let Some(t) = self.soak_degc {
            twin.soak_degc(t)?;
        }
        Ok(())
    }

    /// The phase in effect at cycle time `t_s` (the last one after the end).
    pub fn phase_at(&self, t_s: f64) -> &Phase {
        let mut acc = 0.0;
        for p in &self.phases {
            acc += p.duration_s;
            if t_s < acc {
                return p;
            }
        }
        // Cycles are built with at least one phase.
        &self.phases[self.phases.len() - 1]
    }

    /// Mean spindle speed over cycle time `[from_s, to_s]`, rpm (the speed at `from_s` for an
    /// empty interval).
    pub fn mean_rpm(&self, from_s: f64, to_s: f64) -> f64 {
        self.mean_of(from_s, to_s, |p| p.spindle_rpm)
    }

    /// Mean |speed| of each axis over cycle time `[from_s, to_s]`, mm/min (the speeds at
    /// `from_s` for an empty interval).
    pub fn mean_axis_feed(&self, from_s: f64, to_s: f64) -> [f64; 3] {
        [0, 1, 2].map(|a| self.mean_of(from_s, to_s, |p| p.axis_speed_mm_per_min[a].abs()))
    }

    /// Time mean of a phase quantity over cycle time `[from_s, to_s]` (its value at `from_s`
    /// for an empty interval).
    fn mean_of(&self, from_s: f64, to_s: f64, value: impl Fn(&Phase) -> f64) -> f64 {
        if to_s <= from_s {
            return value(self.phase_at(from_s));
        }
        let mut acc = 0.0;
        let mut sum = 0.0;
        for (k, p) in self.phases.iter().enumerate() {
            let start = acc;
            acc += p.duration_s;
            // The last phase lasts beyond the end.
            let end = if k + 1 == self.phases.len() {
                f64::INFINITY
            } else {
                acc
            };
            let overlap = to_s.min(end) - from_s.max(start);
            if overlap > 0.0 {
                sum += overlap * value(p);
            }
        }
        sum / (to_s - from_s)
    }

    /// The typical cycles of the original plan: heating at constant combined duties (one with a
    /// speed change, one axis-heavy), then cooling, over an ordinary workshop day (one with a
    /// slow ambient drift, one with ambient steps as when the air conditioning changes its set
    /// point — steps and ramps, not the held-out sinusoidal swing). Every one heats the spindle
    /// and the axes together, in a shop at 19–22.5 °C.
    pub fn combined_duty_set() -> Vec<ThermalCycle> {
        let combined = "combined duty";
        vec![
            cycle(
                "cal_3000rpm",
                combined,
                AMBIENT_20,
                vec![phase(4.0, 3000.0, [2000.0, 1500.0, 800.0]), cool(4.0)],
            ),
            cycle(
                "cal_6000rpm",
                combined,
                AMBIENT_20,
                vec![phase(4.0, 6000.0, [2000.0, 4000.0, 1500.0]), cool(4.0)],
            ),
            cycle(
                "cal_9000rpm",
                combined,
                AMBIENT_20,
                vec![phase(4.0, 9000.0, [4000.0, 3000.0, 2000.0]), cool(4.0)],
            ),
            cycle(
                "cal_4000_8000rpm",
                "combined duty, a speed change",
                AMBIENT_20,
                vec![
                    phase(2.0, 4000.0, [3000.0, 2000.0, 1000.0]),
                    phase(2.0, 8000.0, [3000.0, 2000.0, 1000.0]),
                    cool(4.0),
                ],
            ),
            cycle(
                "cal_axes_2000rpm",
                "combined duty, axis-heavy",
                AMBIENT_20,
                vec![phase(4.0, 2000.0, [6000.0, 5000.0, 3000.0]), cool(4.0)],
            ),
            cycle(
                "cal_day_drift",
                "combined duty, ambient ramp 19.5 → 21.5 °C",
                AmbientProfile::Table {
                    points: vec![[0.0, 19.5], [8.0 * 3600.0, 21.5]],
                },
                vec![phase(4.0, 7000.0, [3000.0, 3000.0, 1500.0]), cool(4.0)],
            ),
            cycle(
                "cal_ambient_steps",
                "combined duty, ambient steps 20 → 22.5 → 19 °C",
                AmbientProfile::Table {
                    points: vec![
                        [3600.0, 20.0],
                        [4500.0, 22.5],
                        [5.0 * 3600.0, 22.5],
                        [5.25 * 3600.0, 19.0],
                    ],
                },
                vec![phase(3.0, 5000.0, [2500.0, 2000.0, 1000.0]), cool(5.0)],
            ),
        ]
    }

    /// The calibration plan for a machine, designed so that the heat sources can be told apart:
    /// the combined duties of [`Self::combined_duty_set`]; each axis alone (its screw and motor
    /// at the machine's maximum feed, spindle stopped); the spindle alone stepped over its whole
    /// speed range up to `max_spindle_rpm` (axes parked); and a cold (15 °C) and a warm (28 °C)
    /// shop, wider than the ambient any evaluation sees. Every cycle heats, then cools: 8 h of
    /// machine time each, measurement blocks included.
    pub fn calibration_plan(spec: &MachineSpec) -> Vec<ThermalCycle> {
        let n_max = spec.motion.max_spindle_rpm;
        let f_max = spec.motion.max_feed_mm_per_min;
        let mut v = Self::combined_duty_set();
        for (a, axis) in ["x", "y", "z"].into_iter().enumerate() {
            let mut speeds = [0.0; 3];
            speeds[a] = f_max;
            v.push(cycle(
                &format!("cal_{axis}_axis_alone"),
                &format!(
                    "{} screw and motor alone: their heat apart from the spindle's",
                    axis.to_uppercase()
                ),
                AMBIENT_20,
                vec![phase(4.0, 0.0, speeds), cool(4.0)],
            ));
        }
        let step = |k: f64| phase(1.0, (k * n_max / 4.0).round(), [0.0; 3]);
        v.push(cycle(
            "cal_spindle_sweep",
            "spindle alone, stepped up to max_spindle_rpm: its heat apart from the axes'",
            AMBIENT_20,
            vec![step(1.0), step(2.0), step(3.0), step(4.0), cool(4.0)],
        ));
        let half = (0.5 * n_max).round();
        for (name, t) in [("cal_cold_shop", 15.0), ("cal_warm_shop", 28.0)] {
            v.push(shop(
                name,
                &format!("a shop at {t} °C: the machine's response to the air's level"),
                t,
                vec![phase(4.0, half, [3000.0, 3000.0, 1500.0]), cool(4.0)],
            ));
        }
        v
    }

    /// Atypical cycles held out for evaluation. `seed` draws the random speed steps.
    pub fn evaluation_set(seed: u64) -> Vec<ThermalCycle> {
        // Random speed steps every 30 min, drawn from a small deterministic generator.
        let mut state = sub_seed(seed, 77);
        let mut next = || {
            state = sub_seed(state, 1);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let steps: Vec<Phase> = (0..12)
            .map(|_| {
                let rpm = (next() * 10.0).floor() * 1000.0;
                let duty = next();
                phase(0.5, rpm, [4000.0 * duty, 3000.0 * duty, 2000.0 * duty])
            })
            .chain(std::iter::once(phase(2.0, 0.0, [0.0; 3])))
            .collect();
        vec![
            cycle(
                "eval_random_steps",
                "random speed and duty steps",
                AMBIENT_20,
                steps,
            ),
            cycle(
                "eval_ambient_swing",
                "combined duty under a sinusoidal ambient",
                AmbientProfile::Sinusoid {
                    mean_degc: 20.5,
                    amplitude_degc: 1.5,
                    period_s: 8.0 * 3600.0,
                    phase_rad: 0.0,
                },
                vec![phase(4.0, 7000.0, [3500.0, 2500.0, 1500.0]), cool(4.0)],
            ),
            cycle(
                "eval_restart",
                "restart after a stop",
                AMBIENT_20,
                vec![
                    phase(2.0, 9000.0, [4000.0, 3000.0, 2000.0]),
                    cool(1.5),
                    phase(2.5, 5000.0, [3000.0, 3000.0, 1000.0]),
                    cool(2.0),
                ],
            ),
        ]
    }

    /// Stress cycles held out for evaluation, one per way a calibration fails in a machine's
    /// first week: Z-heavy strokes with the spindle stopped, the spindle at
    /// `max_spindle_rpm` for hours, and a warm shop. None of them is a calibration cycle.
    pub fn stress_set(spec: &MachineSpec) -> Vec<ThermalCycle> {
        let n_max = spec.motion.max_spindle_rpm;
        vec![
            cycle(
                "stress_z_strokes",
                "Z-heavy strokes, little XY, spindle stopped",
                AMBIENT_20,
                vec![phase(3.0, 0.0, [400.0, 400.0, 6000.0]), cool(3.0)],
            ),
            cycle(
                "stress_top_speed",
                "hours at max_spindle_rpm with combined duty",
                AMBIENT_20,
                vec![phase(6.0, n_max, [3000.0, 2000.0, 1000.0]), cool(2.0)],
            ),
            shop(
                "stress_warm_shop",
                "a shop at 26 °C",
                26.0,
                vec![phase(4.0, 6000.0, [3000.0, 3000.0, 1500.0]), cool(4.0)],
            ),
        ]
    }
}
