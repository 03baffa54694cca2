//! The fit: parameter layout and bounds, variable projection of the drift gains, projected
//! Levenberg–Marquardt from several starting points.

use nalgebra::{DMatrix, DVector};

use super::{Mode, RcData, RcError, RcFit, RcNetwork, RcSettings};

/// Regressor columns of every row (offset, node rises, ambient rise, measured rises) and the
/// simulated node rises.
pub(super) struct Regressors {
    /// Columns, in the order of [`RcFit::regressor_names`].
    pub cols: Vec<Vec<f64>>,
    /// Node rises above the first ambient reading, one column per node.
    pub rises: Vec<Vec<f64>>,
}

/// The regressors of `net` on `data` in `mode`.
pub(super) fn regressors(net: &RcNetwork, data: &RcData, mode: Mode) -> Regressors {
    let n = data.time_s.len();
    let zeros;
    let amb = match data.ambient_degc {
        Some(a) => a,
        None => {
            zeros = vec![0.0; n];
            &zeros
        }
    };
    let a0 = amb.first().copied().unwrap_or(0.0);
    let rises: Vec<Vec<f64>> = net
        .simulate(data.time_s, data.rpm, amb)
        .into_iter()
        .map(|c| c.into_iter().map(|t| t - a0).collect())
        .collect();
    let rise_of = |v: &[f64]| -> Vec<f64> {
        let v0 = v.first().copied().unwrap_or(0.0);
        v.iter().map(|t| t - v0).collect()
    };
    let mut cols = vec![vec![1.0; n]];
    cols.extend(rises.iter().cloned());
    if let Some(a) = data.ambient_degc {
        cols.push(rise_of(a));
    }
    if mode == Mode::WithTemps {
        cols.extend(data.temps.iter().map(|t| rise_of(t)));
    }
    Regressors { cols, rises }
}

/// Checks the columns (and `rows`, if given).
pub(super) fn check_rows(data: &RcData, rows: Option<&[usize]>) -> Result<(), RcError> {
    let n = data.time_s.len();
    let lens_ok = data.rpm.len() == n
        && data.ambient_degc.is_none_or(|a| a.len() == n)
        && data.drifts.iter().all(|d| d.len() == n || d.is_empty())
        && data.node_temps.iter().flatten().all(|t| t.len() == n)
        && data.temps.iter().all(|t| t.len() == n);
    if !lens_ok || n < 2 {
        return Err(RcError::BadData(format!(
            "need equally long columns and at least 2 rows ({n} rows)"
        )));
    }
    if let Some(rows) = rows {
        if rows.len() < 10 || rows.iter().any(|&r| r >= n) {
            return Err(RcError::BadData(format!(
                "need at least 10 fitting rows within the {n} rows, got {}",
                rows.len()
            )));
        }
    }
    if let Some(r) = (1..n).find(|&r| {
        data.time_s[r].partial_cmp(&data.time_s[r - 1]) != Some(std::cmp::Ordering::Greater)
    }) {
        return Err(RcError::BadData(format!(
            "time must increase strictly (row {r}: {} s after {} s)",
            data.time_s[r],
            data.time_s[r - 1]
        )));
    }
    if let Some(row) = data.rpm.iter().position(|v| *v < 0.0) {
        return Err(RcError::NegativeSpeed {
            row,
            rpm: data.rpm[row],
        });
    }
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite() && (x * x).is_finite());
    let all_finite = finite(data.time_s)
        && finite(data.rpm)
        && data.ambient_degc.is_none_or(finite)
        && data.drifts.iter().all(|d| finite(d))
        && data.node_temps.iter().flatten().all(|t| finite(t))
        && data.temps.iter().all(|t| finite(t));
    if !all_finite {
        return Err(RcError::BadData(
            "a value is not finite (or too large to square)".into(),
        ));
    }
    Ok(())
}

/// How each parameter of the vector is transformed.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// Stored as its logarithm.
    Log,
    /// Stored as is.
    Plain,
}

/// The free parameters: names, transforms and bounds (in the transformed space).
struct Layout {
    nodes: usize,
    convection: bool,
    c0: f64,
    names: Vec<String>,
    lo: Vec<f64>,
    hi: Vec<f64>,
    /// Bounds in natural units (for the exponentials of log-parameters, which may round
    /// past them).
    nat: Vec<[f64; 2]>,
}

impl Layout {
    fn new(s: &RcSettings) -> Self {
        let (mut names, mut lo, mut hi, mut nat) = (vec![], vec![], vec![], vec![]);
        let b = &s.bounds;
        let mut push = |name: String, kind: Kind, [l, h]: [f64; 2]| {
            names.push(name);
            nat.push([l, h]);
            let (l, h) = match kind {
                Kind::Log => (l.ln(), h.ln()),
                Kind::Plain => (l, h),
            };
            lo.push(l);
            hi.push(h);
        };
        for i in 1..s.nodes {
            push(format!("C{i}"), Kind::Log, b.capacity_j_per_k);
        }
        for i in 0..s.nodes - 1 {
            push(format!("G{i}{}", i + 1), Kind::Log, b.conductance_w_per_k);
        }
        for i in 0..s.nodes {
            push(format!("H{i}"), Kind::Log, b.conductance_w_per_k);
        }
        push("a".into(), Kind::Plain, b.heat_w);
        push("b".into(), Kind::Plain, b.heat_w);
        if s.speed_convection {
            push("gamma".into(), Kind::Plain, b.ha_gain_per_krpm);
        }
        Self {
            nodes: s.nodes,
            convection: s.speed_convection,
            c0: s.node0_capacity_j_per_k,
            names,
            lo,
            hi,
            nat,
        }
    }

    fn pack(&self, net: &RcNetwork) -> Vec<f64> {
        let mut p: Vec<f64> = net.capacity_j_per_k[1..]
            .iter()
            .chain(&net.link_w_per_k)
            .chain(&net.ambient_w_per_k)
            .map(|v| v.ln())
            .collect();
        p.push(net.heat_w_per_krpm);
        p.push(net.heat_w_per_krpm2);
        if self.convection {
            p.push(net.ha_gain_per_krpm);
        }
        self.clamp(p).0
    }

    fn unpack(&self, p: &[f64]) -> RcNetwork {
        let n = self.nodes;
        let e = |from: usize, to: usize| {
            (from..to)
                .map(|j| p[j].exp().clamp(self.nat[j][0], self.nat[j][1]))
                .collect::<Vec<_>>()
        };
        let mut capacity = vec![self.c0];
        capacity.extend(e(0, n - 1));
        let links = e(n - 1, 2 * n - 2);
        let ambient = e(2 * n - 2, 3 * n - 2);
        RcNetwork {
            capacity_j_per_k: capacity,
            link_w_per_k: links,
            ambient_w_per_k: ambient,
            heat_w_per_krpm: p[3 * n - 2],
            heat_w_per_krpm2: p[3 * n - 1],
            ha_gain_per_krpm: if self.convection { p[3 * n] } else { 0.0 },
        }
    }

    /// `p` cut back into the box, and the indices that were cut.
    fn clamp(&self, mut p: Vec<f64>) -> (Vec<f64>, Vec<usize>) {
        let mut cut = Vec::new();
        for (j, v) in p.iter_mut().enumerate() {
            if *v < self.lo[j] || *v > self.hi[j] {
                *v = v.clamp(self.lo[j], self.hi[j]);
                cut.push(j);
            }
        }
        (p, cut)
    }

    /// Names of the parameters on a bound (within 1e-9 of its width in the transformed space).
    fn on_bounds(&self, p: &[f64]) -> Vec<String> {
        (0..p.len())
            .filter(|&j| {
                let tol = 1e-9 * (self.hi[j] - self.lo[j]).abs().max(1.0);
                (p[j] - self.lo[j]).abs() <= tol || (self.hi[j] - p[j]).abs() <= tol
            })
            .map(|j| self.names[j].clone())
            .collect()
    }
}

/// The problem on some rows: data, rows, scales and mode.
struct Problem<'a> {
    data: &'a RcData<'a>,
    rows: &'a [usize],
    /// Per drift channel, then per anchored node.
    scales: Vec<f64>,
    mode: Mode,
    layout: Layout,
}

impl Problem<'_> {
    /// Scaled residuals and the drift gains of the network `p`, None if not finite.
    fn residuals(&self, p: &[f64]) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
        let net = self.layout.unpack(p);
        let x = regressors(&net, self.data, self.mode);
        let rows = self.rows;
        let m = x.cols.len();
        // Columns scaled to unit RMS for the conditioning of the solve.
        let norms: Vec<f64> = x
            .cols
            .iter()
            .map(|c| {
                let s = (rows.iter().map(|&r| c[r] * c[r]).sum::<f64>() / rows.len() as f64).sqrt();
                if s > 1e-300 && s.is_finite() {
                    s
                } else {
                    1.0
                }
            })
            .collect();
        let xm = DMatrix::from_fn(rows.len(), m, |i, j| x.cols[j][rows[i]] / norms[j]);
        let svd = xm.clone().svd(true, true);
        let tol = 1e-11 * svd.singular_values.max();
        let mut res = Vec::with_capacity(rows.len() * (self.data.drifts.len() + 1));
        let mut gains = Vec::with_capacity(self.data.drifts.len());
        for (k, d) in self.data.drifts.iter().enumerate() {
            let y = DVector::from_iterator(rows.len(), rows.iter().map(|&r| d[r]));
            let c = svd.solve(&y, tol).ok()?;
            let fit = &xm * &c;
            res.extend((0..rows.len()).map(|i| (y[i] - fit[i]) / self.scales[k]));
            gains.push(c.iter().zip(&norms).map(|(c, s)| c / s).collect());
        }
        let mut s = self.data.drifts.len();
        for (i, t) in self.data.node_temps.iter().enumerate() {
            if let (Some(t), Some(rise)) = (t, x.rises.get(i)) {
                res.extend(
                    rows.iter()
                        .map(|&r| (rise[r] - (t[r] - t[0])) / self.scales[s]),
                );
                s += 1;
            }
        }
        res.iter().all(|v| v.is_finite()).then_some((res, gains))
    }
}

/// One Levenberg–Marquardt run from `p` (at most `max_iter` iterations).
struct Run {
    p: Vec<f64>,
    cost: f64,
    gains: Vec<Vec<f64>>,
    iterations: usize,
    hit: Vec<usize>,
}

fn levenberg_marquardt(prob: &Problem, p: Vec<f64>, max_iter: usize) -> Option<Run> {
    let (r0, g0) = prob.residuals(&p)?;
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut run = Run {
        cost: cost(&r0),
        p,
        gains: g0,
        iterations: 0,
        hit: Vec::new(),
    };
    let mut r0 = r0;
    let mut mu = 1e-3;
    let np = run.p.len();
    for _ in 0..max_iter {
        if run.cost < 1e-28 {
            break;
        }
        run.iterations += 1;
        // Forward-difference Jacobian (backward at an upper bound).
        let m = r0.len();
        let mut jac = DMatrix::<f64>::zeros(m, np);
        for j in 0..np {
            let mut h = 1e-7 * run.p[j].abs().max(1.0);
            if run.p[j] + h > prob.layout.hi[j] {
                h = -h;
            }
            let mut q = run.p.clone();
            q[j] += h;
            let Some((rj, _)) = prob.residuals(&q) else {
                continue;
            };
            for i in 0..m {
                jac[(i, j)] = (rj[i] - r0[i]) / h;
            }
        }
        let jt = jac.transpose();
        let jtj = &jt * &jac;
        let g = &jt * DVector::from_column_slice(&r0);
        let mut improved = false;
        let mut converged = false;
        for _ in 0..16 {
            let mut a = jtj.clone();
            for d in 0..np {
                a[(d, d)] += mu * jtj[(d, d)].max(1e-12);
            }
            let Some(step) = a.lu().solve(&(-&g)) else {
                mu *= 10.0;
                continue;
            };
            let trial: Vec<f64> = run.p.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            let (q, cut) = prob.layout.clamp(trial);
            match prob.residuals(&q) {
                Some((r, gains)) if cost(&r) < run.cost => {
                    let c = cost(&r);
                    let moved = q
                        .iter()
                        .zip(&run.p)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max);
                    converged = run.cost - c <= 1e-14 * run.cost || moved < 1e-13;
                    for j in cut {
                        if !run.hit.contains(&j) {
                            run.hit.push(j);
                        }
                    }
                    (run.p, run.cost, r0, run.gains) = (q, c, r, gains);
                    mu = (mu / 3.0).max(1e-15);
                    improved = true;
                    break;
                }
                _ => mu *= 10.0,
            }
        }
        if !improved || converged {
            break;
        }
    }
    Some(run)
}

/// The starting networks: node 0's time constant about 10 min, 30 min and 1.5 h, each further
/// node 5 times heavier and slower.
fn starts(s: &RcSettings) -> Vec<RcNetwork> {
    let c0 = s.node0_capacity_j_per_k;
    [600.0, 1800.0, 5400.0]
        .iter()
        .map(|tau| {
            let g = c0 / tau;
            RcNetwork {
                capacity_j_per_k: (0..s.nodes).map(|i| c0 * 5f64.powi(i as i32)).collect(),
                link_w_per_k: vec![0.5 * g; s.nodes - 1],
                ambient_w_per_k: (0..s.nodes).map(|_| 0.5 * g).collect(),
                ha_gain_per_krpm: if s.speed_convection { 0.1 } else { 0.0 },
                heat_w_per_krpm: g,
                heat_w_per_krpm2: 0.2 * g,
            }
        })
        .collect()
}

/// `net` with one more node at the end of the chain: five times the last capacity, the last
/// node's conductance to ambient, linked by a conductance a thousandth of it (within bounds).
fn extended(net: &RcNetwork, bounds: &super::RcBounds) -> RcNetwork {
    let mut n = net.clone();
    let last_c = n.capacity_j_per_k.last().copied().unwrap_or(1.0);
    let last_h = n.ambient_w_per_k.last().copied().unwrap_or(1.0);
    let [lo, hi] = bounds.conductance_w_per_k;
    n.capacity_j_per_k.push(5.0 * last_c);
    n.ambient_w_per_k.push(last_h);
    n.link_w_per_k.push((1e-3 * last_h).clamp(lo * 10.0, hi));
    n
}

/// Standard deviation over `rows` (1 if zero).
fn sd(v: &[f64], rows: &[usize]) -> f64 {
    let n = rows.len().max(1) as f64;
    let m = rows.iter().map(|&r| v[r]).sum::<f64>() / n;
    let s = (rows.iter().map(|&r| (v[r] - m).powi(2)).sum::<f64>() / n).sqrt();
    if s > 0.0 {
        s
    } else {
        1.0
    }
}

/// Identifies the network and the drift gains on `rows` of `data` in `mode` (the simulation
/// runs over every row, so the state carries the history of rows not fitted). Deterministic.
///
/// # Errors
/// [`RcError::BadData`] for inconsistent columns or fewer than 10 fitting rows,
/// [`RcError::NegativeSpeed`], [`RcError::BadSettings`] for a node count outside 1…3 or a
/// non-positive node-0 capacity, [`RcError::Diverged`] when no start gives finite residuals.
pub fn identify(
    data: &RcData,
    rows: &[usize],
    settings: &RcSettings,
    mode: Mode,
) -> Result<RcFit, RcError> {
    if !(1..=3).contains(&settings.nodes) {
        return Err(RcError::BadSettings {
            field: "nodes",
            reason: format!("must be 1, 2 or 3, got {}", settings.nodes),
        });
    }
    let c0 = settings.node0_capacity_j_per_k;
    let b = &settings.bounds;
    if !(c0.is_finite() && c0 > 0.0) {
        return Err(RcError::BadSettings {
            field: "node0_capacity_j_per_k",
            reason: format!("must be > 0, got {c0}"),
        });
    }
    let ok = |[l, h]: [f64; 2], min: f64| l.is_finite() && h.is_finite() && l >= min && h > l;
    if !(ok(b.capacity_j_per_k, f64::MIN_POSITIVE)
        && ok(b.conductance_w_per_k, f64::MIN_POSITIVE)
        && ok(b.heat_w, 0.0)
        && ok(b.ha_gain_per_krpm, 0.0))
    {
        return Err(RcError::BadSettings {
            field: "bounds",
            reason: format!("each must be finite, lower < upper, ≥ 0 (> 0 for logs): {b:?}"),
        });
    }
    if data.drifts.is_empty() {
        return Err(RcError::BadData("no drift channel".into()));
    }
    if data.node_temps.len() > settings.nodes {
        return Err(RcError::BadData(format!(
            "{} node temperatures for {} nodes",
            data.node_temps.len(),
            settings.nodes
        )));
    }
    check_rows(data, Some(rows))?;
    let scales: Vec<f64> = data
        .drifts
        .iter()
        .map(|d| sd(d, rows))
        .chain(data.node_temps.iter().flatten().map(|t| sd(t, rows)))
        .collect();
    let prob = Problem {
        data,
        rows,
        scales,
        mode,
        layout: Layout::new(settings),
    };
    // Nested start: the best network of one node fewer, extended by a weakly linked node (it
    // starts from that fit's predictions, so the larger network fits at least as well).
    let mut starts = starts(settings);
    if settings.nodes > 1 {
        let fewer = RcSettings {
            nodes: settings.nodes - 1,
            ..settings.clone()
        };
        let sub_data = RcData {
            node_temps: &data.node_temps[..data.node_temps.len().min(fewer.nodes)],
            ..*data
        };
        if let Ok(f) = identify(&sub_data, rows, &fewer, mode) {
            starts.push(extended(&f.network, &settings.bounds));
        }
    }
    let best = starts
        .iter()
        .filter_map(|s| levenberg_marquardt(&prob, prob.layout.pack(s), settings.start_iter))
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .ok_or(RcError::Diverged)?;
    let start_iterations = best.iterations;
    let mut hit = best.hit.clone();
    let mut run = levenberg_marquardt(&prob, best.p, settings.max_iter).ok_or(RcError::Diverged)?;
    run.iterations += start_iterations;
    hit.extend(run.hit.iter().filter(|j| !best.hit.contains(j)));
    hit.sort_unstable();
    Ok(RcFit {
        network: prob.layout.unpack(&run.p),
        mode,
        with_ambient: data.ambient_degc.is_some(),
        gains: run.gains,
        iterations: run.iterations,
        cost: run.cost,
        at_bounds: prob.layout.on_bounds(&run.p),
        hit_bounds: hit.iter().map(|&j| prob.layout.names[j].clone()).collect(),
    })
}
