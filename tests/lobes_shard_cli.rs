//! Sharded stability lobes and their merge, through the real binary: the merge of any split of
//! the speeds prints and writes exactly what the unsharded `lobes` does (bit for bit, also when
//! a shard's block starts inside a run of the boundary tracer, and with more shards than
//! speeds), with a tool and with a controller; sets of shards that do not belong together and
//! bad `--shard` values are refused in one line.

mod common;

use std::path::Path;

use common::{ok, refused, repo_file, vmc, TempDir};

/// What a command printed, without the lines naming the files it wrote.
fn report(stdout: &str) -> String {
    let lines: Vec<&str> = stdout
        .lines()
        .filter(|l| !l.starts_with("wrote "))
        .collect();
    assert!(lines.len() > 5, "{stdout}");
    lines.join("\n")
}

/// Small lobes: 11 speeds at a_e/D = 0.05, where Hopf and flip lobes alternate; the tracer's
/// runs are speeds 1–8 and 9–11, so the blocks of 2 and 3 shards start inside a run.
const LOBES: [&str; 5] = ["lobes", "--immersion", "0.05", "--rpm", "5000:25000:11"];

/// `LOBES` (or `base`) with `extra` after it.
fn with<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
    let mut a = base.to_vec();
    a.extend(extra);
    a
}

/// Runs every shard of an `n`-way split of `base` at once into `dir/<tag>n<n>-s<i>` and gives
/// their folders and printed lines.
fn run_shards(dir: &Path, base: &[&str], tag: &str, n: usize) -> Vec<(String, String)> {
    let names: Vec<String> = (1..=n).map(|i| format!("{tag}n{n}-s{i}")).collect();
    let printed: Vec<String> = std::thread::scope(|s| {
        let handles: Vec<_> = names
            .iter()
            .enumerate()
            .map(|(k, name)| {
                let shard = format!("{}/{n}", k + 1);
                s.spawn(move || {
                    let args = with(base, &["--shard", &shard, "--shard-dir", name]);
                    ok(&vmc(dir, &args), &format!("shard {shard}"))
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    names.into_iter().zip(printed).collect()
}

/// `merge` of `shards` (given last first) into `out`, with `extra` options.
fn merge(dir: &Path, shards: &[(String, String)], out: &str, extra: &[&str]) -> String {
    let mut args = vec!["merge"];
    args.extend(shards.iter().rev().map(|(name, _)| name.as_str()));
    args.extend(["--out", out]);
    args.extend(extra);
    ok(&vmc(dir, &args), &format!("merge into {out}"))
}

#[test]
fn merged_lobes_shards_equal_the_unsharded_lobes_bit_for_bit_for_1_2_3_and_13_shards() {
    let tmp = TempDir::new("lobesmerge");
    let dir = tmp.path();
    let unsharded = ok(&vmc(dir, &with(&LOBES, &["--out", "l.csv"])), "lobes");
    let whole_csv = std::fs::read(dir.join("l.csv")).unwrap();
    assert!(unsharded.contains("11 speeds"), "{unsharded}");
    for n in [1, 2, 3, 13] {
        let shards = run_shards(dir, &with(&LOBES, &["--out", "l.csv"]), "", n);
        let out = format!("merged{n}");
        let merged = merge(dir, &shards, &out, &[]);
        let csv = std::fs::read(dir.join(&out).join("l.csv")).unwrap();
        assert!(csv == whole_csv, "{n} shards: the CSV differs");
        assert_eq!(report(&merged), report(&unsharded), "{n} shards");
        assert!(
            merged.ends_with(&format!("wrote {out}/l.csv\n")),
            "{merged}"
        );
        if n == 3 {
            assert!(
                shards[1].1.contains("4 of 11 speeds")
                    && shards[1].1.contains("traced from speed 1 of the list"),
                "{shards:?}"
            );
        }
        if n == 13 {
            // 13 shards of 11 speeds: two are empty, and merge as well.
            let empty = shards
                .iter()
                .filter(|(_, printed)| printed.contains("0 of 11 speeds (none"))
                .count();
            assert_eq!(empty, 2, "{shards:?}");
        }
    }
    // Shards without --out merge into lobes.csv; the merge's --rrd records the lobe diagram.
    let shards = run_shards(dir, &LOBES, "plain", 2);
    let merged = merge(dir, &shards, "plain", &["--rrd", "plain.rrd"]);
    assert!(std::fs::read(dir.join("plain/lobes.csv")).unwrap() == whole_csv);
    assert!(merged.contains("wrote plain.rrd ("), "{merged}");
    assert!(dir.join("plain.rrd").is_file());
    // The zero-order method, each speed on its own, merges as well.
    let zoa = with(&LOBES, &["--method", "zoa", "--out", "z.csv"]);
    let whole_zoa = ok(&vmc(dir, &zoa), "zoa");
    let shards = run_shards(dir, &zoa, "zoa", 3);
    let merged = merge(dir, &shards, "zoa", &[]);
    assert!(
        std::fs::read(dir.join("zoa/z.csv")).unwrap() == std::fs::read(dir.join("z.csv")).unwrap()
    );
    assert_eq!(report(&merged), report(&whole_zoa));
}

#[test]
fn merged_controller_lobes_shards_equal_the_unsharded_run_bit_for_bit() {
    let tmp = TempDir::new("lobesctl");
    let dir = tmp.path();
    let plant = repo_file("machines/benchmarks/blade.toml")
        .display()
        .to_string();
    let design = [
        "control",
        "design",
        "--plant",
        &plant,
        "--controller",
        "lqg",
        "-o",
        "ctrl.json",
    ];
    ok(&vmc(dir, &design), "control design");
    // Ten speeds at 40 steps per tooth period: fast, and the shards of 3 start inside a run.
    let lobes = [
        "lobes",
        "--controller",
        "ctrl.json",
        "--rpm",
        "1500:4500:10",
        "--steps",
        "40",
        "--out",
        "c.csv",
    ];
    let unsharded = ok(&vmc(dir, &lobes), "lobes --controller");
    assert!(
        unsharded.contains("closed loop: minimum critical depth"),
        "{unsharded}"
    );
    let whole_csv = std::fs::read(dir.join("c.csv")).unwrap();
    for n in [2, 3] {
        let shards = run_shards(dir, &lobes, "c", n);
        let out = format!("cmerged{n}");
        let merged = merge(dir, &shards, &out, &[]);
        let csv = std::fs::read(dir.join(&out).join("c.csv")).unwrap();
        assert!(csv == whole_csv, "{n} shards: the CSV differs");
        assert_eq!(report(&merged), report(&unsharded), "{n} shards");
    }
}

#[test]
fn merge_refuses_lobes_shards_that_do_not_belong_together_naming_them() {
    let tmp = TempDir::new("lobesrefuse");
    let dir = tmp.path();
    let three = ["lobes", "--immersion", "0.05", "--rpm", "5000,6000,7000"];
    let shard = |base: &[&str], i: &str, name: &str| {
        ok(
            &vmc(dir, &with(base, &["--shard", i, "--shard-dir", name])),
            name,
        );
    };
    shard(&three, "1/3", "a1");
    shard(&three, "2/3", "a2");
    let mut other = three;
    other[2] = "0.1";
    shard(&other, "3/3", "immersion3");
    let campaign = ["campaign", "--seeds", "1", "--shard", "1/4", "--out", "c1"];
    ok(&vmc(dir, &campaign), "campaign shard");
    let merge = |dirs: &[&str]| {
        let mut args = vec!["merge"];
        args.extend(dirs);
        args.extend(["--out", "m"]);
        refused(&vmc(dir, &args), &dirs.join(" "))
    };
    let e = merge(&["a1", "a2"]);
    assert!(
        e.contains("shard 3/3 of 3 missing (given: 1/3, 2/3)"),
        "{e}"
    );
    let e = merge(&["a1", "a2", "a2"]);
    assert!(e.contains("shard 2/3 is given twice: a2 and a2"), "{e}");
    let e = merge(&["a1", "a2", "immersion3"]);
    assert!(
        e.contains("a1 and immersion3 were run on different inputs (immersion)"),
        "{e}"
    );
    let e = merge(&["a1", "c1"]);
    assert!(
        e.contains("c1 is a shard of `campaign`, a1 of `lobes`"),
        "{e}"
    );
    let e = merge(&["c1", "a1"]);
    assert!(
        e.contains("a1 is a shard of `lobes`, c1 of `campaign`"),
        "{e}"
    );
    // Shards at another resolution of the semi-discretisation do not belong together.
    shard(&with(&three, &["--steps", "40"]), "3/3", "steps3");
    let e = merge(&["a1", "a2", "steps3"]);
    assert!(
        e.contains("a1 and steps3 were run on different inputs (resolution)"),
        "{e}"
    );
    assert!(!dir.join("m").exists(), "nothing written on a refusal");
    // A shard whose points were altered after it wrote them is refused by its checksum,
    // naming the file.
    shard(&three, "3/3", "a3");
    let points = std::fs::read_to_string(dir.join("a2/lobes.jsonl")).unwrap();
    std::fs::write(
        dir.join("a2/lobes.jsonl"),
        points.replacen("6000.0", "6000.5", 1),
    )
    .unwrap();
    let e = merge(&["a1", "a2", "a3"]);
    assert!(
        e.contains("a2/lobes.jsonl: changed since its shard wrote it"),
        "{e}"
    );
}

#[test]
fn bad_lobes_shards_get_one_clear_message_each() {
    let tmp = TempDir::new("lobesbad");
    let dir = tmp.path();
    let cases: [(&[&str], &str); 8] = [
        (
            &["--shard", "0/4", "--shard-dir", "o"],
            "--shard 0/4: the shard must be between 1/4 and 4/4",
        ),
        (
            &["--shard", "5/4", "--shard-dir", "o"],
            "--shard 5/4: the shard must be between 1/4 and 4/4",
        ),
        (
            &["--shard", "1/0", "--shard-dir", "o"],
            "--shard 1/0: the number of shards must be at least 1",
        ),
        (&["--shard", "two", "--shard-dir", "o"], "expected I/N"),
        (
            &["--shard", "1/2"],
            "--shard 1/2 needs --shard-dir DIR for the shard's results",
        ),
        (&["--shard-dir", "o"], "give --shard I/N too"),
        (
            &["--shard", "1/2", "--shard-dir", "o", "--rrd", "l.rrd"],
            "pass it to `vmc-twin merge`",
        ),
        (
            &["--shard", "1/2", "--shard-dir", "o", "--out", "/"],
            "give a file name",
        ),
    ];
    for (args, msg) in cases {
        let a = with(&LOBES, args);
        let e = refused(&vmc(dir, &a), &a.join(" "));
        assert!(e.contains(msg), "{}: {e}", a.join(" "));
    }
    assert!(!dir.join("o").exists(), "nothing written on a refusal");
}
