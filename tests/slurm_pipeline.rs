//! The Slurm pipeline of deploy/slurm on a one-node cluster started on this machine
//! (`deploy/slurm/local-cluster.sh up`): a job array of 4 campaign shards and the merge job that
//! depends on it give the unsharded campaign's report.json and summary, bit for bit. Where Slurm
//! cannot be installed or started (not root, no apt, no network), the test says it was skipped
//! and why.

mod common;

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use common::{repo_file, vmc, TempDir, BIN};

/// Runs a script of deploy/slurm with the cluster's configuration (and `VMC_COMMAND` if given);
/// gives (status ok, stdout, stderr).
fn script(name: &str, args: &[&str], conf: &Path) -> (bool, String, String) {
    script_of(None, name, args, conf)
}

/// [`script`] with the sharded command `VMC_COMMAND` (None: the campaign).
fn script_of(
    command: Option<&str>,
    name: &str,
    args: &[&str],
    conf: &Path,
) -> (bool, String, String) {
    let mut cmd = Command::new(repo_file(&format!("deploy/slurm/{name}")));
    cmd.args(args).env("SLURM_CONF", conf).env("VMC_TWIN", BIN);
    if let Some(c) = command {
        cmd.env("VMC_COMMAND", c);
    }
    let out = cmd.output().expect("the script starts");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// Whether job `id` is still in the queue.
fn queued(id: &str, conf: &Path) -> bool {
    Command::new("squeue")
        .args(["-h", "-j", id])
        .env("SLURM_CONF", conf)
        .output()
        .map(|o| !String::from_utf8_lossy(&o.stdout).trim().is_empty())
        .unwrap_or(false)
}

#[test]
fn a_four_task_array_and_its_merge_job_give_the_unsharded_campaign_bit_for_bit() {
    let uid = Command::new("id").arg("-u").output().map(|o| o.stdout);
    if !uid.is_ok_and(|u| u.trim_ascii() == b"0") {
        eprintln!("skipped: starting the Slurm daemons of the local cluster needs root");
        return;
    }
    let slurm_dir = std::env::var("VMC_SLURM_DIR").unwrap_or("/tmp/vmc-slurm".into());
    let conf = Path::new(&slurm_dir).join("slurm.conf");
    let was_up = Path::new(&slurm_dir).join("slurmctld.pid").exists();
    let (up, _, err) = script("local-cluster.sh", &["up"], &conf);
    if !up {
        eprintln!("skipped: no local Slurm cluster here: {}", err.trim());
        return;
    }
    let tmp = TempDir::new("slurm");
    let dir = tmp.path();
    // The smallest campaign: two machines, so two of the four array tasks have no seed.
    let whole = vmc(dir, &["campaign", "--seeds", "1..2", "--out", "whole"]);
    assert!(whole.status.success());
    let whole = String::from_utf8(whole.stdout).unwrap();
    let out = dir.join("pipeline");
    let out_s = out.to_str().unwrap();
    let (ok, ids, err) = script("submit.sh", &[out_s, "4", "1", "--seeds", "1..2"], &conf);
    assert!(ok, "submit: {err}");
    wait_for_merge(&ids, &conf);
    let logs = |f: &str| std::fs::read_to_string(out.join("logs").join(f)).unwrap_or_default();
    let merged = std::fs::read(out.join("merged/report.json"))
        .unwrap_or_else(|e| panic!("no merged report ({e}); merge log: {}", logs("merge.err")));
    let report = std::fs::read(dir.join("whole/report.json")).unwrap();
    assert!(merged == report, "the merged report.json differs");
    let summary = std::fs::read_to_string(out.join("summary.txt")).unwrap();
    let body = |s: &str| -> String {
        let lines: Vec<&str> = s.lines().collect();
        lines[..lines.len() - 1].join("\n")
    };
    assert_eq!(body(&summary), body(&whole));
    for i in 1..=4 {
        assert!(
            logs(&format!("shard-{i}.err")).contains(&format!("shard {i}/4 end")),
            "array task {i} did not finish: {}",
            logs(&format!("shard-{i}.err"))
        );
    }
    lobes_pipeline(dir, &conf);
    if !was_up {
        let (down, _, err) = script("local-cluster.sh", &["down"], &conf);
        assert!(down, "{err}");
    }
}

/// Waits until the merge job of `ids` (array job, merge job) has left the queue.
fn wait_for_merge(ids: &str, conf: &Path) {
    let merge_job = ids
        .split_whitespace()
        .nth(1)
        .expect("two job ids")
        .to_string();
    let start = Instant::now();
    while queued(&merge_job, conf) {
        assert!(
            start.elapsed() < Duration::from_secs(1800),
            "the pipeline did not finish in 30 min"
        );
        std::thread::sleep(Duration::from_millis(500));
    }
}

/// `VMC_COMMAND=lobes`: 3 array tasks over 41 speeds and the merge give the unsharded CSV and
/// report.
fn lobes_pipeline(dir: &Path, conf: &Path) {
    let opts = [
        "--immersion",
        "0.05",
        "--rpm",
        "5000:25000:41",
        "--out",
        "lobes.csv",
    ];
    let whole = vmc(dir, &[&["lobes"][..], &opts[..]].concat());
    assert!(whole.status.success());
    let out = dir.join("lobes-pipeline");
    let mut args = vec![out.to_str().unwrap(), "3", "1"];
    args.extend(opts);
    let (ok, ids, err) = script_of(Some("lobes"), "submit.sh", &args, conf);
    assert!(ok, "submit: {err}");
    wait_for_merge(&ids, conf);
    let merged = std::fs::read(out.join("merged/lobes.csv")).unwrap_or_else(|e| {
        let log = std::fs::read_to_string(out.join("logs/merge.err")).unwrap_or_default();
        panic!("no merged lobes.csv ({e}); merge log: {log}")
    });
    assert!(merged == std::fs::read(dir.join("lobes.csv")).unwrap());
    let summary = std::fs::read_to_string(out.join("summary.txt")).unwrap();
    let whole = String::from_utf8(whole.stdout).unwrap();
    let body = |s: &str| {
        s.lines()
            .take_while(|l| !l.starts_with("wrote "))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(body(&summary), body(&whole));
}
