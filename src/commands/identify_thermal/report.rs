//! The printed report of `identify-thermal`.

use std::fmt::Write as _;

use super::{rmse, BlackBox, Columns, Fold, GreyBoxFolds, IdentifyThermalConfig};
use crate::predict::rc_identify::{Mode, RcFit};
use crate::predict::thermal_fit::Table;

/// What the report needs besides the fits.
pub(super) struct Context<'a> {
    pub cfg: &'a IdentifyThermalConfig,
    pub source: &'a str,
    pub table: &'a Table,
    pub cols: &'a Columns<'a>,
    pub folds: &'a [Fold],
    pub note: &'a str,
}

fn raw_rms(y: &[f64], rows: &[usize]) -> f64 {
    (rows.iter().map(|&r| y[r] * y[r]).sum::<f64>() / rows.len().max(1) as f64).sqrt()
}

fn pct(v: Option<f64>) -> String {
    v.filter(|v| v.is_finite())
        .map(|v| format!("{:.1} %", 100.0 * v))
        .unwrap_or_else(|| "-".into())
}

/// The network's parameters in one line.
pub(super) fn network_line(fit: &RcFit) -> String {
    let n = &fit.network;
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.4e}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    format!(
        "C = [{}] J/K, links G = [{}] W/K, to ambient H = [{}] W/K, γ = {:.4} per 1000 rpm, \
         heat a = {:.4} W per 1000 rpm, b = {:.4} W per (1000 rpm)² ({:.1} W at 5000 rpm)",
        list(&n.capacity_j_per_k),
        list(&n.link_w_per_k),
        list(&n.ambient_w_per_k),
        n.ha_gain_per_krpm,
        n.heat_w_per_krpm,
        n.heat_w_per_krpm2,
        n.heat_w(5000.0)
    )
}

/// The whole report.
pub(super) fn text(
    ctx: &Context,
    grey: &GreyBoxFolds,
    finals: &[RcFit],
    black: Option<&BlackBox>,
) -> String {
    let (cfg, t) = (ctx.cfg, &ctx.table.time_s);
    let mut s = String::new();
    let s_ = &cfg.settings;
    let anchors: Vec<String> = cfg
        .node_temps
        .iter()
        .enumerate()
        .map(|(i, c)| format!("node {i} ← {c}"))
        .collect();
    let _ = writeln!(
        s,
        "identify-thermal: {}, {} rows ({}–{} s); speed \"{}\"; {} drift channels; network: {} \
         node(s) in a chain, heat a·k + b·k² (k = speed/1000 rpm) into node 0, {}; node 0's \
         capacity fixed at {} J/K; node temperatures fitted: {}; ambient: {}",
        ctx.source,
        t.len(),
        t.first().copied().unwrap_or(0.0),
        t.last().copied().unwrap_or(0.0),
        cfg.rpm,
        cfg.drifts.len(),
        s_.nodes,
        if s_.speed_convection {
            "node 0's convection growing with speed (γ fitted)"
        } else {
            "convection independent of speed"
        },
        s_.node0_capacity_j_per_k,
        if anchors.is_empty() {
            "none (the temperature scale is not identified)".to_string()
        } else {
            anchors.join(", ")
        },
        cfg.ambient
            .as_deref()
            .map_or("constant".to_string(), |a| format!("column \"{a}\"")),
    );
    let _ = writeln!(s, "folds: {}", ctx.note);
    let _ = writeln!(
        s,
        "held out (ratio = residual RMS / raw drift RMS of the held-out rows): grey speed = the \
         network from the speed profile alone{}; grey temps = the same plus the rises of {}; \
         black-box = fit-thermal's chosen form{}; plainLS = least squares on the raw inputs",
        if cfg.ambient.is_some() {
            " and the ambient"
        } else {
            ""
        },
        if cfg.temps.is_empty() {
            "(no --temps)".to_string()
        } else {
            cfg.temps.join(", ")
        },
        black
            .map(|b| format!(
                " ({}) on {}",
                b.forms.join(", "),
                cfg.baseline
                    .as_ref()
                    .map(|(i, _)| i.join(","))
                    .unwrap_or_default()
            ))
            .unwrap_or_else(|| " (skipped)".into()),
    );
    let _ = writeln!(
        s,
        "  {:<22} {:<10} {:>9} {:>11} {:>11} {:>11} {:>11}",
        "fold", "channel", "raw RMS", "grey speed", "grey temps", "black-box", "plainLS"
    );
    let n_ch = cfg.drifts.len();
    let mut sums = vec![[0.0f64; 4]; n_ch];
    let mut counts = vec![[0usize; 4]; n_ch];
    for (i, f) in ctx.folds.iter().enumerate() {
        for k in 0..n_ch {
            let raw = raw_rms(&ctx.cols.drifts[k], &f.test);
            let r = |e: Option<f64>| e.map(|e| e / raw);
            let vals = [
                r(grey.rmse[i][0].as_ref().map(|v| v[k])),
                r(grey.rmse[i][1].as_ref().map(|v| v[k])),
                r(black.and_then(|b| b.rmse.get(i)).map(|v| v[k].0)),
                r(black.and_then(|b| b.rmse.get(i)).and_then(|v| v[k].1)),
            ];
            for (j, v) in vals.iter().enumerate() {
                if let Some(v) = v.filter(|v| v.is_finite()) {
                    sums[k][j] += v;
                    counts[k][j] += 1;
                }
            }
            let _ = writeln!(
                s,
                "  {:<22} {:<10} {:>9.3} {:>11} {:>11} {:>11} {:>11}",
                if k == 0 { f.label.as_str() } else { "" },
                cfg.drifts[k],
                raw,
                pct(vals[0]),
                pct(vals[1]),
                pct(vals[2]),
                pct(vals[3])
            );
        }
    }
    for k in 0..n_ch {
        let m = |j: usize| (counts[k][j] > 0).then(|| sums[k][j] / counts[k][j] as f64);
        let _ = writeln!(
            s,
            "  {:<22} {:<10} {:>9} {:>11} {:>11} {:>11} {:>11}",
            if k == 0 { "mean over folds" } else { "" },
            cfg.drifts[k],
            "",
            pct(m(0)),
            pct(m(1)),
            pct(m(2)),
            pct(m(3))
        );
    }
    for note in &grey.bound_notes {
        let _ = writeln!(s, "  parameters held at a bound: {note}");
    }
    for fit in finals {
        fit_on_every_row(&mut s, ctx, fit);
    }
    s
}

/// The fit on every row: per fold's rows, the in-sample ratio; the network and gains.
fn fit_on_every_row(s: &mut String, ctx: &Context, fit: &RcFit) {
    let data = ctx.cols.data(&ctx.table.time_s);
    let Ok(pred) = fit.predict(&data) else {
        return;
    };
    let _ = writeln!(
        s,
        "fitted on every row, {} ({} Levenberg–Marquardt iterations, cost {:.4e}): per cycle, \
         ratio of each channel",
        fit.mode.name(),
        fit.iterations,
        fit.cost
    );
    for f in ctx.folds {
        let e = rmse(&ctx.cols.drifts, &pred, &f.test);
        let line: Vec<String> = e
            .iter()
            .zip(&ctx.cols.drifts)
            .zip(&ctx.cfg.drifts)
            .map(|((e, y), name)| format!("{name} {}", pct(Some(e / raw_rms(y, &f.test)))))
            .collect();
        let _ = writeln!(s, "  {:<22} {}", f.label, line.join("  "));
    }
    if fit.mode == Mode::SpeedOnly {
        let _ = writeln!(s, "  network: {}", network_line(fit));
    }
    let names = fit.regressor_names();
    for (k, g) in fit.gains.iter().enumerate() {
        let terms: Vec<String> = names
            .iter()
            .zip(g)
            .map(|(n, g)| {
                let n = match n.strip_prefix('θ').and_then(|j| j.parse::<usize>().ok()) {
                    Some(j) => ctx.cfg.temps.get(j).cloned().unwrap_or_else(|| n.clone()),
                    None => n.clone(),
                };
                format!("{n} {g:.4}")
            })
            .collect();
        let _ = writeln!(
            s,
            "  gains {}: {}",
            ctx.cfg.drifts.get(k).map_or("", String::as_str),
            terms.join(", ")
        );
    }
    if !fit.at_bounds.is_empty() || !fit.hit_bounds.is_empty() {
        let _ = writeln!(
            s,
            "  parameters held at a bound (the data pushed them out of the allowed range): {}; \
             cut back to a bound during the fit: {}",
            if fit.at_bounds.is_empty() {
                "none".to_string()
            } else {
                fit.at_bounds.join(", ")
            },
            if fit.hit_bounds.is_empty() {
                "none".to_string()
            } else {
                fit.hit_bounds.join(", ")
            }
        );
    }
}
