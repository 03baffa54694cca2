//! `vmc-twin select-sensors --shard I/N --shard-dir DIR` and the merge of its shards.
//!
//! The work items are the compare seeds, in the order given. Every shard with at least one
//! seed runs the selection stage (one selection campaign on `--seed`, the proposals and their
//! validation: every comparison depends on the selected set) and the comparison on its seeds;
//! a shard without seeds only writes its manifest. A shard's folder holds:
//! - `shard.json`, the manifest ([`ShardManifest`], command `select-sensors`);
//! - `selection.json` (shards with seeds): the selection stage as the outputs show it — the
//!   printed report up to the comparison, the JSON study without its comparison, the sensor set
//!   file — and the compared sets;
//! - `compare.jsonl`: one line per seed ([`placement::SeedRuns`]), every set's held-out runs.
//!
//! The merge prints the selection part as the shards wrote it, then the comparison recomputed
//! by [`placement::summarise_comparison`] over the runs of all seeds in the order of the compare
//! seeds, and writes the sensor set and the JSON study with the writers the unsharded command
//! uses: the outputs are bit-identical to the unsharded run's.

use std::io::Write;
use std::path::Path;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

use super::select_sensors::{placement_config, sensor_set_toml, SelectConfig};
use super::VERSION;
use crate::files;
use crate::shard::MergeConfig;
use crate::shard::{InputFingerprint, Shard, ShardManifest, MANIFEST_FILE, MANIFEST_FORMAT};
use crate::studies::placement::{self, SeedRuns};

/// Name of the command in a shard's manifest.
pub const COMMAND: &str = "select-sensors";

/// Name of a select-sensors shard's selection stage file.
pub const SELECTION_FILE: &str = "selection.json";

/// Name of a select-sensors shard's per-seed comparison runs (one JSON object per line).
pub const COMPARE_FILE: &str = "compare.jsonl";

/// What the merge needs besides the shards' results (the manifest's header): the output names
/// and the compare seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Header {
    /// The sensor set file as given to `--out`.
    out: String,
    /// The JSON study as given to `--json`.
    json: Option<String>,
    /// The compare seeds, in order.
    compare_seeds: Vec<u64>,
}

/// The selection stage as the outputs show it, and the sets the comparison runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct SelectionPart {
    /// The printed report up to the comparison.
    report: String,
    /// The JSON study without its comparison.
    study: serde_json::Value,
    /// The sensor set file.
    sensor_set: String,
    /// The compared sets: label and candidate names.
    sets: Vec<(String, Vec<String>)>,
}

/// Runs one shard of the study: the selection stage and the comparison on the shard's block of
/// the compare seeds, written for `merge`.
///
/// # Errors
/// No shard folder, no compare seed, outputs that may not be written, study errors.
pub fn select_shard(cfg: &SelectConfig, shard: Shard, out: &mut dyn Write) -> Result<()> {
    let dir = cfg
        .shard_dir
        .as_ref()
        .context("--shard needs --shard-dir DIR for the shard's results")?;
    if cfg.compare_seeds.is_empty() {
        bail!("--shard splits the comparison over the compare seeds; with --no-compare there is nothing to split: run without --shard");
    }
    let seeds = &cfg.compare_seeds[shard.block(cfg.compare_seeds.len())];
    let names = [MANIFEST_FILE, SELECTION_FILE, COMPARE_FILE].map(String::from);
    files::prepare_output_folder(dir, &names, cfg.force)?;
    let header = Header {
        out: cfg.out.display().to_string(),
        json: cfg.json.as_ref().map(|j| j.display().to_string()),
        compare_seeds: cfg.compare_seeds.clone(),
    };
    let manifest = ShardManifest {
        format: MANIFEST_FORMAT,
        command: COMMAND.into(),
        shard,
        work_ids: seeds.iter().map(|s| format!("seed {s}")).collect(),
        work_total: cfg.compare_seeds.len(),
        command_line: cfg.command_line.clone(),
        version: VERSION.into(),
        inputs: select_inputs(cfg)?,
        header: serde_json::to_value(&header)?,
        results: Vec::new(),
    };
    let mut runs = Vec::new();
    if !seeds.is_empty() {
        let study = placement_config(cfg);
        let stage = placement::selection_stage(&cfg.machine, &study, cfg.only.as_deref())?;
        let mut report = Vec::new();
        placement::write_selection_part(&stage.report, &cfg.machine, &study, &mut report)?;
        let part = SelectionPart {
            report: String::from_utf8(report)?,
            study: placement::selection_json(&stage.report),
            sensor_set: sensor_set_toml(cfg, &stage.report.selected_sensors),
            sets: stage.sets.clone(),
        };
        let json = serde_json::to_string_pretty(&part)?;
        files::write_atomic(&dir.join(SELECTION_FILE), json.as_bytes(), cfg.force)?;
        runs = placement::compare_seeds(&stage, &study, seeds)?;
    } else if dir.join(SELECTION_FILE).is_file() {
        // Overwriting (--force) a folder of another run: an empty shard has no selection stage,
        // and a stale one must not reach the merge.
        std::fs::remove_file(dir.join(SELECTION_FILE))
            .with_context(|| format!("{}: cannot remove", dir.join(SELECTION_FILE).display()))?;
    }
    files::write_atomic_with(&dir.join(COMPARE_FILE), cfg.force, |w| {
        for r in &runs {
            serde_json::to_writer(&mut *w, r)?;
            w.write_all(b"\n")?;
        }
        Ok(())
    })?;
    let written: Vec<String> = [SELECTION_FILE, COMPARE_FILE]
        .into_iter()
        .filter(|n| dir.join(n).is_file())
        .map(String::from)
        .collect();
    let path = crate::shard::integrity::write_manifest(dir, manifest, &written, cfg.force)?;
    let list: Vec<String> = seeds.iter().map(u64::to_string).collect();
    writeln!(
        out,
        "select-sensors shard {shard}: {} of {} compare seeds ({}); wrote {}{}",
        seeds.len(),
        cfg.compare_seeds.len(),
        if list.is_empty() {
            "none: nothing to run".to_string()
        } else {
            format!("seeds {}", list.join(", "))
        },
        path.display(),
        if seeds.is_empty() {
            format!(" and an empty {COMPARE_FILE}")
        } else {
            format!(", {SELECTION_FILE} and {COMPARE_FILE}")
        }
    )?;
    Ok(())
}

/// The fingerprints of everything the study's results depend on, each named so that a refusal
/// says which differs: the machine, the candidates, the count, the selection seed, the draws,
/// the compare seeds, the predictor settings, the calibration plan and the diagonal programs.
/// (The selection procedure's other settings have no option: the version fixes them.)
fn select_inputs(cfg: &SelectConfig) -> Result<Vec<InputFingerprint>> {
    let study = placement_config(cfg);
    let mut inputs = cfg.inputs.clone();
    let join = |v: &[u64]| v.iter().map(u64::to_string).collect::<Vec<_>>().join(",");
    let candidates = cfg
        .only
        .as_ref()
        .map_or("all".to_string(), |only| only.join(","));
    for (name, text) in [
        ("candidates", candidates),
        ("count", cfg.count.to_string()),
        ("seed", cfg.seed.to_string()),
        ("random draws", cfg.random_draws.to_string()),
        ("compare seeds", join(&cfg.compare_seeds)),
        (
            "predictor settings",
            serde_json::to_string(&study.settings)?,
        ),
    ] {
        inputs.push(InputFingerprint::of(name, "arguments", text.as_bytes()));
    }
    inputs.extend(super::embedded_fingerprints(&cfg.machine));
    Ok(inputs)
}

/// Merges select-sensors shards (checked as a set, in shard order): prints the report and
/// writes the sensor set (and the JSON study if the shards were asked for one) in `cfg.out_dir`
/// under the file names given to the shards' `--out` and `--json`.
///
/// # Errors
/// A bad header, shards whose selection stages differ or are missing, unreadable results,
/// runs of other seeds than the manifests list, outputs that may not be written.
pub fn merge(
    cfg: &MergeConfig,
    first: &ShardManifest,
    dirs: &[&Path],
    out: &mut dyn Write,
) -> Result<()> {
    if cfg.print_runs || cfg.rrd.is_some() || cfg.png.is_some() {
        bail!("--runs, --rrd and --png are for campaign shards; these are select-sensors shards");
    }
    let header: Header =
        serde_json::from_value(first.header.clone()).context("the shards' header")?;
    let file_name = |given: &str, option: &str| -> Result<String> {
        Path::new(given)
            .file_name()
            .map(|n| n.to_string_lossy().to_string())
            .with_context(|| format!("the shards' {option} `{given}` names no file"))
    };
    let toml_name = file_name(&header.out, "--out")?;
    let json_name = header
        .json
        .as_deref()
        .map(|j| file_name(j, "--json"))
        .transpose()?;
    if json_name.as_ref() == Some(&toml_name) {
        bail!("the shards' --out and --json have the same file name {toml_name}: the merge would write both to one file");
    }
    let mut names = vec![toml_name.clone()];
    names.extend(json_name.clone());
    files::prepare_output_folder(&cfg.out_dir, &names, cfg.force)?;
    let part = read_selection(dirs)?;
    let runs = read_runs(dirs, &header.compare_seeds, part.sets.len())?;
    let comparison = placement::summarise_comparison(&part.sets, &runs);
    out.write_all(part.report.as_bytes())?;
    placement::write_comparison(&comparison, &header.compare_seeds, out)?;
    let toml_path = cfg.out_dir.join(&toml_name);
    files::write_atomic(&toml_path, part.sensor_set.as_bytes(), cfg.force)?;
    writeln!(out, "wrote {}", toml_path.display())?;
    if let Some(name) = json_name {
        let path = cfg.out_dir.join(name);
        let json = placement::report_json_with(part.study, &comparison)?;
        files::write_atomic(&path, json.as_bytes(), cfg.force)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    Ok(())
}

/// The selection stage of the first shard that ran one; every other shard that ran one must
/// have written the same (the stage is deterministic: a difference means other inputs).
fn read_selection(dirs: &[&Path]) -> Result<SelectionPart> {
    let mut found: Option<(SelectionPart, &Path)> = None;
    for dir in dirs {
        let path = dir.join(SELECTION_FILE);
        if !path.is_file() {
            continue;
        }
        let text = files::read_named(&path, "shard selection stage")?;
        let part: SelectionPart = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a selection stage", path.display()))?;
        match &found {
            None => found = Some((part, dir)),
            Some((first, first_dir)) if *first != part => bail!(
                "{} and {} hold different selection stages: shards of different studies cannot be merged",
                first_dir.display(),
                dir.display()
            ),
            Some(_) => {}
        }
    }
    found
        .map(|(part, _)| part)
        .with_context(|| format!("no shard holds the selection stage ({SELECTION_FILE})"))
}

/// The runs of every compare seed, read from the shards' files in shard order; the files must
/// hold exactly `seeds` in order, each with `sets` lists of runs.
fn read_runs(dirs: &[&Path], seeds: &[u64], sets: usize) -> Result<Vec<SeedRuns>> {
    let mut expected = seeds.iter();
    let mut all = Vec::with_capacity(seeds.len());
    let files = dirs.iter().map(|d| d.join(COMPARE_FILE));
    super::for_each_shard_line(
        files,
        |r: SeedRuns, at| {
            match expected.next() {
                Some(&s) if s == r.seed => {}
                Some(&s) => bail!("{}: seed {}, expected seed {s}", at(), r.seed),
                None => bail!("{}: seed {} beyond the shards' work list", at(), r.seed),
            }
            if r.runs.len() != sets {
                bail!(
                    "{}: runs of {} sensor sets, the study compares {sets}",
                    at(),
                    r.runs.len()
                );
            }
            all.push(r);
            Ok(())
        },
        |e| e,
    )?;
    if let Some(s) = expected.next() {
        bail!("the shard results hold no runs for compare seed {s}");
    }
    Ok(all)
}
