//! `vmc-twin merge`: combines the shard results of a sharded command into what the unsharded
//! command writes and prints. The shard folders are checked as a set first
//! ([`crate::shard::check_set`]), then merged by the command their manifests name: `campaign`
//! here, `select-sensors` in [`super::select_shard`], `lobes` in [`super::lobes_shard`]. The
//! campaign's per-seed results are streamed from the files, one seed's results at a time: the
//! training summaries, then the runs (the order of `report.json`), then the runs again as often
//! as the summary's exact medians and percentiles need (once more for a few machines, two or
//! three times for a large fleet), so the merge's memory does not grow with the runs it streams.

use std::cell::RefCell;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use serde::ser::{Error as _, SerializeSeq};
use serde::{Serialize, Serializer};

use super::campaign::{model_file_names, SEED_RESULTS_FILE};
use crate::files;
use crate::record;
use crate::shard::MergeConfig;
use crate::shard::{check_set, integrity, ShardManifest, MANIFEST_FILE};
use crate::studies::campaign::{self, ReportHeader, RunPasses, SeedResults, SummaryBuilder};

/// Reads and checks the shards, then merges them with the command that wrote them.
///
/// # Errors
/// A folder without a readable manifest, a set of shards that does not belong together (see
/// [`check_set`]), unreadable results, outputs that may not be written.
pub fn merge(cfg: &MergeConfig, out: &mut dyn Write) -> Result<()> {
    let mut shards = Vec::new();
    for dir in &cfg.shard_dirs {
        let path = dir.join(MANIFEST_FILE);
        if !path.is_file() {
            bail!(
                "{}: not a shard folder (no {MANIFEST_FILE}; a shard writes it: campaign --shard I/N --out DIR, select-sensors or lobes --shard I/N --shard-dir DIR)",
                dir.display()
            );
        }
        let text = files::read_named(&path, "shard manifest")?;
        let m: ShardManifest = serde_json::from_str(&text)
            .with_context(|| format!("{}: not a shard manifest", path.display()))?;
        shards.push((dir.display().to_string(), m));
    }
    let order = check_set(&shards)?;
    for (dir, (_, m)) in cfg.shard_dirs.iter().zip(&shards) {
        check_integrity(dir, m)?;
    }
    let dirs: Vec<&Path> = order.iter().map(|&k| cfg.shard_dirs[k].as_path()).collect();
    let first = &shards[order[0]].1;
    match first.command.as_str() {
        "campaign" => {
            let header: ReportHeader = serde_json::from_value(first.header.clone())
                .context("the shards' report header")?;
            let seeds = order
                .iter()
                .flat_map(|&k| shards[k].1.work_ids.iter())
                .map(|id| parse_seed_id(id))
                .collect::<Result<Vec<u64>>>()?;
            merge_campaign(cfg, header, &dirs, &seeds, out)
        }
        super::select_shard::COMMAND => super::select_shard::merge(cfg, first, &dirs, out),
        super::lobes_shard::COMMAND => super::lobes_shard::merge(cfg, first, &dirs, out),
        other => bail!("shards of `{other}` cannot be merged by this version"),
    }
}

/// Every result file of a shard is the one its shard wrote: each listed file has its size and
/// hash (see [`integrity`]), and the folder holds no other file (hidden files aside) that a
/// merge could read unchecked.
///
/// # Errors
/// A listed file missing or changed, an unlisted file, another layout version.
fn check_integrity(dir: &Path, m: &ShardManifest) -> Result<()> {
    integrity::verify(dir, m)?;
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot list", dir.display()))?;
    for e in entries {
        let e = e.with_context(|| format!("{}: cannot list", dir.display()))?;
        let name = e.file_name().to_string_lossy().to_string();
        if name == MANIFEST_FILE || name.starts_with('.') || !e.path().is_file() {
            continue;
        }
        if !integrity::lists(m, &name) {
            bail!(
                "{}: not among the result files {MANIFEST_FILE} lists (a file its shard did not \
                 write, or a shard of an older version); remove it or run that shard again",
                e.path().display()
            );
        }
    }
    Ok(())
}

/// `seed 17` → 17.
fn parse_seed_id(id: &str) -> Result<u64> {
    id.strip_prefix("seed ")
        .and_then(|s| s.parse().ok())
        .with_context(|| format!("work id `{id}` is not `seed N`"))
}

/// Merges campaign shards (in shard order) covering `seeds`: `report.json`, the trained models
/// and the printed summary, as `campaign` over the same seeds writes and prints them.
fn merge_campaign(
    cfg: &MergeConfig,
    header: ReportHeader,
    dirs: &[&Path],
    seeds: &[u64],
    out: &mut dyn Write,
) -> Result<()> {
    let mut names = vec!["report.json".to_string()];
    names.extend(model_file_names(seeds));
    files::prepare_output_folder(&cfg.out_dir, &names, cfg.force)?;
    if let Some(rrd) = &cfg.rrd {
        record::check_rrd_path(rrd, cfg.force)?;
    }
    if let Some(png) = &cfg.png {
        files::check_writable(png, cfg.force)?;
    }
    let results = SeedFiles {
        files: dirs.iter().map(|d| d.join(SEED_RESULTS_FILE)).collect(),
        seeds: seeds.to_vec(),
    };
    let digest = RefCell::new(SummaryBuilder::new(header.clone()));
    let path = cfg.out_dir.join("report.json");
    files::write_atomic_with(&path, cfg.force, |w| {
        let training = TrainingStream(&results);
        let runs = RunStream {
            files: &results,
            digest: &digest,
        };
        campaign::write_report_json(&header, training, runs, w).map_err(std::io::Error::other)
    })?;
    for (dir, name) in dirs
        .iter()
        .flat_map(|d| std::iter::repeat(*d).zip(std::fs::read_dir(d).into_iter().flatten()))
        .filter_map(|(d, e)| Some((d, e.ok()?.file_name().to_string_lossy().to_string())))
        .filter(|(_, n)| names[1..].contains(n))
    {
        let to = cfg.out_dir.join(&name);
        let text = std::fs::read(dir.join(&name))
            .with_context(|| format!("{}: cannot read", dir.join(&name).display()))?;
        // The model's own check: it reads as a model (its checksum matched already).
        crate::predict::predictor::AnyPredictor::from_json_str(&String::from_utf8_lossy(&text))
            .with_context(|| format!("{}: not a trained model", dir.join(&name).display()))?;
        files::write_atomic(&to, &text, cfg.force)?;
    }
    for name in &names[1..] {
        if !cfg.out_dir.join(name).is_file() {
            bail!("no shard holds the trained model {name}");
        }
    }
    let mut digest = digest.into_inner();
    let changed = "the shard results changed while they were merged";
    while !digest.end_pass().context(changed)? {
        results.for_each(
            |r| {
                r.runs.iter().for_each(|run| digest.push(run));
                Ok(())
            },
            |e| e,
        )?;
    }
    let digest = digest.finish();
    let mut summary = Vec::new();
    campaign::write_summary(&digest, &mut summary)?;
    out.write_all(&summary)?;
    if cfg.print_runs {
        campaign::write_run_table_head(out)?;
        results.for_each(
            |r| {
                r.runs
                    .iter()
                    .try_for_each(|run| campaign::write_run_row(run, out))
                    .map_err(anyhow::Error::from)
            },
            |e| e,
        )?;
        campaign::write_run_table_foot(out)?;
    }
    writeln!(out, "wrote {} and the trained models", path.display())?;
    if let Some(png) = &cfg.png {
        write_png(png, &digest.fleet, cfg.force, out)?;
    }
    if let Some(rrd) = &cfg.rrd {
        let seeds: Vec<String> = seeds.iter().map(u64::to_string).collect();
        let title = format!(
            "vmc-twin fleet of {} on seeds {}",
            header.machine,
            seeds.join(",")
        );
        let text = String::from_utf8_lossy(&summary);
        let bytes = record::fleet::record_fleet(rrd, cfg.force, &title, &digest.fleet, &text)?;
        super::wrote_recording(out, rrd, bytes, "; the fleet's histograms")?;
    }
    Ok(())
}

/// The shards' per-seed result files, in shard order, and the seeds they must hold in order.
struct SeedFiles {
    files: Vec<PathBuf>,
    seeds: Vec<u64>,
}

impl SeedFiles {
    /// Calls `f` with each seed's results in order, one at a time; checks that the files hold
    /// exactly the expected seeds (a problem there becomes an `E` through `wrap`).
    fn for_each<E>(
        &self,
        mut f: impl FnMut(&SeedResults) -> Result<(), E>,
        wrap: impl Fn(anyhow::Error) -> E,
    ) -> Result<(), E> {
        let mut expected = self.seeds.iter();
        super::for_each_shard_line(
            self.files.iter().cloned(),
            |r: SeedResults, at| {
                match expected.next() {
                    Some(&s) if s == r.seed => {}
                    Some(&s) => {
                        return Err(wrap(anyhow::anyhow!(
                            "{}: seed {}, expected seed {s}",
                            at(),
                            r.seed
                        )))
                    }
                    None => {
                        return Err(wrap(anyhow::anyhow!(
                            "{}: seed {} beyond the shard's work list",
                            at(),
                            r.seed
                        )))
                    }
                }
                f(&r)
            },
            &wrap,
        )?;
        match expected.next() {
            Some(s) => Err(wrap(anyhow::anyhow!(
                "the shard results hold no results for seed {s}"
            ))),
            None => Ok(()),
        }
    }
}

/// The training summaries of every seed, serialised as one sequence while the files are read.
struct TrainingStream<'a>(&'a SeedFiles);

impl Serialize for TrainingStream<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut seq = serializer.serialize_seq(None)?;
        self.0.for_each(
            |r| r.training.iter().try_for_each(|t| seq.serialize_element(t)),
            |e| S::Error::custom(format!("{e:#}")),
        )?;
        seq.end()
    }
}

/// The runs of every seed, serialised as one sequence while the files are read; each run also
/// goes into the summary's first pass.
struct RunStream<'a> {
    files: &'a SeedFiles,
    digest: &'a RefCell<SummaryBuilder>,
}

impl Serialize for RunStream<'_> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let mut seq = serializer.serialize_seq(None)?;
        self.files.for_each(
            |r| {
                r.runs.iter().try_for_each(|run| {
                    self.digest.borrow_mut().push(run);
                    seq.serialize_element(run)
                })
            },
            |e| S::Error::custom(format!("{e:#}")),
        )?;
        seq.end()
    }
}

/// Writes the fleet's histograms as a PNG picture and says what each panel spans.
fn write_png(
    path: &Path,
    fleet: &campaign::fleet::FleetSummary,
    force: bool,
    out: &mut dyn Write,
) -> Result<()> {
    let panels = campaign::fleet_png::panels(fleet);
    let bytes = campaign::fleet_png::encode_png(&campaign::fleet_png::raster(&panels))?;
    files::write_atomic(path, &bytes, force)?;
    writeln!(
        out,
        "wrote {} (histograms across machines, {} bins; red line: the goal):",
        path.display(),
        campaign::fleet::BINS
    )?;
    for (pos, (name, (hist, _))) in ["top left", "top right", "bottom left", "bottom right"]
        .iter()
        .zip(&panels)
    {
        if let Some(h) = hist {
            let top = h.counts.iter().max().copied().unwrap_or(0);
            writeln!(
                out,
                "  {pos:<12} {name}: {:.2} to {:.2}, tallest bar {top} machines",
                h.lo,
                h.lo + h.width * h.counts.len() as f64
            )?;
        }
    }
    Ok(())
}
