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
//!
//! The figures are built from the runs fed in passes ([`FleetBuilder`]): a machine's runs come
//! together (report order is seed by seed), so only the current machine's reductions are held;
//! the percentiles across machines are exact order statistics ([`super::order_stats`]) and the
//! histograms take a pass of their own, so the memory does not grow with the machines.

use std::io::Write;

use crate::predict::predictor::ModelKind;

use super::histogram::{Histogram, HistogramBuilder};
use super::order_stats::{median_of_middle, Selector, StreamChanged, Wanted};
use super::report::{replay, RunPasses, RunReport};

/// Reduction of RMS |E| every run of a machine must reach (fraction).
pub const GOAL_REDUCTION: f64 = 0.80;

/// Largest residual |E| after compensation allowed on any run of a machine, µm.
pub const GOAL_MAX_RESIDUAL_UM: f64 = 2.0;

/// Thermal states whose name starts with this are the stress states (Z strokes, top speed):
/// the goals are also counted without them.
pub const STRESS_PREFIX: &str = "stress_";

/// Worst machines listed.
pub const WORST_LISTED: usize = 5;

/// Percentiles printed (then the largest value, the 100th).
pub const PERCENTILES: [f64; 5] = [5.0, 25.0, 50.0, 75.0, 95.0];

/// Bins of each histogram across machines.
pub const BINS: usize = 20;

/// The fleet quantities, in the order of the summary, the picture and the recording: median
/// reduction (%), worst-run reduction (%), max residual (µm), worst residual share of the
/// thermal part (%, machines with a warm run).
pub const QUANTITIES: [&str; 4] = [
    "median reduction %",
    "worst-run reduction %",
    "max residual |E'| µm",
    "worst residual/thermal %",
];

/// One machine's figures over its hybrid runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    /// Machine seed.
    pub seed: u64,
    /// Hybrid runs of the machine.
    pub runs: usize,
    /// Median reduction of its runs (fraction).
    pub median_reduction: f64,
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
    /// A machine before its first run.
    fn new(seed: u64) -> Self {
        Self {
            seed,
            runs: 0,
            median_reduction: f64::NAN,
            worst_reduction: f64::INFINITY,
            max_residual_um: f64::NEG_INFINITY,
            worst_residual_share: None,
            worst_reduction_unstressed: f64::INFINITY,
            max_residual_unstressed_um: f64::NEG_INFINITY,
            worst_run: Default::default(),
            worst_run_after_xyz_um: [0.0; 3],
            worst_run_before_xyz_um: [0.0; 3],
            worst_run_thermal_um: None,
        }
    }

    /// Adds one of its hybrid runs.
    fn push(&mut self, r: &RunReport) {
        self.runs += 1;
        self.worst_reduction = self.worst_reduction.min(r.reduction);
        if let Some(s) = r.residual_share_of_thermal {
            self.worst_residual_share = Some(self.worst_residual_share.map_or(s, |w| w.max(s)));
        }
        if !r.thermal_state.starts_with(STRESS_PREFIX) {
            self.worst_reduction_unstressed = self.worst_reduction_unstressed.min(r.reduction);
            self.max_residual_unstressed_um = self.max_residual_unstressed_um.max(r.max_after_um);
        }
        if r.max_after_um > self.max_residual_um {
            self.max_residual_um = r.max_after_um;
            self.worst_run = (r.diagonal.clone(), r.thermal_state.clone());
            self.worst_run_after_xyz_um = r.max_after_xyz_um;
            self.worst_run_before_xyz_um = r.max_before_xyz_um;
            self.worst_run_thermal_um = r.rms_thermal_um;
        }
    }

    /// Whether every run reaches [`GOAL_REDUCTION`].
    pub fn meets_reduction(&self) -> bool {
        self.worst_reduction >= GOAL_REDUCTION
    }

    /// Whether no run leaves more than [`GOAL_MAX_RESIDUAL_UM`].
    pub fn meets_residual(&self) -> bool {
        self.max_residual_um <= GOAL_MAX_RESIDUAL_UM
    }

    /// Whether every run outside the stress states reaches [`GOAL_REDUCTION`].
    pub fn meets_reduction_unstressed(&self) -> bool {
        self.worst_reduction_unstressed >= GOAL_REDUCTION
    }

    /// Whether no run outside the stress states leaves more than [`GOAL_MAX_RESIDUAL_UM`].
    pub fn meets_residual_unstressed(&self) -> bool {
        self.max_residual_unstressed_um <= GOAL_MAX_RESIDUAL_UM
    }

    /// The machine's value of each of the [`QUANTITIES`] (None: no warm run for the share).
    pub fn quantities(&self) -> [Option<f64>; 4] {
        [
            Some(self.median_reduction * 100.0),
            Some(self.worst_reduction * 100.0),
            Some(self.max_residual_um),
            self.worst_residual_share.map(|s| s * 100.0),
        ]
    }

    /// Whether `self` comes before `other` among the worst: larger max residual, then smaller
    /// seed.
    fn worse_than(&self, other: &Self) -> bool {
        other
            .max_residual_um
            .total_cmp(&self.max_residual_um)
            .then(self.seed.cmp(&other.seed))
            .is_lt()
    }
}

/// The machine being fed: its figures and its runs' reductions, for the median.
#[derive(Debug, Clone)]
struct Current {
    machine: Machine,
    reductions: Vec<f64>,
}

impl Current {
    /// The machine's figures with its median reduction.
    fn finish(mut self) -> Machine {
        self.reductions.sort_by(f64::total_cmp);
        let n = self.reductions.len();
        if n > 0 {
            self.machine.median_reduction =
                median_of_middle(n, self.reductions[(n - 1) / 2], self.reductions[n / 2]);
        }
        self.machine
    }
}

/// One fleet quantity across machines: its percentiles and histogram.
#[derive(Debug, Clone, PartialEq)]
pub struct Quantity {
    /// Name, from [`QUANTITIES`].
    pub name: &'static str,
    /// Machines with a value.
    pub machines: usize,
    /// The [`PERCENTILES`] then the largest value (None without a machine).
    pub percentiles: Vec<Option<f64>>,
    /// Histogram of [`BINS`] bins (None without a finite value).
    pub histogram: Option<Histogram>,
}

/// The fleet's figures, for the summary, the picture and the recording.
#[derive(Debug, Clone, PartialEq)]
pub struct FleetSummary {
    /// Machines (seeds with a hybrid run).
    pub machines: usize,
    /// Machines meeting the reduction goal, the residual goal, both.
    pub meeting: (usize, usize, usize),
    /// The same on the runs outside the stress states.
    pub meeting_unstressed: (usize, usize, usize),
    /// The [`QUANTITIES`] across machines.
    pub quantities: Vec<Quantity>,
    /// The worst machines (largest max residual first, then smaller seed), at most
    /// [`WORST_LISTED`].
    pub worst: Vec<Machine>,
}

/// A quantity's accumulators.
#[derive(Debug, Clone)]
struct QuantityBuilder {
    selector: Selector,
    histogram: HistogramBuilder,
}

/// Builds a [`FleetSummary`] from the runs, fed in passes ([`RunPasses`]). A machine's runs
/// must come together.
#[derive(Debug, Clone)]
pub struct FleetBuilder {
    /// Passes ended.
    passes: u32,
    current: Option<Current>,
    machines: usize,
    meeting: [usize; 6],
    worst: Vec<Machine>,
    quantities: Vec<QuantityBuilder>,
}

impl Default for FleetBuilder {
    fn default() -> Self {
        Self::with_keep_max(super::order_stats::KEEP_MAX)
    }
}

impl FleetBuilder {
    /// A builder whose order statistics keep at most `keep_max` values per search (fewer:
    /// more passes).
    pub fn with_keep_max(keep_max: usize) -> Self {
        let mut wanted = PERCENTILES.to_vec();
        wanted.push(100.0);
        Self {
            passes: 0,
            current: None,
            machines: 0,
            meeting: [0; 6],
            worst: Vec::new(),
            quantities: QUANTITIES
                .iter()
                .map(|_| QuantityBuilder {
                    selector: Selector::with_keep_max(
                        Wanted::Percentiles(wanted.clone()),
                        keep_max,
                    ),
                    histogram: HistogramBuilder::new(BINS),
                })
                .collect(),
        }
    }

    /// The current machine is complete.
    fn end_machine(&mut self) {
        let Some(c) = self.current.take() else {
            return;
        };
        let m = c.finish();
        for (q, v) in self.quantities.iter_mut().zip(m.quantities()) {
            if let Some(v) = v {
                q.selector.push(v);
                if self.passes <= 1 {
                    q.histogram.push(v);
                }
            }
        }
        if self.passes > 0 {
            return;
        }
        self.machines += 1;
        let goals = [
            m.meets_reduction(),
            m.meets_residual(),
            m.meets_reduction() && m.meets_residual(),
            m.meets_reduction_unstressed(),
            m.meets_residual_unstressed(),
            m.meets_reduction_unstressed() && m.meets_residual_unstressed(),
        ];
        for (count, met) in self.meeting.iter_mut().zip(goals) {
            *count += usize::from(met);
        }
        let at = self.worst.partition_point(|w| w.worse_than(&m));
        if at < WORST_LISTED {
            self.worst.insert(at, m);
            self.worst.truncate(WORST_LISTED);
        }
    }

    /// The fleet's figures (after the pass that said done).
    pub fn finish(self) -> FleetSummary {
        let m = self.meeting;
        FleetSummary {
            machines: self.machines,
            meeting: (m[0], m[1], m[2]),
            meeting_unstressed: (m[3], m[4], m[5]),
            quantities: QUANTITIES
                .iter()
                .zip(self.quantities)
                .map(|(name, q)| Quantity {
                    name,
                    machines: q.selector.count(),
                    percentiles: PERCENTILES
                        .iter()
                        .chain(&[100.0])
                        .map(|&p| q.selector.percentile(p))
                        .collect(),
                    histogram: q.histogram.finish(),
                })
                .collect(),
            worst: self.worst,
        }
    }
}

impl RunPasses for FleetBuilder {
    /// Adds a run of the current pass (only the hybrid's count).
    fn push(&mut self, r: &RunReport) {
        if r.predictor != ModelKind::Hybrid {
            return;
        }
        if self
            .current
            .as_ref()
            .is_some_and(|c| c.machine.seed != r.seed)
        {
            self.end_machine();
        }
        let c = self.current.get_or_insert_with(|| Current {
            machine: Machine::new(r.seed),
            reductions: Vec::new(),
        });
        c.machine.push(r);
        c.reductions.push(r.reduction);
    }

    /// Ends a pass; true when the figures are complete (the first pass finds the ranges of the
    /// histograms, the second counts them; the percentiles may take a few more).
    ///
    /// # Errors
    /// A pass over other runs than the first one.
    fn end_pass(&mut self) -> Result<bool, StreamChanged> {
        self.end_machine();
        let mut done = self.passes >= 1 || self.machines == 0;
        for q in &mut self.quantities {
            done &= q.selector.end_pass()?;
            if self.passes == 0 {
                q.histogram.end_range_pass();
            }
        }
        self.passes += 1;
        Ok(done)
    }
}

impl FleetSummary {
    /// The fleet of a campaign's runs (a machine's runs together).
    pub fn of(runs: &[RunReport]) -> Self {
        let mut b = FleetBuilder::default();
        // The same runs in the same order: the passes agree.
        let _ = replay(&mut b, runs.iter());
        b.finish()
    }
}

/// Writes the fleet section of the campaign summary (nothing for fewer than two machines).
///
/// # Errors
/// The writer's.
pub fn write_fleet_summary(fleet: &FleetSummary, out: &mut dyn Write) -> std::io::Result<()> {
    let n = fleet.machines;
    if n < 2 {
        return Ok(());
    }
    let pct = |k: usize| 100.0 * k as f64 / n as f64;
    writeln!(
        out,
        "fleet of {n} machines (one per seed), hybrid predictor: machines meeting the goals"
    )?;
    for (what, (red, res, both)) in [
        ("all states", fleet.meeting),
        ("without stress states", fleet.meeting_unstressed),
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
    for q in &fleet.quantities {
        write!(out, "  {:<26}", q.name)?;
        for v in &q.percentiles {
            write!(out, " {:>7.2}", v.unwrap_or(f64::NAN))?;
        }
        writeln!(out)?;
    }
    writeln!(out, "  worst machines (largest residual; its run, residual per axis |Ex'|/|Ey'|/|Ez'| and error before |Ex|/|Ey|/|Ez|, µm):")?;
    for m in &fleet.worst {
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
    fn machines_meet_the_goals_on_their_worst_run_and_the_worst_come_first() {
        // Machine 1: fine. Machine 2: one run at 79 %. Machine 3: one residual of 2.5 µm.
        let mut runs = vec![
            run(1, 0.95, 1.0, "XY"),
            run(1, 0.90, 1.5, "PPP"),
            run(2, 0.79, 1.0, "XY"),
            run(2, 0.99, 1.2, "PPP"),
        ];
        let mut other = run(3, 0.1, 50.0, "XZ");
        other.predictor = ModelKind::Linear;
        runs.push(other);
        runs.extend([run(3, 0.97, 2.5, "YZ"), run(3, 0.98, 1.0, "PPP")]);
        let f = FleetSummary::of(&runs);
        assert_eq!(f.machines, 3);
        assert_eq!(f.meeting, (2, 2, 1));
        assert_eq!(f.worst.len(), 3);
        assert_eq!(f.worst[0].seed, 3);
        assert_eq!(f.worst[0].worst_run.0, "YZ");
        assert_eq!(f.worst[1].seed, 1);
        assert!((f.worst[2].median_reduction - 0.89).abs() < 1e-12);
        // Worst-run reductions 90, 79, 97 %: P50 is the second smallest.
        assert_eq!(f.quantities[1].percentiles[2], Some(90.0));
        assert_eq!(f.quantities[1].percentiles[5], Some(97.0));
        let mut text = Vec::new();
        write_fleet_summary(&f, &mut text).unwrap();
        let text = String::from_utf8(text).unwrap();
        assert!(text.contains("both: 1 (33.3 %)"), "{text}");
        assert!(text.contains("seed 3      max residual  2.50 µm"), "{text}");
        assert!(text.contains("(mostly Ey)"), "{text}");
    }

    #[test]
    fn the_figures_do_not_depend_on_how_many_values_are_kept_per_pass() {
        // 60 machines of 7 runs with ties: percentiles found by sorting (all kept) and by
        // several passes (2 kept) are the same, and so are the worst machines.
        let runs: Vec<RunReport> = (0..420u32)
            .map(|i| {
                let seed = u64::from(i / 7 + 1);
                let red = 0.9 + f64::from((i * 37) % 23) / 400.0;
                run(seed, red, 1.0 + f64::from((i * 11) % 19) / 10.0, "XY")
            })
            .collect();
        let whole = FleetSummary::of(&runs);
        let mut b = FleetBuilder::with_keep_max(2);
        let passes = replay(&mut b, runs.iter()).unwrap();
        assert!(passes > 2, "{passes} passes");
        assert_eq!(b.finish(), whole);
        assert_eq!(whole.worst.len(), WORST_LISTED);
        let hist = whole.quantities[2].histogram.as_ref().unwrap();
        assert_eq!(hist.counts.iter().sum::<u64>(), 60);
    }
}
