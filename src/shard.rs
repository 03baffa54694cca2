//! Splitting a long command's work over independent processes (a scheduler's array tasks) and
//! checking that a set of shard results belongs together before they are merged.
//!
//! A command enumerates its work list deterministically (the campaign: one item per machine
//! seed, in the order given). Shard `I/N` (1-based) takes the contiguous block
//! `⌊(I−1)·n/N⌋ .. ⌊I·n/N⌋` of the `n` items, so the blocks cover the list once, in order, and
//! differ in size by at most one; with more shards than items some blocks are empty. Each shard
//! writes a [`ShardManifest`] (`shard.json`): the work ids it covered, the command line, the
//! program version and a fingerprint of every input. The merge accepts a set of manifests only
//! when they come from the same command, version and inputs and form exactly `1/N … N/N`
//! ([`check_set`]).
//!
//! Fingerprints are 64-bit FNV-1a hashes of the input's bytes: not a defence against a forger,
//! a guard against merging the results of two different studies by mistake.

use std::fmt;
use std::ops::Range;
use std::path::PathBuf;
use std::str::FromStr;

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Version of the `shard.json` layout.
pub const MANIFEST_FORMAT: u32 = 2;

pub mod integrity;

/// Name of the manifest file in a shard's output folder.
pub const MANIFEST_FILE: &str = "shard.json";

/// One shard of a work list: the `index`-th of `count` (1-based, `1 ≤ index ≤ count`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// Which shard, from 1.
    pub index: usize,
    /// How many shards the work list is split into, at least 1.
    pub count: usize,
}

/// A `--shard` value or a set of shards that cannot be used.
#[derive(Debug, Error, PartialEq)]
pub enum ShardError {
    /// Not of the form `I/N`.
    #[error("--shard {0}: expected I/N with whole numbers, e.g. --shard 2/4")]
    Syntax(String),
    /// `N` is zero.
    #[error("--shard {0}: the number of shards must be at least 1")]
    NoShards(String),
    /// `I` outside `1..=N`.
    #[error("--shard {text}: the shard must be between 1/{count} and {count}/{count} (shards count from 1)")]
    OutOfRange {
        /// The value given.
        text: String,
        /// N.
        count: usize,
    },
    /// Nothing to merge.
    #[error("no shard folders given")]
    Empty,
    /// A shard of another command than the first one.
    #[error("{dir} is a shard of `{found}`, {first} of `{expected}`: shards of different commands cannot be merged")]
    OtherCommand {
        /// The odd shard's folder.
        dir: String,
        /// Its command.
        found: String,
        /// The first shard's folder.
        first: String,
        /// The first shard's command.
        expected: String,
    },
    /// Shards written by different program versions.
    #[error("{a} was written by version {va}, {b} by version {vb}: shards of different versions cannot be merged")]
    Version {
        /// First folder.
        a: String,
        /// Its version.
        va: String,
        /// Second folder.
        b: String,
        /// Its version.
        vb: String,
    },
    /// Shards of different inputs (machine, programs, settings, work list).
    #[error("{a} and {b} were run on different inputs ({what}): shards of different studies cannot be merged")]
    Inputs {
        /// First folder.
        a: String,
        /// Second folder.
        b: String,
        /// The inputs that differ, named.
        what: String,
    },
    /// Shards of splits into different numbers of shards.
    #[error("{a} is shard {sa}, {b} is shard {sb}: shards of different splits cannot be merged")]
    Count {
        /// First folder.
        a: String,
        /// Its shard.
        sa: Shard,
        /// Second folder.
        b: String,
        /// Its shard.
        sb: Shard,
    },
    /// The same shard twice.
    #[error("shard {shard} is given twice: {a} and {b}")]
    Duplicate {
        /// The shard.
        shard: Shard,
        /// First folder.
        a: String,
        /// Second folder.
        b: String,
    },
    /// Shards missing from the set.
    #[error("shard{} {} of {count} missing (given: {given})", if missing.len() > 1 { "s" } else { "" }, missing.join(", "), count = count)]
    Missing {
        /// The missing shards, `I/N`.
        missing: Vec<String>,
        /// N.
        count: usize,
        /// The shards given, `I/N`.
        given: String,
    },
    /// A shard whose work ids are not its block of the work list.
    #[error(
        "{dir}: shard {shard} covers {found} work items, its block of the {total} has {expected}"
    )]
    Coverage {
        /// The folder.
        dir: String,
        /// The shard.
        shard: Shard,
        /// Work ids it lists.
        found: usize,
        /// Work ids its block has.
        expected: usize,
        /// Length of the work list.
        total: usize,
    },
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = ShardError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let text = s.trim();
        let (i, n) = text
            .split_once('/')
            .ok_or_else(|| ShardError::Syntax(text.into()))?;
        let parse = |v: &str| {
            v.trim()
                .parse::<usize>()
                .map_err(|_| ShardError::Syntax(text.into()))
        };
        let (index, count) = (parse(i)?, parse(n)?);
        if count == 0 {
            return Err(ShardError::NoShards(text.into()));
        }
        if index == 0 || index > count {
            return Err(ShardError::OutOfRange {
                text: text.into(),
                count,
            });
        }
        Ok(Shard { index, count })
    }
}

impl Shard {
    /// The whole work list as one shard (`1/1`).
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// This shard's block of a work list of `len` items: `⌊(I−1)·len/N⌋ .. ⌊I·len/N⌋`.
    pub fn block(&self, len: usize) -> Range<usize> {
        let at = |i: usize| (i as u128 * len as u128 / self.count as u128) as usize;
        at(self.index - 1)..at(self.index)
    }
}

/// 64-bit FNV-1a hash of `bytes` (offset basis 0xcbf29ce484222325, prime 0x100000001b3).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The fingerprint of one input of a sharded command.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputFingerprint {
    /// What the input is (`machine`, `program XY`, `settings`, `seeds`, …).
    pub name: String,
    /// Where it came from: a file path, `embedded` for the built-in reference, or `arguments`.
    pub source: String,
    /// FNV-1a 64 of its bytes, 16 hex digits.
    pub fnv1a64: String,
}

impl InputFingerprint {
    /// The fingerprint of `bytes`, named.
    pub fn of(name: &str, source: &str, bytes: &[u8]) -> Self {
        Self {
            name: name.into(),
            source: source.into(),
            fnv1a64: format!("{:016x}", fnv1a64(bytes)),
        }
    }
}

/// What a shard writes next to its results (`shard.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardManifest {
    /// Layout version ([`MANIFEST_FORMAT`]).
    pub format: u32,
    /// The command that wrote it (`campaign`).
    pub command: String,
    /// Which shard.
    pub shard: Shard,
    /// The work ids this shard covered, in order (e.g. `seed 17`).
    pub work_ids: Vec<String>,
    /// Length of the whole work list.
    pub work_total: usize,
    /// The command line that ran the shard.
    pub command_line: Vec<String>,
    /// The program version.
    pub version: String,
    /// A fingerprint of every input (machine, programs, settings, the work list).
    pub inputs: Vec<InputFingerprint>,
    /// What the command needs to merge, beyond the per-item results (the campaign: the
    /// report's header).
    pub header: serde_json::Value,
    /// The result files with their size and hash, checked by `merge` (see [`integrity`]);
    /// absent (empty) in layout version 1, which `merge` refuses.
    #[serde(default)]
    pub results: Vec<integrity::ResultFile>,
}

/// Checks that `shards` (each with the folder it was read from) form one complete split of one
/// study: the same command as the first, the same version and inputs, shards `1/N … N/N` once
/// each, each covering its block. Gives the positions of `shards` in shard order.
///
/// # Errors
/// The first problem found, naming the folders involved.
pub fn check_set(shards: &[(String, ShardManifest)]) -> Result<Vec<usize>, ShardError> {
    let (first_dir, first) = shards.first().ok_or(ShardError::Empty)?;
    for (dir, m) in shards {
        if m.command != first.command {
            return Err(ShardError::OtherCommand {
                dir: dir.clone(),
                found: m.command.clone(),
                first: first_dir.clone(),
                expected: first.command.clone(),
            });
        }
    }
    for (dir, m) in shards {
        if m.version != first.version {
            return Err(ShardError::Version {
                a: first_dir.clone(),
                va: first.version.clone(),
                b: dir.clone(),
                vb: m.version.clone(),
            });
        }
        let differ = differing_inputs(&first.inputs, &m.inputs);
        let differ = if differ.is_empty() && (m.header != first.header) {
            "the report header".to_string()
        } else {
            differ
        };
        if !differ.is_empty() || m.work_total != first.work_total {
            return Err(ShardError::Inputs {
                a: first_dir.clone(),
                b: dir.clone(),
                what: if differ.is_empty() {
                    "length of the work list".into()
                } else {
                    differ
                },
            });
        }
        if m.shard.count != first.shard.count {
            return Err(ShardError::Count {
                a: first_dir.clone(),
                sa: first.shard,
                b: dir.clone(),
                sb: m.shard,
            });
        }
    }
    let count = first.shard.count;
    let mut at: Vec<Option<usize>> = vec![None; count];
    for (k, (dir, m)) in shards.iter().enumerate() {
        let slot = &mut at[m.shard.index - 1];
        if let Some(prev) = *slot {
            return Err(ShardError::Duplicate {
                shard: m.shard,
                a: shards[prev].0.clone(),
                b: dir.clone(),
            });
        }
        *slot = Some(k);
        let expected = m.shard.block(m.work_total).len();
        if m.work_ids.len() != expected {
            return Err(ShardError::Coverage {
                dir: dir.clone(),
                shard: m.shard,
                found: m.work_ids.len(),
                expected,
                total: m.work_total,
            });
        }
    }
    let missing: Vec<String> = (1..=count)
        .filter(|i| at[i - 1].is_none())
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        let given: Vec<String> = (1..=count)
            .filter(|i| at[i - 1].is_some())
            .map(|i| format!("{i}/{count}"))
            .collect();
        return Err(ShardError::Missing {
            missing,
            count,
            given: given.join(", "),
        });
    }
    Ok(at.into_iter().flatten().collect())
}

/// The names of the inputs whose fingerprints differ or that only one list has, `, `-joined
/// (empty when they agree).
fn differing_inputs(a: &[InputFingerprint], b: &[InputFingerprint]) -> String {
    let mut names: Vec<&str> = Vec::new();
    for x in a {
        if !b.iter().any(|y| y.name == x.name && y.fnv1a64 == x.fnv1a64) {
            names.push(&x.name);
        }
    }
    for y in b {
        if !a.iter().any(|x| x.name == y.name) && !names.contains(&y.name.as_str()) {
            names.push(&y.name);
        }
    }
    names.join(", ")
}

/// What to merge, validated.
pub struct MergeConfig {
    /// The shard folders (each with its `shard.json`), in any order.
    pub shard_dirs: Vec<PathBuf>,
    /// Folder for the merged results.
    pub out_dir: PathBuf,
    /// Overwrite existing output files.
    pub force: bool,
    /// Print the per-run table too (campaign).
    pub print_runs: bool,
    /// A Rerun recording of the fleet's histograms and the summary.
    pub rrd: Option<PathBuf>,
    /// A PNG picture of the fleet's histograms.
    pub png: Option<PathBuf>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest(index: usize, count: usize, total: usize) -> ShardManifest {
        let shard = Shard { index, count };
        ShardManifest {
            format: MANIFEST_FORMAT,
            command: "campaign".into(),
            shard,
            work_ids: shard.block(total).map(|k| format!("seed {k}")).collect(),
            work_total: total,
            command_line: vec![],
            version: "1.0".into(),
            inputs: vec![InputFingerprint::of("machine", "embedded", b"m")],
            header: serde_json::Value::Null,
            results: Vec::new(),
        }
    }

    fn set(ms: Vec<ShardManifest>) -> Vec<(String, ShardManifest)> {
        ms.into_iter()
            .enumerate()
            .map(|(k, m)| (format!("d{k}"), m))
            .collect()
    }

    #[test]
    fn fnv1a64_matches_the_published_test_vectors() {
        assert_eq!(fnv1a64(b""), 0xcbf29ce484222325);
        assert_eq!(fnv1a64(b"a"), 0xaf63dc4c8601ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x85944171f73967e8);
    }

    #[test]
    fn blocks_cover_the_list_once_in_order_and_differ_by_at_most_one() {
        for len in 0..30 {
            for count in 1..12 {
                let blocks: Vec<Range<usize>> = (1..=count)
                    .map(|index| Shard { index, count }.block(len))
                    .collect();
                assert_eq!(blocks[0].start, 0);
                assert_eq!(blocks[count - 1].end, len);
                for w in blocks.windows(2) {
                    assert_eq!(w[0].end, w[1].start);
                }
                let sizes: Vec<usize> = blocks.iter().map(|b| b.len()).collect();
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(hi - lo <= 1, "{len} in {count}: {sizes:?}");
            }
        }
    }

    #[test]
    fn shard_values_parse_and_bad_ones_are_refused_each_with_its_message() {
        assert_eq!("2/4".parse(), Ok(Shard { index: 2, count: 4 }));
        assert_eq!(
            "0/4".parse::<Shard>().unwrap_err().to_string(),
            "--shard 0/4: the shard must be between 1/4 and 4/4 (shards count from 1)"
        );
        assert!(matches!(
            "5/4".parse::<Shard>(),
            Err(ShardError::OutOfRange { count: 4, .. })
        ));
        assert_eq!(
            "1/0".parse::<Shard>().unwrap_err().to_string(),
            "--shard 1/0: the number of shards must be at least 1"
        );
        for bad in ["", "3", "a/4", "1/-2", "1/2/3"] {
            assert!(
                matches!(bad.parse::<Shard>(), Err(ShardError::Syntax(_))),
                "{bad}"
            );
        }
    }

    #[test]
    fn a_complete_set_in_any_order_is_accepted_in_shard_order() {
        let s = set(vec![
            manifest(3, 3, 5),
            manifest(1, 3, 5),
            manifest(2, 3, 5),
        ]);
        assert_eq!(check_set(&s), Ok(vec![1, 2, 0]));
    }

    #[test]
    fn every_bad_set_is_refused_naming_the_shards() {
        let e = check_set(&set(vec![manifest(1, 3, 5), manifest(3, 3, 5)])).unwrap_err();
        assert_eq!(e.to_string(), "shard 2/3 of 3 missing (given: 1/3, 3/3)");
        let e = check_set(&set(vec![manifest(1, 2, 5), manifest(1, 2, 5)])).unwrap_err();
        assert_eq!(e.to_string(), "shard 1/2 is given twice: d0 and d1");
        let mut other = manifest(2, 2, 5);
        other.command = "select-sensors".into();
        let e = check_set(&set(vec![manifest(1, 2, 5), other])).unwrap_err();
        assert!(matches!(e, ShardError::OtherCommand { .. }), "{e}");
        let mut newer = manifest(2, 2, 5);
        newer.version = "1.1".into();
        let e = check_set(&set(vec![manifest(1, 2, 5), newer])).unwrap_err();
        assert!(
            e.to_string().contains("version 1.0, d1 by version 1.1"),
            "{e}"
        );
        let mut moved = manifest(2, 2, 5);
        moved.inputs = vec![InputFingerprint::of("machine", "embedded", b"n")];
        let e = check_set(&set(vec![manifest(1, 2, 5), moved])).unwrap_err();
        assert!(e.to_string().contains("different inputs (machine)"), "{e}");
        let e = check_set(&set(vec![manifest(1, 2, 5), manifest(2, 3, 5)])).unwrap_err();
        assert!(matches!(e, ShardError::Count { .. }), "{e}");
        let mut short = manifest(2, 2, 5);
        short.work_ids.pop();
        let e = check_set(&set(vec![manifest(1, 2, 5), short])).unwrap_err();
        assert!(matches!(e, ShardError::Coverage { .. }), "{e}");
        assert_eq!(check_set(&[]), Err(ShardError::Empty));
    }
}
