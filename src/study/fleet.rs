//! The fleet view of a campaign: every seed is one machine built to the specification (its own
//! geometric errors and thermal parameters), so over many seeds the campaign tells a builder how
//! the compensation does across the machines they build — the distribution over machines of the
//! hybrid predictor's reduction, max residual and residual share of the thermal part, the share
//! of machines that meet the goals, and the worst machines with what made them worst.
//!
//! Per machine, over its hybrid runs: the worst run's reduction of RMS |E|, the median
//! reduction, the largest residual |E'| and the largest residual share of the thermal part
//! (warm runs). A machine meets the reduction goal when its worst run reaches
//! [`GOAL_REDUCTION`], the residual goal when no run leaves more than [`GOAL_MAX_RESIDUAL_UM`].
//! Percentiles are of the nearest rank: the smallest value with at least p % of the machines
//! at or below it.

use std::io::Write;

use crate::predict::predictor::ModelKind;

use super::report::{median, RunReport};

/// Reduction of RMS |E| every run of a machine must reach (fraction).
pub const GOAL_REDUCTION: f64 = 0.80;

/// Largest residual |E| after compensation allowed on any run of a machine, µm.
pub const GOAL_MAX_RESIDUAL_UM: f64 = 2.0;

/// Thermal states whose name starts with this are the stress states (Z strokes, top speed):
/// the goals are also counted without them.
pub const STRESS_PREFIX: &str = "stress_";

/// Worst machines listed.
pub const WORST_LISTED: usize = 5;

/// Percentiles printed.
pub const PERCENTILES: [f64; 5] = [5.0, 25.0, 50.0, 75.0, 95.0];

/// One machine's figures over its hybrid runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    /// Machine seed.
    pub seed: u64,
    /// Hybrid runs of the machine.
    pub runs: usize,
    /// Reductions of its runs (fraction), for the median.
    reductions: Vec<f64>,
    /// Smallest reduction of a run (fraction).
    pub worst_reduction: f64,
    /// Largest residual |E'|, µm.
    pub max_residual_um: f64,
    /// Largest residual share of the thermal part over its warm runs (fraction).
    pub worst_residual_share: Option<f64>,
    /// Smallest reduction of a run outside the stress states (fraction).
    pub worst_reduction_unstressed: f64,
    /// Largest residual |E'| outside the stress states, µm.
    pub max_residual_unstressed_um: f64,
    /// The run that left the largest residual: diagonal, thermal state.
    pub worst_run: (String, String),
    /// That run's largest residual per component |Ex'|, |Ey'|, |Ez'|, µm.
    pub worst_run_after_xyz_um: [f64; 3],
    /// That run's largest error per component before compensation, µm.
    pub worst_run_before_xyz_um: [f64; 3],
    /// That run's RMS of the thermal part of |E|, µm.
    pub worst_run_thermal_um: Option<f64>,
}

impl Machine {
    /// Median reduction of the machine's runs (fraction).
    pub fn median_reduction(&self) -> f64 {
        median(&mut self.reductions.clone()).unwrap_or(f64::NAN)
    }

    /// Whether every run reaches [`GOAL_REDUCTION`].
    pub fn meets_reduction(&self) -> bool {
        self.worst_reduction >= GOAL_REDUCTION
    }

    /// Whether no run leaves more than [`GOAL_MAX_RESIDUAL_UM`].
    pub fn meets_residual(&self) -> bool {
        self.max_residual_um <= GOAL_MAX_RESIDUAL_UM
    }
}

/// The machines of a campaign, fed one run at a time (memory: one [`Machine`] per seed).
#[derive(Debug, Clone, Default)]
pub struct Fleet {
    /// The machines in the order of their first run.
    pub machines: Vec<Machine>,
}

impl Fleet {
    /// Adds a run (only the hybrid's count).
    pub fn push(&mut self, r: &RunReport) {
        if r.predictor != ModelKind::Hybrid {
            return;
        }
        let at = match self.machines.iter().rposition(|m| m.seed == r.seed) {
            Some(k) => k,
            None => {
                self.machines.push(Machine {
                    seed: r.seed,
                    runs: 0,
                    reductions: Vec::new(),
                    worst_reduction: f64::INFINITY,
                    max_residual_um: f64::NEG_INFINITY,
                    worst_residual_share: None,
                    worst_reduction_unstressed: f64::INFINITY,
                    max_residual_unstressed_um: f64::NEG_INFINITY,
                    worst_run: Default::default(),
                    worst_run_after_xyz_um: [0.0; 3],
                    worst_run_before_xyz_um: [0.0; 3],
                    worst_run_thermal_um: None,
                });
                self.machines.len() - 1
            }
        };
        let m = &mut self.machines[at];
        m.runs += 1;
        m.reductions.push(r.reduction);
        m.worst_reduction = m.worst_reduction.min(r.reduction);
        if let Some(s) = r.residual_share_of_thermal {
            m.worst_residual_share = Some(m.worst_residual_share.map_or(s, |w| w.max(s)));
        }
        if !r.thermal_state.starts_with(STRESS_PREFIX) {
            m.worst_reduction_unstressed = m.worst_reduction_unstressed.min(r.reduction);
            m.max_residual_unstressed_um = m.max_residual_unstressed_um.max(r.max_after_um);
        }
        if r.max_after_um > m.max_residual_um {
            m.max_residual_um = r.max_after_um;
            m.worst_run = (r.diagonal.clone(), r.thermal_state.clone());
            m.worst_run_after_xyz_um = r.max_after_xyz_um;
            m.worst_run_before_xyz_um = r.max_before_xyz_um;
            m.worst_run_thermal_um = r.rms_thermal_um;
        }
    }

    /// The fleet of the runs of a report.
    pub fn of<'a>(runs: impl IntoIterator<Item = &'a RunReport>) -> Self {
        let mut f = Self::default();
        for r in runs {
            f.push(r);
        }
        f
    }

    /// Machines meeting the reduction goal, the residual goal, both.
    pub fn meeting(&self) -> (usize, usize, usize) {
        let count = |f: &dyn Fn(&Machine) -> bool| self.machines.iter().filter(|m| f(m)).count();
        (
            count(&|m| m.meets_reduction()),
            count(&|m| m.meets_residual()),
            count(&|m| m.meets_reduction() && m.meets_residual()),
        )
    }

    /// [`Self::meeting`] on the runs outside the stress states.
    pub fn meeting_unstressed(&self) -> (usize, usize, usize) {
        let red = |m: &Machine| m.worst_reduction_unstressed >= GOAL_REDUCTION;
        let res = |m: &Machine| m.max_residual_unstressed_um <= GOAL_MAX_RESIDUAL_UM;
        let count = |f: &dyn Fn(&Machine) -> bool| self.machines.iter().filter(|m| f(m)).count();
        (count(&red), count(&res), count(&|m| red(m) && res(m)))
    }

    /// The worst machines: largest max residual first (ties: larger seed last), at most `n`.
    pub fn worst(&self, n: usize) -> Vec<&Machine> {
        let mut v: Vec<&Machine> = self.machines.iter().collect();
        v.sort_by(|a, b| {
            b.max_residual_um
                .total_cmp(&a.max_residual_um)
                .then(a.seed.cmp(&b.seed))
        });
        v.truncate(n);
        v
    }

    /// The per-machine values of the four fleet quantities: median reduction (%), worst-run
    /// reduction (%), max residual (µm), worst residual share of the thermal part (%, machines
    /// with a warm run).
    pub fn quantities(&self) -> [(&'static str, Vec<f64>); 4] {
        let ms = &self.machines;
        [
            (
                "median reduction %",
                ms.iter().map(|m| m.median_reduction() * 100.0).collect(),
            ),
            (
                "worst-run reduction %",
                ms.iter().map(|m| m.worst_reduction * 100.0).collect(),
            ),
            (
                "max residual |E'| µm",
                ms.iter().map(|m| m.max_residual_um).collect(),
            ),
            (
                "worst residual/thermal %",
                ms.iter()
                    .filter_map(|m| m.worst_residual_share)
                    .map(|s| s * 100.0)
                    .collect(),
            ),
        ]
    }
}

/// The nearest-rank `p`-th percentile of `v` (0 < p ≤ 100): the smallest value with at least
/// p % of the values at or below it; None if `v` is empty.
pub fn percentile(v: &[f64], p: f64) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let rank = ((p / 100.0) * s.len() as f64).ceil().max(1.0) as usize;
    Some(s[rank.min(s.len()) - 1])
}

/// Writes the fleet section of the campaign summary (nothing for fewer than two machines).
///
/// # Errors
/// The writer's.
pub fn write_fleet_summary(fleet: &Fleet, out: &mut dyn Write) -> std::io::Result<()> {
    let n = fleet.machines.len();
    if n < 2 {
        return Ok(());
    }
    let pct = |k: usize| 100.0 * k as f64 / n as f64;
    writeln!(
        out,
        "fleet of {n} machines (one per seed), hybrid predictor: machines meeting the goals"
    )?;
    for (what, (red, res, both)) in [
        ("all states", fleet.meeting()),
        ("without stress states", fleet.meeting_unstressed()),
    ] {
        writeln!(
            out,
            "  {what:<22} every run ≥ {:.0} % reduction: {red} ({:.1} %), max residual ≤ {GOAL_MAX_RESIDUAL_UM} µm: {res} ({:.1} %), both: {both} ({:.1} %)",
            GOAL_REDUCTION * 100.0,
            pct(red),
            pct(res),
            pct(both)
        )?;
    }
    write!(out, "  {:<26}", "across machines")?;
    for p in PERCENTILES {
        write!(out, " {:>7}", format!("P{p:.0}"))?;
    }
    writeln!(out, " {:>7}", "max")?;
    for (name, v) in fleet.quantities() {
        write!(out, "  {name:<26}")?;
        for p in PERCENTILES {
            write!(out, " {:>7.2}", percentile(&v, p).unwrap_or(f64::NAN))?;
        }
        writeln!(out, " {:>7.2}", percentile(&v, 100.0).unwrap_or(f64::NAN))?;
    }
    writeln!(out, "  worst machines (largest residual; its run, residual per axis |Ex'|/|Ey'|/|Ez'| and error before |Ex|/|Ey|/|Ez|, µm):")?;
    for m in fleet.worst(WORST_LISTED) {
        let axis = ["X", "Y", "Z"][largest(&m.worst_run_after_xyz_um)];
        let [a, b, c] = m.worst_run_after_xyz_um;
        let [x, y, z] = m.worst_run_before_xyz_um;
        writeln!(
            out,
            "    seed {:<6} max residual {:>5.2} µm, worst run {:>5.1} %: {} at {}, residual {a:.2}/{b:.2}/{c:.2} (mostly E{}), before {x:.1}/{y:.1}/{z:.1}, thermal part {:.1} µm RMS",
            m.seed,
            m.max_residual_um,
            m.worst_reduction * 100.0,
            m.worst_run.0,
            m.worst_run.1,
            axis.to_lowercase(),
            m.worst_run_thermal_um.unwrap_or(f64::NAN),
        )?;
    }
    Ok(())
}

/// Index of the largest of three values.
fn largest(v: &[f64; 3]) -> usize {
    (0..3).fold(0, |k, i| if v[i] > v[k] { i } else { k })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(seed: u64, reduction: f64, max_after_um: f64, diagonal: &str) -> RunReport {
        RunReport {
            predictor: ModelKind::Hybrid,
            diagonal: diagonal.into(),
            thermal_state: "cold".into(),
            seed,
            points: 10,
            rms_before_um: 10.0,
            rms_after_um: 10.0 * (1.0 - reduction),
            max_before_um: 20.0,
            max_after_um,
            reduction,
            max_reduction: 0.0,
            rms_before_xyz_um: [0.0; 3],
            rms_after_xyz_um: [0.0; 3],
            max_before_xyz_um: [5.0, 6.0, 7.0],
            max_after_xyz_um: [0.1, max_after_um, 0.2],
            rms_thermal_um: Some(4.0),
            residual_share_of_thermal: Some(0.1),
            mad_um: 0.0,
            mape: None,
            rmse_um: 0.0,
            r2: None,
            samples: Vec::new(),
        }
    }

    #[test]
    fn nearest_rank_percentiles_of_one_to_ten() {
        let v: Vec<f64> = (1..=10).rev().map(f64::from).collect();
        assert_eq!(percentile(&v, 5.0), Some(1.0));
        assert_eq!(percentile(&v, 50.0), Some(5.0));
        assert_eq!(percentile(&v, 95.0), Some(10.0));
        assert_eq!(percentile(&v, 100.0), Some(10.0));
        assert_eq!(percentile(&[], 50.0), None);
    }

    #[test]
    fn machines_meet_the_goals_on_their_worst_run_and_the_worst_come_first() {
        // Machine 1: fine. Machine 2: one run at 79 %. Machine 3: one residual of 2.5 µm.
        let mut runs = vec![
            run(1, 0.95, 1.0, "XY"),
            run(1, 0.90, 1.5, "PPP"),
            run(2, 0.79, 1.0, "XY"),
            run(2, 0.99, 1.2, "PPP"),
            run(3, 0.97, 2.5, "YZ"),
            run(3, 0.98, 1.0, "PPP"),
        ];
        let mut other = run(3, 0.1, 50.0, "XZ");
        other.predictor = ModelKind::Linear;
        runs.push(other);
        let f = Fleet::of(&runs);
        assert_eq!(f.machines.len(), 3);
        assert_eq!(f.meeting(), (2, 2, 1));
        let worst = f.worst(2);
        assert_eq!(worst[0].seed, 3);
        assert_eq!(worst[0].worst_run.0, "YZ");
        assert_eq!(worst[1].seed, 1);
        assert!((f.machines[1].median_reduction() - 0.89).abs() < 1e-12);
        let mut text = Vec::new();
        write_fleet_summary(&f, &mut text).unwrap();
        let text = String::from_utf8(text).unwrap();
        assert!(text.contains("both: 1 (33.3 %)"), "{text}");
        assert!(text.contains("seed 3      max residual  2.50 µm"), "{text}");
        assert!(text.contains("(mostly Ey)"), "{text}");
    }
}

/// A histogram: `counts[k]` values in `[lo + k·width, lo + (k+1)·width)` (the last bin closed).
#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    /// Lower edge of the first bin.
    pub lo: f64,
    /// Bin width (1 when every value is the same).
    pub width: f64,
    /// Values per bin.
    pub counts: Vec<u64>,
}

impl Histogram {
    /// `bins` equal bins from the smallest to the largest finite value of `v`; None without
    /// one or with no bin.
    pub fn of(v: &[f64], bins: usize) -> Option<Self> {
        let finite: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        let lo = finite.iter().copied().reduce(f64::min)?;
        let hi = finite.iter().copied().reduce(f64::max)?;
        if bins == 0 {
            return None;
        }
        let width = if hi > lo {
            (hi - lo) / bins as f64
        } else {
            1.0
        };
        let mut counts = vec![0u64; bins];
        for x in finite {
            let k = (((x - lo) / width) as usize).min(bins - 1);
            counts[k] += 1;
        }
        Some(Self { lo, width, counts })
    }

    /// The bins' centres.
    pub fn centres(&self) -> Vec<f64> {
        (0..self.counts.len())
            .map(|k| self.lo + (k as f64 + 0.5) * self.width)
            .collect()
    }
}

#[cfg(test)]
mod histogram_tests {
    use super::*;

    #[test]
    fn every_value_falls_in_one_bin_and_the_largest_in_the_last() {
        let h = Histogram::of(&[0.0, 1.0, 2.0, 3.0, 4.0, f64::NAN], 4).unwrap();
        assert_eq!(h.lo, 0.0);
        assert_eq!(h.width, 1.0);
        assert_eq!(h.counts, vec![1, 1, 1, 2]);
        assert_eq!(h.centres(), vec![0.5, 1.5, 2.5, 3.5]);
        assert_eq!(Histogram::of(&[2.0, 2.0], 3).unwrap().counts, vec![2, 0, 0]);
        assert_eq!(Histogram::of(&[], 3), None);
    }
}
