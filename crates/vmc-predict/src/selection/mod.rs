//! Temperature sensor placement from a calibration-style dataset: which K of
//! many candidate locations carry the information a thermal-error model needs.
//!
//! The procedure, stated so a user can reproduce it on a real machine's data:
//! 1. **Targets** are every error the instruments measured, as *channels*: each laser reading
//!    (axis, position along the axis rounded to 0.1 mm, component), each squareness component
//!    and each spindle drift. Rotations are weighted by an Abbe arm (default 300 mm, so 1 µrad
//!    counts as 0.3 µm) to put every channel in µm. Laser and squareness readings are grouped into
//!    *measurement blocks* (consecutive non-spindle records less than [`SelectionConfig::block_gap_s`]
//!    apart); a block's row uses the mean of its records' temperatures. Spindle readings are rows of
//!    their own. Only channels measured in every block are used.
//! 2. **Score of a sensor set**: leave-one-cycle-out cross-validated error of a multi-output ridge
//!    regression `channels ≈ a + B·temperatures` (inputs standardised on the training folds),
//!    the RMS over channels of each channel's RMS held-out error, in µm. Whole cycles are held
//!    out, never single rows of a time series.
//! 3. **Redundancy**: the correlation of candidate temperatures over all spindle-logging rows (a
//!    dense time series across every cycle). A candidate whose |r| with an already chosen sensor
//!    is ≥ [`SelectionConfig::redundancy_corr`] is not eligible: it would add a copy, not
//!    information. Candidates are also reported in clusters of mutually redundant locations.
//! 4. **Linear forward selection**: start from the reference sensors (the cold reference,
//!    ambient), then repeatedly add the eligible candidate that lowers the score most
//!    (*information phase*) while it lowers it by at least
//!    [`SelectionConfig::min_gain_fraction`] of the reference score; after that, add the
//!    candidate least correlated with every chosen one among those strongly linked to a thermal
//!    error (|r| ≥ [`SelectionConfig::min_relevance`]) (*coverage phase*), until K are chosen.
//! 5. **Proposals** ([`Proposal`], `proposals`): the candidates besides the reference are
//!    grouped into K clusters of similar thermal behaviour — average-linkage agglomerative
//!    clustering with distance `1 − |r|`, on the readings or on their rise above the reference
//!    ([`CorrBasis`]) — so that the set covers every structure (spindle, headstock, column,
//!    X, Y, Z drives, bed…) as the study did; one sensor per cluster is taken by relevance
//!    (strongest |r| with a thermal error channel) or by greedy forward selection on the score
//!    (at most one per cluster). With the linear forward selection of step 4 that makes five
//!    proposals ([`Rule`]). Each is ranked by forward selection on the score within the set:
//!    the score after each sensor and its gain are the evidence. Which proposal to keep is not
//!    decided here: the linear score cannot see what the non-linear predictor gains from a
//!    location under conditions the calibration cycles did not excite, so the caller validates
//!    each proposal with the predictor itself (`vmc-twin`'s `placement` module).
//!
//! Channels: only those that all candidates together predict with a cross-validated R² ≥
//! [`SelectionConfig::min_channel_r2`] count as thermal errors; the rest is instrument noise.
//!
//! The module sees datasets only (the information boundary): candidate names are
//! column names, nothing more.

use nalgebra::{DMatrix, DVector};
use thiserror::Error;

use crate::dataset::{Dataset, Instrument};

mod proposals;
pub use proposals::{CorrBasis, Proposal, RankedSensor, Rule};

/// Settings of the selection.
#[derive(Debug, Clone, PartialEq)]
pub struct SelectionConfig {
    /// Sensors to choose besides the reference ones (default 11, the study's count).
    pub count: usize,
    /// Always included, first (default `["ambient"]`: the cold reference).
    pub reference: Vec<String>,
    /// |r| at or above which two locations count as redundant (default 0.998). Why so high:
    /// every node of a machine warms together, so most pairs correlate above 0.9; only
    /// near-copies (the same casting a few cm apart) reach 0.998.
    pub redundancy_corr: f64,
    /// Ridge λ on standardised inputs, relative to the row count (default 1e-4).
    pub ridge: f64,
    /// Abbe arm that turns rotations (µrad) into µm, mm (default 300 mm).
    pub arm_mm: f64,
    /// Largest time gap inside one measurement block, s (default 300 s).
    pub block_gap_s: f64,
    /// A channel counts as a thermal error only if all candidates together predict it with a
    /// leave-one-cycle-out R² of at least this (default 0.5). Why: most of the ~280 channels
    /// (angles, straightness) carry no thermal signal, only instrument noise; left in, their
    /// over-fitting penalty hides the gain of a sensor on the few channels that drift.
    pub min_channel_r2: f64,
    /// Information phase ends when the best candidate lowers the score by less than this
    /// fraction of the reference score (default 0.01); the remaining picks then maximise
    /// coverage ([`Phase::Coverage`]).
    pub min_gain_fraction: f64,
    /// Coverage picks only candidates whose strongest |r| with a thermal error channel is at
    /// least this (default 0.9; all candidates when none is left): a location must be linked to
    /// an error to be worth a sensor — the study's first criterion.
    pub min_relevance: f64,
}

impl Default for SelectionConfig {
    fn default() -> Self {
        Self {
            count: 11,
            reference: vec!["ambient".into()],
            redundancy_corr: 0.998,
            ridge: 1e-4,
            arm_mm: 300.0,
            block_gap_s: 300.0,
            min_channel_r2: 0.5,
            min_gain_fraction: 0.01,
            min_relevance: 0.9,
        }
    }
}

/// Why a selection cannot be made.
#[derive(Debug, Error, PartialEq)]
pub enum SelectionError {
    /// A reference sensor is not a dataset column.
    #[error("reference sensor `{0}` is not among the dataset's sensors")]
    UnknownReference(String),
    /// Fewer than two cycles: no cross-validation across cycles is possible.
    #[error("the dataset has {0} thermal cycle(s); selection needs at least 2 (whole cycles are held out)")]
    TooFewCycles(usize),
    /// No usable error channel.
    #[error(
        "the dataset has no instrument channel measured in every block and no spindle records"
    )]
    NoChannels,
    /// K larger than the eligible candidates.
    #[error("asked for {asked} sensors but only {available} non-redundant candidates are left after {chosen} were chosen")]
    NotEnoughCandidates {
        /// Requested count.
        asked: usize,
        /// Eligible candidates left.
        available: usize,
        /// Chosen so far.
        chosen: usize,
    },
}

/// One row group: rows share their channels.
#[derive(Debug, Clone)]
struct Group {
    /// Temperatures, rows × all candidate sensors.
    temps: DMatrix<f64>,
    /// Channel values, rows × channels (µm).
    values: DMatrix<f64>,
    /// Cycle index of each row.
    cycle: Vec<usize>,
    /// Channel names.
    channels: Vec<String>,
}

/// Evidence about one candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateEvidence {
    /// Sensor (column) name.
    pub name: String,
    /// Cluster of mutually redundant candidates it belongs to (0-based).
    pub cluster: usize,
    /// Largest |r| between its temperature and any error channel.
    pub max_abs_corr: f64,
    /// The channel reaching it.
    pub best_channel: String,
    /// Score of the reference set plus this candidate alone, µm.
    pub alone_score_um: f64,
}

/// One step of the forward selection.
#[derive(Debug, Clone, PartialEq)]
pub struct SelectionStep {
    /// Sensor added.
    pub name: String,
    /// Cross-validated score after adding it, µm.
    pub score_um: f64,
    /// Score decrease it brought, µm.
    pub gain_um: f64,
    /// Why it was chosen.
    pub phase: Phase,
}

/// The two phases of the forward selection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Chosen for the largest drop of the cross-validated error.
    Information,
    /// Chosen as the candidate least correlated with every chosen one, once no candidate
    /// lowers the error noticeably: coverage of the thermal field where the linear score is
    /// blind (gradients the calibration cycles did not excite).
    Coverage,
}

impl Phase {
    /// Short name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Information => "information",
            Phase::Coverage => "coverage",
        }
    }
}

/// The result: the chosen sensors in order, with the evidence.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// Reference sensors (always included).
    pub reference: Vec<String>,
    /// Score of the reference sensors alone, µm.
    pub reference_score_um: f64,
    /// The added sensors in order of addition.
    pub steps: Vec<SelectionStep>,
    /// Every candidate's evidence, in dataset column order.
    pub candidates: Vec<CandidateEvidence>,
    /// Score with every candidate at once, µm.
    pub all_score_um: f64,
    /// Number of thermal error channels used.
    pub n_channels: usize,
    /// Channels dropped as carrying no predictable thermal signal.
    pub n_channels_dropped: usize,
    /// Number of rows used (blocks + spindle records).
    pub n_rows: usize,
    /// The candidate sets proposed by each rule ([`Rule`]), ranked with evidence.
    pub proposals: Vec<Proposal>,
}

impl Selection {
    /// Reference sensors followed by those of the linear forward selection ([`Selection::steps`]).
    pub fn sensor_names(&self) -> Vec<String> {
        self.reference
            .iter()
            .cloned()
            .chain(self.steps.iter().map(|s| s.name.clone()))
            .collect()
    }
}

/// A prepared dataset: the row groups, ready for scoring sensor subsets.
#[derive(Debug, Clone)]
pub struct SelectionData {
    names: Vec<String>,
    groups: Vec<Group>,
    n_cycles: usize,
    ridge: f64,
}

impl SelectionData {
    /// Groups `ds` into blocks and spindle rows (see the module doc).
    ///
    /// # Errors
    /// [`SelectionError::TooFewCycles`], [`SelectionError::NoChannels`].
    pub fn new(ds: &Dataset, cfg: &SelectionConfig) -> Result<Self, SelectionError> {
        let mut cycles: Vec<&str> = Vec::new();
        for r in &ds.records {
            if !cycles.contains(&r.cycle.as_str()) {
                cycles.push(&r.cycle);
            }
        }
        if cycles.len() < 2 {
            return Err(SelectionError::TooFewCycles(cycles.len()));
        }
        let cycle_of = |name: &str| cycles.iter().position(|c| *c == name).unwrap_or(0);
        let k = ds.sensor_names.len();
        let arm_um_per_urad = cfg.arm_mm * 1e-3;
        let mut groups = Vec::new();

        // Blocks of laser and squareness readings.
        struct Block {
            cycle: usize,
            temps: Vec<f64>,
            n: usize,
            values: Vec<(String, f64)>,
            last_t: f64,
        }
        let mut blocks: Vec<Block> = Vec::new();
        for r in &ds.records {
            let axis = match r.instrument {
                Instrument::LaserX => Some(0),
                Instrument::LaserY => Some(1),
                Instrument::LaserZ => Some(2),
                Instrument::Squareness => None,
                Instrument::Spindle | Instrument::Volumetric => continue,
            };
            let c = cycle_of(&r.cycle);
            let new_block = match blocks.last() {
                Some(b) => b.cycle != c || r.time_s - b.last_t > cfg.block_gap_s,
                None => true,
            };
            if new_block {
                blocks.push(Block {
                    cycle: c,
                    temps: vec![0.0; k],
                    n: 0,
                    values: Vec::new(),
                    last_t: r.time_s,
                });
            }
            let b = blocks.last_mut().expect("pushed above");
            b.last_t = r.time_s;
            b.n += 1;
            for (s, t) in b.temps.iter_mut().zip(&r.temps_degc) {
                *s += t;
            }
            for (i, v) in r.values.iter().enumerate() {
                if !v.is_finite() {
                    continue;
                }
                let v = if i >= 3 { v * arm_um_per_urad } else { *v };
                let key = match axis {
                    Some(a) => format!(
                        "{}@{:.1}:{}",
                        r.instrument.name(),
                        r.pos_mm[a],
                        COMPONENTS[i]
                    ),
                    None => format!("{}:{}", r.instrument.name(), COMPONENTS[i]),
                };
                b.values.push((key, v));
            }
        }
        if !blocks.is_empty() {
            // Channels measured in every block (first occurrence in a block counts).
            let mut channels: Vec<String> = Vec::new();
            for (key, _) in &blocks[0].values {
                if !channels.contains(key)
                    && blocks
                        .iter()
                        .all(|b| b.values.iter().any(|(k2, _)| k2 == key))
                {
                    channels.push(key.clone());
                }
            }
            if !channels.is_empty() {
                let rows = blocks.len();
                let temps =
                    DMatrix::from_fn(rows, k, |i, j| blocks[i].temps[j] / blocks[i].n as f64);
                let values = DMatrix::from_fn(rows, channels.len(), |i, j| {
                    blocks[i]
                        .values
                        .iter()
                        .find(|(key, _)| *key == channels[j])
                        .map_or(f64::NAN, |(_, v)| *v)
                });
                groups.push(Group {
                    temps,
                    values,
                    cycle: blocks.iter().map(|b| b.cycle).collect(),
                    channels,
                });
            }
        }

        // Spindle records: one row each.
        let spindle: Vec<_> = ds
            .records
            .iter()
            .filter(|r| r.instrument == Instrument::Spindle)
            .collect();
        if !spindle.is_empty() {
            let comps: Vec<usize> = (0..6)
                .filter(|&i| spindle.iter().all(|r| r.values[i].is_finite()))
                .collect();
            if !comps.is_empty() {
                let temps = DMatrix::from_fn(spindle.len(), k, |i, j| spindle[i].temps_degc[j]);
                let values = DMatrix::from_fn(spindle.len(), comps.len(), |i, j| {
                    let c = comps[j];
                    let v = spindle[i].values[c];
                    if c >= 3 {
                        v * arm_um_per_urad
                    } else {
                        v
                    }
                });
                groups.push(Group {
                    temps,
                    values,
                    cycle: spindle.iter().map(|r| cycle_of(&r.cycle)).collect(),
                    channels: comps
                        .iter()
                        .map(|&c| format!("spindle:{}", COMPONENTS[c]))
                        .collect(),
                });
            }
        }
        if groups.is_empty() {
            return Err(SelectionError::NoChannels);
        }
        Ok(Self {
            names: ds.sensor_names.clone(),
            groups,
            n_cycles: cycles.len(),
            ridge: cfg.ridge,
        })
    }

    /// Candidate (column) names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Leave-one-cycle-out score of the sensor columns `cols`, µm (see the module doc).
    pub fn score_um(&self, cols: &[usize]) -> f64 {
        // Mean MSE per error component (instrument + component, all positions together), then
        // the RMS over components: a positioning error read at 15 positions counts once, as
        // much as a spindle drift read at one.
        let mut comps: Vec<(String, f64, usize)> = Vec::new();
        for (g, mse) in self.groups.iter().zip(self.channel_mse(cols)) {
            for (name, m) in g.channels.iter().zip(mse) {
                let key = component_of(name);
                match comps.iter_mut().find(|(k, _, _)| *k == key) {
                    Some(c) => {
                        c.1 += m;
                        c.2 += 1;
                    }
                    None => comps.push((key, m, 1)),
                }
            }
        }
        if comps.is_empty() {
            return f64::NAN;
        }
        let sum: f64 = comps.iter().map(|(_, m, n)| m / *n as f64).sum();
        (sum / comps.len() as f64).sqrt()
    }

    /// Keeps only the channels that `cols` predict with a cross-validated R² ≥ `min_r2`;
    /// returns how many were dropped.
    fn keep_predictable_channels(&mut self, cols: &[usize], min_r2: f64) -> usize {
        let mse = self.channel_mse(cols);
        let mut dropped = 0;
        for (g, mse) in self.groups.iter_mut().zip(mse) {
            let n = g.values.nrows() as f64;
            let keep: Vec<usize> = (0..g.values.ncols())
                .filter(|&c| {
                    let col = g.values.column(c);
                    let mean = col.iter().sum::<f64>() / n;
                    let var = col.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
                    var > 0.0 && 1.0 - mse[c] / var >= min_r2
                })
                .collect();
            dropped += g.values.ncols() - keep.len();
            g.values = g.values.select_columns(keep.iter());
            g.channels = keep.iter().map(|&c| g.channels[c].clone()).collect();
        }
        self.groups.retain(|g| g.values.ncols() > 0);
        dropped
    }

    /// Leave-one-cycle-out mean squared error of each channel (per group), µm².
    fn channel_mse(&self, cols: &[usize]) -> Vec<Vec<f64>> {
        let mut out = Vec::with_capacity(self.groups.len());
        for g in &self.groups {
            let m = g.values.ncols();
            let mut err_sq = vec![0.0; m];
            let mut count = 0usize;
            for fold in 0..self.n_cycles {
                let train: Vec<usize> =
                    (0..g.cycle.len()).filter(|&i| g.cycle[i] != fold).collect();
                let test: Vec<usize> = (0..g.cycle.len()).filter(|&i| g.cycle[i] == fold).collect();
                if test.is_empty() || train.len() < 2 {
                    continue;
                }
                let pred = ridge_fit_predict(g, cols, &train, &test, self.ridge);
                for (ti, &row) in test.iter().enumerate() {
                    for (c, e) in err_sq.iter_mut().enumerate() {
                        let d = pred[(ti, c)] - g.values[(row, c)];
                        *e += d * d;
                    }
                }
                count += test.len();
            }
            if count == 0 {
                continue;
            }
            out.push(err_sq.into_iter().map(|e| e / count as f64).collect());
        }
        out
    }

    /// Pearson correlation of two candidate columns over the densest group's rows.
    fn temp_corr(&self, a: usize, b: usize) -> f64 {
        let g = self
            .groups
            .iter()
            .max_by_key(|g| g.temps.nrows())
            .expect("at least one group");
        pearson(g.temps.column(a).iter(), g.temps.column(b).iter())
    }

    /// Strongest |r| of column `a` with any channel, and that channel.
    fn best_channel_corr(&self, a: usize) -> (f64, String) {
        let mut best = (0.0, String::new());
        for g in &self.groups {
            for (c, name) in g.channels.iter().enumerate() {
                let r = pearson(g.temps.column(a).iter(), g.values.column(c).iter()).abs();
                if r.is_finite() && r > best.0 {
                    best = (r, name.clone());
                }
            }
        }
        best
    }
}

/// The error component of a channel name: `laser_x@160.0:dx_um` → `laser_x:dx_um` (the
/// position dropped); other names are components already.
fn component_of(channel: &str) -> String {
    match (channel.find('@'), channel.find(':')) {
        (Some(at), Some(colon)) if at < colon => format!("{}{}", &channel[..at], &channel[colon..]),
        _ => channel.to_string(),
    }
}

const COMPONENTS: [&str; 6] = ["dx_um", "dy_um", "dz_um", "rx_urad", "ry_urad", "rz_urad"];

/// Pearson correlation; 0 when either side is constant.
fn pearson<'a>(
    a: impl Iterator<Item = &'a f64> + Clone,
    b: impl Iterator<Item = &'a f64> + Clone,
) -> f64 {
    let n = a.clone().count() as f64;
    if n < 2.0 {
        return 0.0;
    }
    let ma = a.clone().sum::<f64>() / n;
    let mb = b.clone().sum::<f64>() / n;
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    if saa <= 0.0 || sbb <= 0.0 {
        return 0.0;
    }
    sab / (saa * sbb).sqrt()
}

/// Fits `values ≈ a + B·temps[cols]` on `train` rows (ridge on standardised inputs) and predicts
/// `test` rows.
fn ridge_fit_predict(
    g: &Group,
    cols: &[usize],
    train: &[usize],
    test: &[usize],
    ridge: f64,
) -> DMatrix<f64> {
    let k = cols.len();
    let m = g.values.ncols();
    let n = train.len() as f64;
    let mut mean_x = vec![0.0; k];
    let mut sd_x = vec![0.0; k];
    for (j, &c) in cols.iter().enumerate() {
        mean_x[j] = train.iter().map(|&i| g.temps[(i, c)]).sum::<f64>() / n;
        let var = train
            .iter()
            .map(|&i| (g.temps[(i, c)] - mean_x[j]).powi(2))
            .sum::<f64>()
            / n;
        sd_x[j] = if var > 0.0 { var.sqrt() } else { 1.0 };
    }
    let mean_y: Vec<f64> = (0..m)
        .map(|c| train.iter().map(|&i| g.values[(i, c)]).sum::<f64>() / n)
        .collect();
    let x = DMatrix::from_fn(train.len(), k, |r, j| {
        (g.temps[(train[r], cols[j])] - mean_x[j]) / sd_x[j]
    });
    let y = DMatrix::from_fn(train.len(), m, |r, c| g.values[(train[r], c)] - mean_y[c]);
    let mut a = x.transpose() * &x;
    for j in 0..k {
        a[(j, j)] += ridge * n + 1e-12;
    }
    let b = x.transpose() * &y;
    let w = match a.cholesky() {
        Some(ch) => ch.solve(&b),
        None => DMatrix::zeros(k, m),
    };
    let xt = DMatrix::from_fn(test.len(), k, |r, j| {
        (g.temps[(test[r], cols[j])] - mean_x[j]) / sd_x[j]
    });
    let mut pred = xt * w;
    let my = DVector::from_vec(mean_y);
    for mut row in pred.row_iter_mut() {
        row += my.transpose();
    }
    pred
}

/// Runs the selection on `ds` (see the module doc).
///
/// # Errors
/// [`SelectionError`] when the dataset cannot support it.
pub fn select_sensors(ds: &Dataset, cfg: &SelectionConfig) -> Result<Selection, SelectionError> {
    let mut data = SelectionData::new(ds, cfg)?;
    let names = data.names.clone();
    let all: Vec<usize> = (0..names.len()).collect();
    let n_channels_dropped = data.keep_predictable_channels(&all, cfg.min_channel_r2);
    if data.groups.is_empty() {
        return Err(SelectionError::NoChannels);
    }
    let mut chosen: Vec<usize> = Vec::new();
    for r in &cfg.reference {
        let i = names
            .iter()
            .position(|n| n == r)
            .ok_or_else(|| SelectionError::UnknownReference(r.clone()))?;
        chosen.push(i);
    }
    let reference_score_um = data.score_um(&chosen);
    let all_score_um = data.score_um(&all);

    // Clusters of mutually redundant candidates (complete linkage at the threshold).
    let mut clusters: Vec<Vec<usize>> = Vec::new();
    let mut cluster_of = Vec::with_capacity(names.len());
    for i in 0..names.len() {
        let found = clusters.iter().position(|cl| {
            cl.iter()
                .all(|&j| data.temp_corr(i, j).abs() >= cfg.redundancy_corr)
        });
        let c = found.unwrap_or(clusters.len());
        if c == clusters.len() {
            clusters.push(Vec::new());
        }
        clusters[c].push(i);
        cluster_of.push(c);
    }
    let candidates: Vec<CandidateEvidence> = (0..names.len())
        .map(|i| {
            let (max_abs_corr, best_channel) = data.best_channel_corr(i);
            let mut with = chosen.clone();
            if !with.contains(&i) {
                with.push(i);
            }
            CandidateEvidence {
                name: names[i].clone(),
                cluster: cluster_of[i],
                max_abs_corr,
                best_channel,
                alone_score_um: data.score_um(&with),
            }
        })
        .collect();

    let mut steps = Vec::new();
    let mut score = reference_score_um;
    let mut phase = Phase::Information;
    while steps.len() < cfg.count {
        let eligible: Vec<usize> = (0..names.len())
            .filter(|i| !chosen.contains(i))
            .filter(|&i| {
                chosen
                    .iter()
                    .all(|&j| data.temp_corr(i, j).abs() < cfg.redundancy_corr)
            })
            .collect();
        let scored: Vec<(usize, f64)> = eligible
            .iter()
            .map(|&i| {
                let mut with = chosen.clone();
                with.push(i);
                (i, data.score_um(&with))
            })
            .collect();
        let Some(&(best_i, best_s)) = scored.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
            return Err(SelectionError::NotEnoughCandidates {
                asked: cfg.count,
                available: eligible.len(),
                chosen: steps.len(),
            });
        };
        if phase == Phase::Information
            && score - best_s < cfg.min_gain_fraction * reference_score_um
        {
            phase = Phase::Coverage;
        }
        let (i, s) = match phase {
            Phase::Information => (best_i, best_s),
            // Coverage: the candidate whose strongest correlation with a chosen sensor is the
            // weakest. (Max relevance − redundancy was tried instead and measured worse on
            // held-out compensation: it piles sensors on the spindle, whose drift is covered.)
            Phase::Coverage => {
                let relevant: Vec<&(usize, f64)> = scored
                    .iter()
                    .filter(|(i, _)| candidates[*i].max_abs_corr >= cfg.min_relevance)
                    .collect();
                let pool: Vec<&(usize, f64)> = if relevant.is_empty() {
                    scored.iter().collect()
                } else {
                    relevant
                };
                let redundancy = |i: usize| {
                    chosen
                        .iter()
                        .map(|&j| data.temp_corr(i, j).abs())
                        .fold(0.0, f64::max)
                };
                **pool
                    .iter()
                    .min_by(|a, b| redundancy(a.0).total_cmp(&redundancy(b.0)))
                    .expect("scored is not empty")
            }
        };
        chosen.push(i);
        steps.push(SelectionStep {
            name: names[i].clone(),
            score_um: s,
            gain_um: score - s,
            phase,
        });
        score = s;
    }
    let reference: Vec<usize> = chosen[..cfg.reference.len()].to_vec();
    let pool: Vec<usize> = (0..names.len())
        .filter(|i| !reference.contains(i))
        .collect();
    let relevance: Vec<f64> = candidates.iter().map(|c| c.max_abs_corr).collect();
    let proposals = proposals::build(
        &data,
        &reference,
        &pool,
        &relevance,
        &chosen[reference.len()..],
        cfg.count,
    );
    Ok(Selection {
        proposals,
        reference: cfg.reference.clone(),
        reference_score_um,
        steps,
        candidates,
        all_score_um,
        n_channels: data.groups.iter().map(|g| g.values.ncols()).sum(),
        n_channels_dropped,
        n_rows: data.groups.iter().map(|g| g.values.nrows()).sum(),
    })
}

#[cfg(test)]
mod tests;
