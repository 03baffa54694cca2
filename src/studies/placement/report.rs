//! The placement study's text report and JSON (see [`super`]).

use super::{validation_states, PlacementConfig, PlacementReport, SetResult};
use vmc_machine::machine::MachineSpec;
use vmc_machine::thermal::AMBIENT_NODE;

/// The structural group of a node, from its name (`spindle`, `headstock`, `column`, `x`, …):
/// what the coverage line of the report counts.
fn group_of(name: &str) -> &str {
    name.split('_').next().unwrap_or(name)
}

/// Prints the study: candidates, ranking with evidence, clusters ([`write_selection_part`]),
/// comparison ([`write_comparison`]).
///
/// # Errors
/// Write errors.
pub fn write_report(
    rep: &PlacementReport,
    spec: &MachineSpec,
    cfg: &PlacementConfig,
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    write_selection_part(rep, spec, cfg, out)?;
    write_comparison(&rep.comparison, &cfg.compare_seeds, out)
}

/// Prints the selection stage of the study: candidates, proposals with their validation,
/// ranking with evidence, clusters, coverage, near-copies.
///
/// # Errors
/// Write errors.
pub fn write_selection_part(
    rep: &PlacementReport,
    spec: &MachineSpec,
    cfg: &PlacementConfig,
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    let sel = &rep.selection;
    let t = spec.sensors.iter().find(|s| s.node != AMBIENT_NODE);
    writeln!(
        out,
        "vmc-twin select-sensors on {}: {} candidate locations (thermal nodes + ambient), read as thermistors{}",
        spec.machine.name,
        sel.candidates.len(),
        t.map(|t| format!(
            " (σ {} °C, τ {} s, {} °C steps)",
            t.noise_sigma_degc, t.time_constant_s, t.resolution_degc
        ))
        .unwrap_or_default()
    )?;
    writeln!(
        out,
        "selection campaign (machine seed {}): {}; {} rows, {} thermal error channels (laser sweeps, squareness, spindle drifts; rotations × {} mm; {} channels without predictable thermal signal dropped)",
        cfg.seed,
        rep.scenarios.join(", "),
        sel.n_rows,
        sel.n_channels,
        cfg.selection.arm_mm,
        sel.n_channels_dropped
    )?;
    writeln!(
        out,
        "procedure: candidates grouped into {k} clusters of similar thermal behaviour (average-linkage correlation clustering, distance 1 − |r|, of the readings or of their rise above ambient); one sensor per cluster by relevance (strongest |r| with a thermal error) or by greedy forward selection on the leave-one-cycle-out error of a linear model; plus the linear forward selection (information, then coverage). Each proposal is validated with the hybrid predictor trained on the typical cycles, compensating every diagonal at {n} selection-only states; the lowest quadratic-mean RMS |E| after wins",
        k = cfg.selection.count,
        n = validation_states(cfg.seed).len()
    )?;
    writeln!(
        out,
        "linear score, µm: reference only {:.3}, all {} candidates {:.3}",
        sel.reference_score_um,
        sel.candidates.len(),
        sel.all_score_um
    )?;
    writeln!(
        out,
        "proposals (validation: selection-only states, machine seed {}):",
        cfg.seed
    )?;
    writeln!(
        out,
        "  {:<30} {:>9} {:>12} {:>10} {:>14}  sensors",
        "rule", "lin. µm", "median red.", "worst run", "qmean RMS' µm"
    )?;
    for (i, (p, v)) in sel.proposals.iter().zip(&rep.validation).enumerate() {
        writeln!(
            out,
            "{} {:<30} {:>9.3} {:>11.1}% {:>9.1}% {:>14.3}  {}",
            if i == rep.chosen { "*" } else { " " },
            p.rule.name(),
            p.score_um,
            100.0 * v.median_reduction,
            100.0 * v.worst_reduction,
            v.qmean_rms_after_um,
            p.sensors[sel.reference.len()..].join(",")
        )?;
    }
    let chosen = &sel.proposals[rep.chosen];
    writeln!(
        out,
        "chosen: {} (*), ranked by forward selection on the linear score within the set:",
        chosen.rule.name()
    )?;
    writeln!(
        out,
        "{:>4}  {:<22} {:>9} {:>8} {:>7}  {:<28} {:>7}",
        "rank", "location", "score_um", "gain_um", "max|r|", "strongest error channel", "cluster"
    )?;
    let ev = |name: &str| sel.candidates.iter().find(|c| c.name == name);
    for (i, r) in sel.reference.iter().enumerate() {
        if let Some(c) = ev(r) {
            writeln!(
                out,
                "{:>4}  {:<22} {:>9.3} {:>8} {:>7.3}  {:<28} {:>7}",
                format!("ref{}", i),
                c.name,
                sel.reference_score_um,
                "-",
                c.max_abs_corr,
                c.best_channel,
                "-"
            )?;
        }
    }
    for (i, s) in chosen.ranking.iter().enumerate() {
        let c = ev(&s.name);
        writeln!(
            out,
            "{:>4}  {:<22} {:>9.3} {:>8.3} {:>7.3}  {:<28} {:>7}",
            i + 1,
            s.name,
            s.score_um,
            s.gain_um,
            c.map_or(f64::NAN, |c| c.max_abs_corr),
            c.map_or("", |c| c.best_channel.as_str()),
            s.cluster.map_or("-".to_string(), |k| (k + 1).to_string()),
        )?;
    }
    if !chosen.clusters.is_empty() {
        let cl: Vec<String> = chosen
            .clusters
            .iter()
            .enumerate()
            .map(|(k, c)| format!("{}: {{{}}}", k + 1, c.join(", ")))
            .collect();
        writeln!(out, "clusters: {}", cl.join(" "))?;
    }
    let mut groups: Vec<(String, usize)> = Vec::new();
    for n in chosen.sensors.clone() {
        let g = group_of(&n).to_string();
        match groups.iter_mut().find(|(k, _)| *k == g) {
            Some(e) => e.1 += 1,
            None => groups.push((g, 1)),
        }
    }
    let cov: Vec<String> = groups.iter().map(|(g, n)| format!("{g} ×{n}")).collect();
    writeln!(out, "coverage by structure: {}", cov.join(", "))?;
    let n_clusters = sel
        .candidates
        .iter()
        .map(|c| c.cluster)
        .max()
        .map_or(0, |m| m + 1);
    let mut multi = Vec::new();
    for k in 0..n_clusters {
        let members: Vec<&str> = sel
            .candidates
            .iter()
            .filter(|c| c.cluster == k)
            .map(|c| c.name.as_str())
            .collect();
        if members.len() > 1 {
            multi.push(format!("{{{}}}", members.join(", ")));
        }
    }
    writeln!(
        out,
        "near-copies (|r| ≥ {}): {}",
        cfg.selection.redundancy_corr,
        if multi.is_empty() {
            "none".to_string()
        } else {
            multi.join(" ")
        }
    )?;
    let names: Vec<&str> = sel.candidates.iter().map(|c| c.name.as_str()).collect();
    let left_out = super::defaults_not_candidates(spec, &names);
    if !cfg.compare_seeds.is_empty() && !left_out.is_empty() {
        writeln!(
            out,
            "the machine's own sensor set (study default) is not compared: {} not among the candidates",
            left_out.join(", ")
        )?;
    }
    Ok(())
}

/// Prints the comparison table of the sets on the machine seeds `compare_seeds` (nothing when
/// `comparison` is empty).
///
/// # Errors
/// Write errors.
pub fn write_comparison(
    comparison: &[SetResult],
    compare_seeds: &[u64],
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    if !comparison.is_empty() {
        let seeds: Vec<String> = compare_seeds.iter().map(u64::to_string).collect();
        writeln!(
            out,
            "compensation on held-out runs (hybrid predictor trained on the typical cycles with each set; every diagonal × held-out state; machine seeds {}):",
            seeds.join(",")
        )?;
        writeln!(
            out,
            "  {:<16} {:>7} {:>5} {:>12} {:>10} {:>13} {:>15}",
            "sensor set",
            "sensors",
            "runs",
            "median red.",
            "worst run",
            "max resid um",
            "mean RMS' um"
        )?;
        for r in comparison {
            writeln!(
                out,
                "  {:<16} {:>7} {:>5} {:>11.1}% {:>9.1}% {:>13.2} {:>15.2}",
                r.label,
                r.sensors.len(),
                r.runs,
                100.0 * r.median_reduction,
                100.0 * r.worst_reduction,
                r.max_residual_um,
                r.mean_rms_after_um
            )?;
        }
    }
    Ok(())
}

/// The study as JSON (selection steps, evidence, comparison): [`selection_json`] with the
/// comparison added ([`report_json_with`]).
///
/// # Errors
/// Serialisation errors.
pub fn report_json(rep: &PlacementReport) -> Result<String, serde_json::Error> {
    report_json_with(selection_json(rep), &rep.comparison)
}

/// The JSON study from its selection part ([`selection_json`]) and the comparison.
///
/// # Errors
/// Serialisation errors.
pub fn report_json_with(
    selection: serde_json::Value,
    comparison: &[SetResult],
) -> Result<String, serde_json::Error> {
    let mut v = selection;
    if let serde_json::Value::Object(map) = &mut v {
        map.insert("comparison".into(), serde_json::to_value(comparison)?);
    }
    serde_json::to_string_pretty(&v)
}

/// The selection stage of the study as a JSON object (selection steps, evidence, proposals
/// with their validation, the choice), without the comparison.
pub fn selection_json(rep: &PlacementReport) -> serde_json::Value {
    let sel = &rep.selection;
    serde_json::json!({
        "scenarios": rep.scenarios,
        "reference": sel.reference,
        "reference_score_um": sel.reference_score_um,
        "all_score_um": sel.all_score_um,
        "linear_forward": sel.steps.iter().map(|s| serde_json::json!({
            "name": s.name, "score_um": s.score_um, "gain_um": s.gain_um, "phase": s.phase.name(),
        })).collect::<Vec<_>>(),
        "candidates": sel.candidates.iter().map(|c| serde_json::json!({
            "name": c.name, "cluster": c.cluster, "max_abs_corr": c.max_abs_corr,
            "best_channel": c.best_channel, "alone_score_um": c.alone_score_um,
        })).collect::<Vec<_>>(),
        "proposals": sel.proposals.iter().zip(&rep.validation).map(|(p, v)| serde_json::json!({
            "rule": p.rule.name(), "sensors": p.sensors, "linear_score_um": p.score_um,
            "clusters": p.clusters,
            "ranking": p.ranking.iter().map(|r| serde_json::json!({
                "name": r.name, "cluster": r.cluster, "score_um": r.score_um, "gain_um": r.gain_um,
            })).collect::<Vec<_>>(),
            "validation": v,
        })).collect::<Vec<_>>(),
        "chosen": sel.proposals[rep.chosen].rule.name(),
    })
}
