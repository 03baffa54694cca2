//! `vmc-twin control design`, `lobes --controller` and `cut --controller` as a user runs them:
//! the real binary in a temporary folder, on the shipped blade (machines/benchmarks/blade.toml).

mod common;
use common::*;

/// The first number after `prefix` on the first line containing it.
fn number_after(out: &str, prefix: &str) -> f64 {
    let line = out
        .lines()
        .find(|l| l.contains(prefix))
        .unwrap_or_else(|| panic!("no `{prefix}` in:\n{out}"));
    let rest = &line[line.find(prefix).unwrap() + prefix.len()..];
    rest.split_whitespace()
        .next()
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no number after `{prefix}` in `{line}`"))
}

fn blade() -> String {
    repo_file("machines/benchmarks/blade.toml")
        .display()
        .to_string()
}

/// The LQG design on the shipped blade: a stable sampled loop, the first mode attenuated by
/// more than 20 dB, the second by more than 6 dB, and the controller file that the lobes and
/// the cut read: the closed-loop minimum critical depth at least twice the open loop's, and a
/// cut at twice the open-loop minimum that chatters without the controller and is stable with
/// it, its command within the stroke.
#[test]
fn lqg_design_lobes_and_cut_work_end_to_end() {
    let tmp = TempDir::new("control-lqg");
    let plant = blade();
    let out = succeed(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            &plant,
            "--controller",
            "lqg",
            "-o",
            "ctrl.json",
        ],
    );
    assert!(out.contains("wrote ctrl.json"), "{out}");
    assert!(number_after(&out, "spectral radius") < 1.0, "{out}");
    let line1 = out.lines().find(|l| l.contains("mode 1")).unwrap();
    let db1: f64 = line1
        .split_whitespace()
        .rev()
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    let line2 = out.lines().find(|l| l.contains("mode 2")).unwrap();
    let db2: f64 = line2
        .split_whitespace()
        .rev()
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert!(db1 > 20.0 && db2 > 6.0, "{out}");

    let lobes = succeed(
        tmp.path(),
        &[
            "lobes",
            "--controller",
            "ctrl.json",
            "--rpm",
            "1800:2000:5",
            "--steps",
            "40",
            "--out",
            "lobes.csv",
        ],
    );
    let open = number_after(&lobes, "open loop  : minimum critical depth");
    let closed = number_after(&lobes, "closed loop: minimum critical depth");
    assert!(closed > 2.0 * open, "{lobes}");
    assert!(
        lobes.contains("resolution: 40 steps per tooth period at every speed"),
        "{lobes}"
    );
    let csv = std::fs::read_to_string(tmp.path().join("lobes.csv")).unwrap();
    assert_eq!(csv.lines().count(), 6, "{csv}");
    assert!(csv.starts_with(
        "spindle_rpm,open_depth_mm,closed_depth_mm,open_steps_per_period,closed_steps_per_period\n"
    ));
    // Each depth comes with its steps (a speed without a boundary below 50 mm has neither).
    for row in csv.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        for (depth, steps) in [(f[1], f[3]), (f[2], f[4])] {
            assert_eq!(steps, if depth.is_empty() { "" } else { "40" }, "{csv}");
        }
    }

    let depth = format!("{:.4}", 2.0 * open);
    let cut = succeed(
        tmp.path(),
        &[
            "cut",
            "--controller",
            "ctrl.json",
            "--rpm",
            "1900",
            "--depth-mm",
            &depth,
            "--feed-per-tooth-mm",
            "0.08",
            "--revolutions",
            "100",
        ],
    );
    assert!(
        cut.lines()
            .any(|l| l.starts_with("open loop") && l.contains("chatter")),
        "{cut}"
    );
    assert!(
        cut.lines()
            .any(|l| l.starts_with("closed loop") && l.contains("stable")),
        "{cut}"
    );
    assert!(number_after(&cut, "largest command") < 150.0, "{cut}");
}

#[test]
fn hinf_design_prints_gamma_and_strategy_2_needs_its_table() {
    let tmp = TempDir::new("control-hinf");
    let plant = blade();
    let out = succeed(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            &plant,
            "--controller",
            "hinf",
            "--lowpass-hz",
            "2000",
        ],
    );
    assert!(number_after(&out, "gamma") > 0.0, "{out}");
    let text = std::fs::read_to_string(&plant).unwrap();
    let cut_at = text.find("[strategy2]").unwrap();
    std::fs::write(tmp.path().join("no-s2.toml"), &text[..cut_at]).unwrap();
    let o = vmc(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            "no-s2.toml",
            "--controller",
            "lqg",
            "--strategy",
            "2",
        ],
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("[strategy2]"), "{}", stderr(&o));
}

#[test]
fn bad_inputs_are_refused_with_a_reason() {
    let tmp = TempDir::new("control-bad");
    let plant = blade();
    let o = vmc(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            &plant,
            "--controller",
            "lqg",
            "--strategy",
            "3",
        ],
    );
    assert!(
        !o.status.success() && stderr(&o).contains("--strategy"),
        "{}",
        stderr(&o)
    );
    std::fs::write(
        tmp.path().join("bad.json"),
        "{\"format\": \"something else\"}",
    )
    .unwrap();
    let o = vmc(tmp.path(), &["lobes", "--controller", "bad.json"]);
    assert!(
        !o.status.success() && stderr(&o).contains("bad.json"),
        "{}",
        stderr(&o)
    );
    let o = vmc(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            "missing.toml",
            "--controller",
            "lqg",
        ],
    );
    assert!(
        !o.status.success() && stderr(&o).contains("missing.toml"),
        "{}",
        stderr(&o)
    );
}

/// The default resolution of `lobes --controller` (converged, at most 640 steps per tooth
/// period) agrees with a fixed 1280 steps within 0.5 % at a low speed, where the blade's kHz
/// modes span many vibration cycles per tooth period, and at a high one; the steps behind each
/// point are in the CSV.
#[test]
fn controller_lobes_at_the_default_resolution_agree_with_finer_fixed_steps() {
    let tmp = TempDir::new("control-conv");
    let design = [
        "control",
        "design",
        "--plant",
        &blade(),
        "--controller",
        "lqg",
    ];
    succeed(tmp.path(), &[&design[..], &["-o", "ctrl.json"]].concat());
    let lobes = |extra: &[&str], csv: &str| -> Vec<Vec<String>> {
        let base = ["lobes", "--controller", "ctrl.json", "--rpm", "1700,4400"];
        let out = succeed(tmp.path(), &[&base[..], extra, &["--out", csv]].concat());
        assert!(out.contains("resolution: "), "{out}");
        let text = std::fs::read_to_string(tmp.path().join(csv)).unwrap();
        text.lines()
            .skip(1)
            .map(|r| r.split(',').map(String::from).collect())
            .collect()
    };
    let conv = lobes(&[], "conv.csv");
    let fine = lobes(&["--steps", "1280"], "fine.csv");
    assert_eq!(conv.len(), 2);
    for (c, f) in conv.iter().zip(&fine) {
        for col in [1, 2] {
            let (a, b): (f64, f64) = (c[col].parse().unwrap(), f[col].parse().unwrap());
            assert!((a / b - 1.0).abs() < 0.005, "{c:?} vs {f:?}");
        }
        for col in [3, 4] {
            let steps: usize = c[col].parse().unwrap();
            assert!((40..=640).contains(&steps), "{c:?}");
        }
    }
}
