//! Sharded sensor-placement studies and their merge, through the real binary: the merge of any
//! split of a small study writes and prints exactly what the unsharded `select-sensors` does,
//! and every set of shards that does not belong together is refused with a message naming them.

mod common;

use common::{ok, refused, vmc, TempDir};

/// The smallest study that still has a selection and a comparison over two machine seeds: one
/// sensor besides ambient among the reference machine's own locations (the "study default" set
/// must be among the candidates), no random set; three sets compared on seeds 1 and 2.
const STUDY: [&str; 12] = [
    "select-sensors",
    "--count",
    "1",
    "--candidates",
    "headstock_right,headstock_front,spindle_housing,spindle_nose,x_motor,x_support,y_motor,y_support,column_top_front,column_bottom_front,work_zone",
    "--compare-seeds",
    "1,2",
    "--random-draws",
    "0",
    "-o",
    "sensors.toml",
    "--json",
];

/// The study's arguments with `extra` after them (`--json` first takes its file).
fn study_args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut a: Vec<&str> = STUDY.to_vec();
    a.push("study.json");
    a.extend(extra);
    a
}

/// What a command printed, without the lines naming the files it wrote.
fn report(stdout: &str) -> String {
    let lines: Vec<&str> = stdout
        .lines()
        .filter(|l| !l.starts_with("wrote "))
        .collect();
    assert!(lines.len() > 10, "{stdout}");
    lines.join("\n")
}

#[test]
fn merged_shards_equal_the_unsharded_study_bit_for_bit_for_1_2_and_3_shards() {
    let tmp = TempDir::new("selmerge");
    let dir = tmp.path();
    std::fs::create_dir_all(dir.join("whole")).unwrap();
    let splits = [1usize, 2, 3];
    // The unsharded study and every shard of every split, at once.
    let (unsharded, shard_outs) = std::thread::scope(|s| {
        let whole = s.spawn(|| ok(&vmc(&dir.join("whole"), &study_args(&[])), "unsharded"));
        let shards: Vec<_> = splits
            .iter()
            .flat_map(|&n| (1..=n).map(move |i| (n, i)))
            .map(|(n, i)| {
                s.spawn(move || {
                    let (shard, name) = (format!("{i}/{n}"), format!("n{n}-s{i}"));
                    let args = study_args(&["--shard", &shard, "--shard-dir", &name]);
                    ok(&vmc(dir, &args), &format!("shard {shard}"))
                })
            })
            .collect();
        let shards: Vec<String> = shards.into_iter().map(|h| h.join().unwrap()).collect();
        (whole.join().unwrap(), shards)
    });
    // 3 shards of 2 seeds: shard 1/3 is empty, writes no selection stage, and merges as well.
    assert!(
        shard_outs
            .iter()
            .any(|o| o.starts_with("select-sensors shard 1/3: 0 of 2 compare seeds")),
        "{shard_outs:?}"
    );
    assert!(!dir.join("n3-s1/selection.json").exists());
    let whole_toml = std::fs::read(dir.join("whole/sensors.toml")).unwrap();
    let whole_json = std::fs::read(dir.join("whole/study.json")).unwrap();
    for n in splits {
        let out = format!("merged{n}");
        let mut args = vec!["merge".to_string()];
        args.extend((1..=n).rev().map(|i| format!("n{n}-s{i}")));
        args.extend(["--out".to_string(), out.clone()]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let merged = ok(&vmc(dir, &args), &format!("merge of {n}"));
        let read = |f: &str| std::fs::read(dir.join(&out).join(f)).unwrap();
        assert!(read("sensors.toml") == whole_toml, "{n} shards: sensor set");
        assert!(read("study.json") == whole_json, "{n} shards: study.json");
        assert_eq!(report(&merged), report(&unsharded), "{n} shards");
        assert!(
            merged.contains(&format!("wrote {out}/sensors.toml\nwrote {out}/study.json")),
            "{merged}"
        );
    }
    assert!(
        unsharded.contains("machine seeds 1,2):") && unsharded.contains("all candidates"),
        "{unsharded}"
    );
    // A shard whose selection stage was altered after it wrote it is refused by its checksum,
    // naming the file.
    std::fs::create_dir_all(dir.join("altered")).unwrap();
    for f in ["shard.json", "selection.json", "compare.jsonl"] {
        std::fs::copy(dir.join("n2-s2").join(f), dir.join("altered").join(f)).unwrap();
    }
    let sel = std::fs::read_to_string(dir.join("altered/selection.json")).unwrap();
    std::fs::write(
        dir.join("altered/selection.json"),
        sel.replacen("select-sensors on", "select-sensors  on", 1),
    )
    .unwrap();
    let e = refused(
        &vmc(dir, &["merge", "n2-s1", "altered", "--out", "m"]),
        "altered",
    );
    assert!(
        e.contains("altered/selection.json: changed since its shard wrote it"),
        "{e}"
    );
}

#[test]
fn merge_refuses_select_shards_that_do_not_belong_together_naming_them() {
    let tmp = TempDir::new("selrefuse");
    let dir = tmp.path();
    // Two compare seeds in five shards: shards 1/5, 2/5 and 4/5 are empty and cost nothing.
    let shard = |i: &str, name: &str, count: &str| {
        let mut args = study_args(&["--shard", i, "--shard-dir", name]);
        args[2] = count;
        ok(&vmc(dir, &args), name);
    };
    shard("1/5", "a1", "1");
    // An empty shard written with --force over another run's folder leaves no stale stage.
    std::fs::write(dir.join("a1/selection.json"), "{}").unwrap();
    let again = study_args(&["--shard", "1/5", "--shard-dir", "a1", "--force"]);
    ok(&vmc(dir, &again), "a1 again");
    assert!(!dir.join("a1/selection.json").exists());
    shard("2/5", "a2", "1");
    shard("2/5", "count2", "2");
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
        e.contains("shards 3/5, 4/5, 5/5 of 5 missing (given: 1/5, 2/5)"),
        "{e}"
    );
    let e = merge(&["a1", "a2", "a2"]);
    assert!(e.contains("shard 2/5 is given twice: a2 and a2"), "{e}");
    let e = merge(&["a1", "count2"]);
    assert!(
        e.contains("a1 and count2 were run on different inputs (count)"),
        "{e}"
    );
    let e = merge(&["a1", "c1"]);
    assert!(
        e.contains("c1 is a shard of `campaign`, a1 of `select-sensors`"),
        "{e}"
    );
    let e = merge(&["c1", "a1"]);
    assert!(
        e.contains("a1 is a shard of `select-sensors`, c1 of `campaign`"),
        "{e}"
    );
    assert!(!dir.join("m").exists(), "nothing written on a refusal");
}

#[test]
fn bad_select_shards_get_one_clear_message_each() {
    let tmp = TempDir::new("selbad");
    let dir = tmp.path();
    let cases: [(&[&str], &str); 5] = [
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
            &["--shard", "1/2", "--shard-dir", "o", "--no-compare"],
            "with --no-compare there is nothing to split",
        ),
    ];
    for (args, msg) in cases {
        let a = study_args(args);
        let e = refused(&vmc(dir, &a), &a.join(" "));
        assert!(e.contains(msg), "{}: {e}", a.join(" "));
    }
    // --shard and --shard-dir go together (the argument parser says which is missing).
    for (args, missing) in [
        (["--shard", "1/2"], "--shard-dir"),
        (["--shard-dir", "o"], "--shard"),
    ] {
        let out = vmc(dir, &study_args(&args));
        assert!(!out.status.success(), "{args:?} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(missing), "{args:?}: {err}");
    }
    assert!(!dir.join("o").exists(), "nothing written on a refusal");
}
