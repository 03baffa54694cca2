//! Arguments of `campaign` (with seed ranges and shards) and `merge`.

use std::path::PathBuf;

use anyhow::{bail, Result};

use super::{ForceArg, MachineArg, RrdArgs, SensorsArg};
use crate::commands;
use crate::shard::Shard;

/// The most seeds a campaign takes (a guard against a mistyped range).
pub const MAX_SEEDS: u64 = 1_000_000;

/// Arguments of `campaign`.
#[derive(clap::Args)]
pub struct CampaignArgs {
    #[command(flatten)]
    pub machine: MachineArg,
    #[command(flatten)]
    pub sensors: SensorsArg,
    /// Machine realisations to calibrate and evaluate: comma-separated seeds and inclusive
    /// ranges, e.g. `1,2,3`, `1..1000` or `1..5,9`.
    #[arg(long, value_delimiter = ',', default_values = ["1", "2", "3"])]
    pub seeds: Vec<String>,
    /// Folder for report.json and the trained models (created if missing); with --shard, the
    /// shard's results (shard.json, seeds.jsonl, models) for `merge`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub force: ForceArg,
    /// Opt-in: the hybrid's spindle part also takes the commanded spindle speed as heat input
    /// (see docs/decisions on the spindle-speed input).
    #[arg(long)]
    pub spindle_speed: bool,
    /// Also print the full table, one row per run (it is always in report.json).
    #[arg(long)]
    pub runs: bool,
    /// Run only shard I of N of the seeds (1-based, e.g. 2/4) and write its results under
    /// --out for `vmc-twin merge`.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Probe four reference spheres on the table every MIN minutes of every held-out run (from
    /// its start, and right before its diagonal) and correct the drift the model missed
    /// (experimental; see docs/results.md, on-machine probing).
    #[arg(long, value_name = "MIN")]
    pub probe_every: Option<f64>,
    /// Also judge static compensation tables on the same held-out runs: per-joint and own+cross
    /// tables sampled from each seed's hybrid frozen cold and frozen warm (HOURS into the
    /// calibration cycle cal_4000_8000rpm, default 2: after 2 h at 4000 rpm), against the live
    /// hybrid; with --out, writes static-tables.json.
    #[arg(long, value_name = "HOURS", num_args = 0..=1, default_missing_value = "2")]
    pub static_tables: Option<f64>,
    #[command(flatten)]
    pub rrd: RrdArgs,
}

impl CampaignArgs {
    /// The validated config.
    ///
    /// # Errors
    /// An unreadable or invalid machine or sensor set, no seed, a bad seed range or a seed given
    /// twice, a bad shard or a shard without --out or with --rrd or --runs, a bad recording path
    /// or magnification.
    pub fn config(self) -> Result<commands::campaign::CampaignConfig> {
        let seeds = parse_seeds("--seeds", &self.seeds)?;
        let shard = self.shard.as_deref().map(str::parse::<Shard>).transpose()?;
        if let Some(s) = shard {
            if self.out.is_none() {
                bail!("--shard {s} needs --out DIR for the shard's results");
            }
            if self.rrd.rrd.is_some() {
                bail!("--rrd records the whole campaign: run it without --shard");
            }
            if self.runs {
                bail!("--runs prints the merged campaign's runs: pass it to `vmc-twin merge`");
            }
        }
        if let Some(min) = self.probe_every {
            if !(min.is_finite() && (1.0..=1440.0).contains(&min)) {
                bail!("--probe-every {min}: the interval must be 1 to 1440 minutes");
            }
            if shard.is_some() {
                bail!("--probe-every runs the whole campaign: run it without --shard");
            }
        }
        if let Some(h) = self.static_tables {
            check_static_tables(h, shard.is_some(), self.probe_every.is_some())?;
        }
        let machine = self.machine.load(Some(&self.sensors))?;
        let inputs = commands::input_fingerprints(
            self.machine.machine.as_deref(),
            self.sensors.sensors.as_deref(),
        )?;
        let force = self.force.force;
        Ok(commands::campaign::CampaignConfig {
            machine,
            seeds,
            out_dir: self.out,
            force,
            spindle_speed: self.spindle_speed,
            print_runs: self.runs,
            rrd: self.rrd.checked()?,
            shard,
            probe_every_min: self.probe_every,
            static_tables_warm_h: self.static_tables,
            inputs,
            command_line: std::env::args().collect(),
        })
    }
}

/// Checks `--static-tables HOURS` and what it runs with.
///
/// # Errors
/// Hours outside the freezing cycle, a shard, probing.
fn check_static_tables(hours: f64, shard: bool, probing: bool) -> Result<()> {
    let cycle_h = crate::studies::tables::freezing_states(crate::studies::tables::DEFAULT_WARM_H)?
        .last()
        .map_or(0.0, |(_, s)| s.cycle.duration_s() / 3600.0);
    if !(hours.is_finite() && hours > 0.0 && hours <= cycle_h) {
        bail!(
            "--static-tables {hours}: the warm freezing state is HOURS into the calibration \
             cycle {} and must be within its {cycle_h} h (0 < HOURS ≤ {cycle_h})",
            crate::studies::tables::FREEZE_CYCLE
        );
    }
    if shard {
        bail!("--static-tables runs the whole campaign: run it without --shard");
    }
    if probing {
        bail!(
            "--static-tables compares tables with the hybrid without probing: run it without \
             --probe-every"
        );
    }
    Ok(())
}

/// The seeds of `items` (each a seed `N` or an inclusive range `A..B`), in order; `option`
/// names the option in errors.
///
/// # Errors
/// An item that is neither, a range backwards or open, no seed at all, more than
/// `MAX_SEEDS` (1,000,000), a seed given twice.
pub fn parse_seeds(option: &str, items: &[String]) -> Result<Vec<u64>> {
    let mut seeds = Vec::new();
    for item in items {
        let item = item.trim();
        let number = |v: &str| -> Result<u64> {
            v.trim().parse::<u64>().map_err(|_| {
                anyhow::anyhow!(
                    "{option} {item}: expected a seed (whole number ≥ 0) or a range A..B, e.g. 1..200"
                )
            })
        };
        match item.split_once("..") {
            Some((a, b)) => {
                if a.trim().is_empty() || b.trim().is_empty() {
                    bail!("{option} {item}: a range needs both ends, e.g. 1..200 (inclusive)");
                }
                let (a, b) = (number(a)?, number(b)?);
                if b < a {
                    bail!("{option} {item}: the range is backwards (it would be empty); write {b}..{a}");
                }
                if b - a >= MAX_SEEDS || seeds.len() as u64 + (b - a + 1) > MAX_SEEDS {
                    bail!("{option} {item}: more than {MAX_SEEDS} seeds");
                }
                seeds.extend(a..=b);
            }
            None if item.is_empty() => {}
            None => seeds.push(number(item)?),
        }
    }
    if seeds.is_empty() {
        bail!("{option} needs at least one seed");
    }
    commands::check_distinct_seeds(option, &seeds)?;
    Ok(seeds)
}

/// Arguments of `merge`.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// The shard folders (each written by a command with --shard I/N --out DIR), in any order.
    #[arg(required = true, value_name = "DIR")]
    pub shards: Vec<PathBuf>,
    /// Folder for the merged results (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub force: ForceArg,
    /// Also print the full table, one row per run (campaign).
    #[arg(long)]
    pub runs: bool,
    /// Write a Rerun recording of the fleet: a histogram across machines of each fleet figure,
    /// and the summary.
    #[arg(long, value_name = "FILE.rrd")]
    pub rrd: Option<PathBuf>,
    /// Write the fleet's histograms as a PNG picture.
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,
}

impl MergeArgs {
    /// The config.
    pub fn config(self) -> crate::shard::MergeConfig {
        crate::shard::MergeConfig {
            shard_dirs: self.shards,
            out_dir: self.out,
            force: self.force.force,
            print_runs: self.runs,
            rrd: self.rrd,
            png: self.png,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seeds(s: &str) -> Result<Vec<u64>> {
        let items: Vec<String> = s.split(',').map(String::from).collect();
        parse_seeds("--seeds", &items)
    }

    #[test]
    fn seed_lists_and_inclusive_ranges_combine_in_order() {
        assert_eq!(seeds("1,2,3").unwrap(), vec![1, 2, 3]);
        assert_eq!(seeds("1..4").unwrap(), vec![1, 2, 3, 4]);
        assert_eq!(seeds("7,1..3,10..10").unwrap(), vec![7, 1, 2, 3, 10]);
        assert_eq!(seeds("1..1000").unwrap().len(), 1000);
    }

    #[test]
    fn bad_seed_ranges_are_refused_each_with_its_message() {
        let e = |s: &str| seeds(s).unwrap_err().to_string();
        assert_eq!(
            e("5..1"),
            "--seeds 5..1: the range is backwards (it would be empty); write 1..5"
        );
        assert!(e("3..").contains("a range needs both ends"), "{}", e("3.."));
        assert!(e("..").contains("a range needs both ends"));
        assert_eq!(e(""), "--seeds needs at least one seed");
        assert!(e("a..3").contains("expected a seed"));
        assert!(e("1..3,2").contains("seed 2 is given twice"));
        assert!(e("0..18446744073709551615").contains("more than"));
    }
}
