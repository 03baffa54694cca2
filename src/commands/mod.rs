//! The use cases behind the command line, as library functions: each takes a validated config
//! (built by the command line, `cli`, or by a program of its own) and a writer for what it prints, and
//! writes its files through [`crate::files`]. Progress bars go to stderr.

pub mod bench;
pub mod calibrate;
pub mod campaign;
pub mod chatter;
pub mod check;
pub mod control;
pub mod control_robust;
pub mod cut;
pub mod export;
pub mod identify;
pub mod identify_thermal;
pub mod interpret;
pub mod lobes;
pub mod lobes_shard;
pub mod merge;
pub mod modal_fit;
pub(crate) mod model;
pub mod probe_campaign;
mod probe_log;
mod probe_update;
pub mod program_placement;
pub mod replay;
pub mod run;
pub mod run_fiveaxis;
mod run_stream;
pub mod select_sensors;
pub mod select_shard;
pub mod thermal;
pub mod train;

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use crate::files;
use crate::shard::InputFingerprint;
use crate::studies::placement;
use vmc_machine::machine::MachineSpec;

/// The program version written in shard manifests.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The fingerprints of what a study embeds rather than reads: the diagonal programs and the
/// calibration plan of `machine` (names, durations, purposes).
pub(crate) fn embedded_fingerprints(machine: &MachineSpec) -> Vec<InputFingerprint> {
    let mut v: Vec<InputFingerprint> = crate::studies::campaign::DIAGONALS
        .iter()
        .map(|(name, text)| {
            InputFingerprint::of(
                &format!("program diag_{}.ngc", name.to_lowercase()),
                "embedded",
                text.as_bytes(),
            )
        })
        .collect();
    let plan: Vec<String> = crate::studies::calibration::ThermalCycle::calibration_plan(machine)
        .iter()
        .map(|c| format!("{} {} {}", c.name, c.duration_s(), c.purpose))
        .collect();
    v.push(InputFingerprint::of(
        "calibration plan",
        "embedded",
        plan.join("\n").as_bytes(),
    ));
    v
}

/// Fingerprints of a command's input files: the machine description (the embedded reference
/// without one) and the sensor set if one is given.
///
/// # Errors
/// A file that cannot be read.
pub fn input_fingerprints(
    machine: Option<&Path>,
    sensors: Option<&Path>,
) -> Result<Vec<InputFingerprint>> {
    let mut v = vec![match machine {
        Some(p) => InputFingerprint::of(
            "machine",
            &p.display().to_string(),
            &std::fs::read(p).with_context(|| format!("{}: cannot read", p.display()))?,
        ),
        None => InputFingerprint::of(
            "machine",
            "embedded",
            vmc_machine::machine::REFERENCE_TOML.as_bytes(),
        ),
    }];
    if let Some(p) = sensors {
        v.push(InputFingerprint::of(
            "sensor set",
            &p.display().to_string(),
            &std::fs::read(p).with_context(|| format!("{}: cannot read", p.display()))?,
        ));
    }
    Ok(v)
}
use crate::record::{self, RecordSettings};

/// A Rerun recording to write: where, and how to draw.
#[derive(Debug, Clone)]
pub struct RrdOutput {
    /// The `.rrd` file (checked before any simulation).
    pub path: PathBuf,
    /// Drawing settings (error magnification).
    pub settings: RecordSettings,
}

/// The machine of a command: the file given, or the embedded reference machine; with `sensors`,
/// its sensor set replaced by the one of that file.
///
/// # Errors
/// An unreadable or invalid machine file or sensor set, or a sensor set that does not fit.
pub fn load_machine(path: Option<&Path>, sensors: Option<&Path>) -> Result<MachineSpec> {
    let spec = match path {
        Some(p) => MachineSpec::load(p).map_err(|e| match e {
            vmc_machine::machine::MachineError::FiveAxis { .. } => anyhow::anyhow!(
                "{e}; five-axis machines are run with `run`, probed with `probe-campaign` and identified with `identify`"
            ),
            e => e.into(),
        })?,
        None => MachineSpec::reference(),
    };
    let Some(file) = sensors else {
        return Ok(spec);
    };
    let name = file.display().to_string();
    let text = files::read_named(file, "sensor set")?;
    let set = placement::SensorSet::from_toml_str(&text, &name)?;
    let spec = placement::with_sensors(&spec, set.sensors).with_context(|| {
        format!(
            "{name}: sensor set does not fit machine {}",
            spec.machine.name
        )
    })?;
    Ok(spec)
}

/// Whether the machine file at `path` describes a five-axis machine (it has `[[rotary]]` axes);
/// the three- and five-axis descriptions are otherwise read by their own parsers.
///
/// # Errors
/// An unreadable file or bad TOML.
pub fn is_five_axis_machine(path: &Path) -> Result<bool> {
    let text = vmc_machine::machine::read_machine_file(path)?;
    let table: toml::Table =
        vmc_machine::machine::parse_machine_toml(&text, &path.display().to_string())?;
    Ok(table.contains_key("rotary"))
}

/// Refuses a seed given twice: its runs would count twice in the medians.
///
/// # Errors
/// The first seed given twice, named with its `option`.
pub fn check_distinct_seeds(option: &str, seeds: &[u64]) -> Result<()> {
    for (i, s) in seeds.iter().enumerate() {
        if seeds[..i].contains(s) {
            anyhow::bail!("{option}: seed {s} is given twice (its runs would count twice)");
        }
    }
    Ok(())
}

/// Reads the result files of shards (JSON lines), in order, and hands each line parsed as a `T`
/// to `f` with where it came from (`FILE line K`, for messages); a problem of the files becomes
/// an `E` through `wrap`.
///
/// # Errors
/// An unreadable file or line, a line that is not a `T`, and `f`'s errors.
pub(crate) fn for_each_shard_line<T: serde::de::DeserializeOwned, E>(
    files: impl IntoIterator<Item = PathBuf>,
    mut f: impl FnMut(T, &dyn Fn() -> String) -> Result<(), E>,
    wrap: impl Fn(anyhow::Error) -> E,
) -> Result<(), E> {
    use std::io::BufRead;
    for file in files {
        let reader = std::io::BufReader::new(
            std::fs::File::open(&file)
                .with_context(|| format!("{}: cannot read shard results", file.display()))
                .map_err(&wrap)?,
        );
        for (k, line) in reader.lines().enumerate() {
            let at = || format!("{} line {}", file.display(), k + 1);
            let line = line.with_context(at).map_err(&wrap)?;
            let r: T = serde_json::from_str(&line)
                .with_context(at)
                .map_err(&wrap)?;
            f(r, &at)?;
        }
    }
    Ok(())
}

/// Says which recording was written and its size (`wrote FILE (x.xx MB<extra>)`).
///
/// # Errors
/// The writer's.
pub fn wrote_recording(
    out: &mut dyn Write,
    path: &Path,
    bytes: u64,
    extra: &str,
) -> std::io::Result<()> {
    writeln!(
        out,
        "wrote {} ({:.2} MB{extra})",
        path.display(),
        bytes as f64 / 1e6
    )
}

/// `lobes` of a tool: the whole list of speeds, or one shard of it for `merge`.
///
/// # Errors
/// See [`lobes::lobes`] and [`lobes_shard::lobes_shard`].
pub fn lobes_whole_or_shard(cfg: &lobes::LobesConfig, out: &mut dyn Write) -> Result<()> {
    match &cfg.shard {
        Some(target) => lobes_shard::lobes_shard(cfg, target, out),
        None => lobes::lobes(cfg, out),
    }
}

/// `lobes --controller`: the whole list of speeds, or one shard of it for `merge`.
///
/// # Errors
/// See [`control::lobes`] and [`lobes_shard::control_lobes_shard`].
pub fn control_lobes_whole_or_shard(
    cfg: &control::ControlLobesConfig,
    out: &mut dyn Write,
) -> Result<()> {
    match &cfg.shard {
        Some(target) => lobes_shard::control_lobes_shard(cfg, target, out),
        None => control::lobes(cfg, out),
    }
}

/// `select-sensors`: the whole study, or one shard of it for `merge`.
///
/// # Errors
/// See [`select_sensors::select_sensors`] and [`select_shard::select_shard`].
pub fn select_sensors_whole_or_shard(
    cfg: &select_sensors::SelectConfig,
    out: &mut dyn Write,
) -> Result<()> {
    match cfg.shard {
        Some(shard) => {
            select_sensors::check_count(cfg)?;
            select_shard::select_shard(cfg, shard, out)
        }
        None => select_sensors::select_sensors(cfg, out),
    }
}

/// Checks the outputs of a run before any work: the output folder's `samples.csv` and
/// `summary.json` (their paths), and the recording's path.
pub(crate) fn prepare_run_outputs(
    out_dir: Option<&Path>,
    rrd: Option<&RrdOutput>,
    force: bool,
) -> Result<Option<(PathBuf, PathBuf)>> {
    let out_files = match out_dir {
        Some(dir) => {
            let names = ["samples.csv", "summary.json"].map(String::from);
            let files = files::prepare_output_folder(dir, &names, force)?;
            Some((files[0].clone(), files[1].clone()))
        }
        None => None,
    };
    if let Some(rrd) = rrd {
        record::check_rrd_path(&rrd.path, force)?;
    }
    Ok(out_files)
}
