//! Sharded campaigns and their merge, through the real binary: the merge of any split of the
//! default campaign writes and prints exactly what the unsharded campaign does, and every set
//! of shards that does not belong together is refused with a message naming them.

mod common;

use std::path::Path;

use common::{ok, refused, vmc, TempDir};

/// What the campaign prints, without the last line (which names the output folder).
fn printed(stdout: &str) -> String {
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines.last().unwrap().starts_with("wrote "), "{stdout}");
    lines[..lines.len() - 1].join("\n")
}

/// Every shard of an `n`-way split of the default campaign, run at once, into `dir/n<k>-s<i>`.
fn run_shards(dir: &Path, n: usize) -> Vec<String> {
    let names: Vec<String> = (1..=n).map(|i| format!("n{n}-s{i}")).collect();
    std::thread::scope(|s| {
        let handles: Vec<_> = names
            .iter()
            .enumerate()
            .map(|(k, name)| {
                let shard = format!("{}/{n}", k + 1);
                s.spawn(move || {
                    let out = vmc(dir, &["campaign", "--shard", &shard, "--out", name]);
                    ok(&out, &format!("shard {shard}"));
                })
            })
            .collect();
        for h in handles {
            h.join().unwrap();
        }
    });
    names
}

#[test]
fn merged_shards_equal_the_unsharded_campaign_bit_for_bit_for_1_2_3_4_and_7_shards() {
    let tmp = TempDir::new("merge");
    let dir = tmp.path();
    let unsharded = ok(
        &vmc(dir, &["campaign", "--out", "whole", "--runs"]),
        "campaign",
    );
    let report = std::fs::read(dir.join("whole/report.json")).unwrap();
    for n in [1, 2, 3, 4, 7] {
        let shards = run_shards(dir, n);
        // 7 shards of 3 seeds: four are empty, and must merge as well.
        let empty = shards
            .iter()
            .filter(|s| {
                let m = std::fs::read_to_string(dir.join(s).join("shard.json")).unwrap();
                m.contains("\"work_ids\": []")
            })
            .count();
        assert_eq!(empty, n.saturating_sub(3), "{n} shards");
        let out = format!("merged{n}");
        let mut args = vec!["merge"];
        args.extend(shards.iter().rev().map(String::as_str));
        args.extend(["--out", &out, "--runs"]);
        let merged = ok(&vmc(dir, &args), &format!("merge of {n}"));
        assert!(
            std::fs::read(dir.join(&out).join("report.json")).unwrap() == report,
            "{n} shards: report.json differs from the unsharded one"
        );
        assert_eq!(printed(&merged), printed(&unsharded), "{n} shards");
        for seed in 1..=3 {
            for kind in ["hybrid", "volumetric", "linear"] {
                let f = format!("model_{kind}_seed{seed}.json");
                assert!(
                    std::fs::read(dir.join(&out).join(&f)).unwrap()
                        == std::fs::read(dir.join("whole").join(&f)).unwrap(),
                    "{n} shards: {f}"
                );
            }
        }
    }
    assert!(unsharded.contains("fleet of 3 machines"), "{unsharded}");
}

/// Rewrites a field of a copy of a shard folder's manifest.
fn copy_with(dir: &Path, from: &str, to: &str, field: &str, old: &str, new: &str) {
    std::fs::create_dir_all(dir.join(to)).unwrap();
    for e in std::fs::read_dir(dir.join(from)).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), dir.join(to).join(e.file_name())).unwrap();
    }
    let path = dir.join(to).join("shard.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let (a, b) = (format!("\"{field}\": {old}"), format!("\"{field}\": {new}"));
    assert!(text.contains(&a), "{text}");
    std::fs::write(&path, text.replace(&a, &b)).unwrap();
}

#[test]
fn merge_refuses_shards_that_do_not_belong_together_naming_them() {
    let tmp = TempDir::new("refuse");
    let dir = tmp.path();
    // One seed in four shards: shards 1/4 to 3/4 are empty, so these cost nothing.
    let shard = |i: &str, name: &str, extra: &[&str]| {
        let mut args = vec!["campaign", "--seeds", "1", "--shard", i, "--out", name];
        args.extend(extra);
        ok(&vmc(dir, &args), name);
    };
    shard("1/4", "a1", &[]);
    shard("2/4", "a2", &[]);
    shard("3/4", "a3", &[]);
    shard("2/4", "seeds2", &["--seeds", "2"]);
    shard("2/4", "spindle", &["--spindle-speed"]);
    shard("2/3", "three", &[]);
    copy_with(dir, "a2", "newer", "version", "\"0", "\"99.0");
    copy_with(
        dir,
        "a2",
        "other",
        "command",
        "\"campaign\"",
        "\"select-sensors\"",
    );
    std::fs::create_dir_all(dir.join("plain")).unwrap();
    let merge = |dirs: &[&str]| {
        let mut args = vec!["merge"];
        args.extend(dirs);
        args.extend(["--out", "m"]);
        refused(&vmc(dir, &args), &dirs.join(" "))
    };
    let e = merge(&["a1", "a2", "a3"]);
    assert!(
        e.contains("shard 4/4 of 4 missing (given: 1/4, 2/4, 3/4)"),
        "{e}"
    );
    let e = merge(&["a1", "a2", "a2", "a3"]);
    assert!(e.contains("shard 2/4 is given twice: a2 and a2"), "{e}");
    let e = merge(&["a1", "seeds2", "a3"]);
    assert!(
        e.contains("a1 and seeds2 were run on different inputs (seeds)"),
        "{e}"
    );
    let e = merge(&["a1", "spindle", "a3"]);
    assert!(e.contains("different inputs (settings"), "{e}");
    let e = merge(&["a1", "newer", "a3"]);
    assert!(
        e.contains("newer by version 99.0") && e.contains("different versions"),
        "{e}"
    );
    let e = merge(&["a1", "other", "a3"]);
    assert!(
        e.contains("other is a shard of `select-sensors`, a1 of `campaign`"),
        "{e}"
    );
    let e = merge(&["a1", "three"]);
    assert!(e.contains("shards of different splits"), "{e}");
    let e = merge(&["a1", "plain"]);
    assert!(e.contains("plain: not a shard folder"), "{e}");
    assert!(!dir.join("m").exists(), "nothing written on a refusal");
}

#[test]
fn bad_shards_and_seed_ranges_get_one_clear_message_each() {
    let tmp = TempDir::new("bad");
    let dir = tmp.path();
    let cases: [(&[&str], &str); 8] = [
        (
            &["--shard", "0/4", "--out", "o"],
            "--shard 0/4: the shard must be between 1/4 and 4/4",
        ),
        (
            &["--shard", "5/4", "--out", "o"],
            "--shard 5/4: the shard must be between 1/4 and 4/4",
        ),
        (
            &["--shard", "1/0", "--out", "o"],
            "--shard 1/0: the number of shards must be at least 1",
        ),
        (&["--shard", "two", "--out", "o"], "expected I/N"),
        (&["--shard", "1/2"], "--shard 1/2 needs --out DIR"),
        (
            &["--seeds", "5..1"],
            "--seeds 5..1: the range is backwards (it would be empty); write 1..5",
        ),
        (&["--seeds", ""], "--seeds needs at least one seed"),
        (&["--seeds", "3.."], "a range needs both ends"),
    ];
    for (args, msg) in cases {
        let mut a = vec!["campaign"];
        a.extend(args);
        let e = refused(&vmc(dir, &a), &a.join(" "));
        assert!(e.contains(msg), "{}: {e}", a.join(" "));
    }
}
