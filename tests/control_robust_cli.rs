//! Controllers judged on blades they were not designed on, as a user runs them: `control
//! design --robustness`, `lobes`/`cut --controller --plant`, and the controller files and
//! plant files that are refused (edited plant, sampling too slow for the modes acted on, a
//! zero weight, a speed below 1 rpm).

use std::path::Path;
use std::process::Output;

mod common;
use common::*;

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn refused(dir: &Path, args: &[&str]) -> String {
    let o = vmc(dir, args);
    let (out, err) = text(&o);
    assert!(!o.status.success(), "{args:?} was accepted:\n{out}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

fn blade_text() -> String {
    std::fs::read_to_string(repo_file("machines/benchmarks/blade.toml")).unwrap()
}

/// The shipped blade with its frequencies × 0.90 (E and the stack's stiffness × 0.81) or its
/// mass × 1.20 (density × 1.2), written as plant files.
fn perturbed_plants(dir: &Path) {
    let t = blade_text();
    let f090 = t
        .replace("youngs_modulus_pa = 210.0e9", "youngs_modulus_pa = 170.1e9")
        .replace("stiffness_n_per_um = 185.0", "stiffness_n_per_um = 149.85");
    let m120 = t.replace("density_kg_per_m3 = 7850.0", "density_kg_per_m3 = 9420.0");
    assert!(f090 != t && m120 != t);
    std::fs::write(dir.join("f090.toml"), f090).unwrap();
    std::fs::write(dir.join("m120.toml"), m120).unwrap();
    std::fs::write(dir.join("blade.toml"), t).unwrap();
}

fn closed_depth(out: &str) -> f64 {
    let line = out
        .lines()
        .find(|l| l.starts_with("closed loop: minimum critical depth"))
        .unwrap_or_else(|| panic!("{out}"));
    line.split_whitespace().nth(5).unwrap().parse().unwrap()
}

fn verdict(out: &str) -> &str {
    let line = out.lines().find(|l| l.starts_with("closed loop")).unwrap();
    if line.contains("stable") {
        "stable"
    } else {
        "chatter"
    }
}

/// The robust H∞ judged on two perturbed blades: the closed-loop lobes at one speed each,
/// confirmed by time-domain cuts (sampled controller, small feed: linear) 5 % below (stable)
/// and 5 % above (chatter).
#[test]
fn time_domain_cuts_confirm_the_lobes_of_the_robust_hinf_on_perturbed_blades() {
    let tmp = TempDir::new("robust-confirm");
    perturbed_plants(tmp.path());
    let d = succeed(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            "blade.toml",
            "--controller",
            "robust-hinf",
            "-o",
            "rh.json",
        ],
    );
    assert!(d.contains("gamma"), "{d}");
    for (plant, rpm) in [("f090.toml", "4300"), ("m120.toml", "3600")] {
        let lobes = succeed(
            tmp.path(),
            &[
                "lobes",
                "--controller",
                "rh.json",
                "--plant",
                plant,
                "--rpm",
                rpm,
            ],
        );
        assert!(lobes.contains("judged on"), "{lobes}");
        let a = closed_depth(&lobes);
        for (factor, expected) in [(0.95, "stable"), (1.05, "chatter")] {
            let depth = format!("{:.4}", factor * a);
            let cut = succeed(
                tmp.path(),
                &[
                    "cut",
                    "--controller",
                    "rh.json",
                    "--plant",
                    plant,
                    "--rpm",
                    rpm,
                    "--depth-mm",
                    &depth,
                    "--feed-per-tooth-mm",
                    "0.001",
                    "--revolutions",
                    "150",
                ],
            );
            assert_eq!(
                verdict(&cut),
                expected,
                "{plant} {rpm} rpm {depth} mm:\n{cut}"
            );
        }
    }
}

/// `--robustness` without lobes (`--rpm none`): the plain H∞ is unstable on most perturbed
/// blades, LQG on none; every case is a row.
#[test]
fn the_robustness_sweep_reports_each_perturbed_blade() {
    let tmp = TempDir::new("robust-sweep");
    perturbed_plants(tmp.path());
    let rows = |out: &str| {
        out.lines()
            .filter(|l| l.starts_with("  ") && (l.contains(" yes ") || l.contains(" NO ")))
            .count()
    };
    let h = succeed(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            "blade.toml",
            "--controller",
            "hinf",
            "--robustness",
            "--rpm",
            "none",
        ],
    );
    assert_eq!(rows(&h), 13, "{h}");
    assert!(h.contains("unstable without cutting: 11 of 13"), "{h}");
    let l = succeed(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            "blade.toml",
            "--controller",
            "lqg",
            "--robustness",
            "--rpm",
            "2000,3000",
            "--steps",
            "40",
        ],
    );
    assert!(l.contains("unstable without cutting: 0 of 13"), "{l}");
    assert!(l.contains("worst closed/open minimum depth"), "{l}");
}

/// A controller file whose stored plant was edited is refused; so is `--plant` onto which the
/// controller is unstable (no lobes to speak of), with the reason.
#[test]
fn an_edited_controller_file_and_an_unstable_judged_loop_are_refused() {
    let tmp = TempDir::new("robust-edited");
    perturbed_plants(tmp.path());
    succeed(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            "blade.toml",
            "--controller",
            "hinf",
            "-o",
            "h.json",
        ],
    );
    let json = std::fs::read_to_string(tmp.path().join("h.json")).unwrap();
    let edited = json.replacen(
        "\"density_kg_per_m3\": 7850.0",
        "\"density_kg_per_m3\": 8242.5",
        1,
    );
    assert_ne!(edited, json);
    std::fs::write(tmp.path().join("edited.json"), edited).unwrap();
    let e = refused(
        tmp.path(),
        &["lobes", "--controller", "edited.json", "--rpm", "3000"],
    );
    assert!(e.contains("do not give the closed-loop poles"), "{e}");
    let e = refused(
        tmp.path(),
        &[
            "lobes",
            "--controller",
            "h.json",
            "--plant",
            "m120.toml",
            "--rpm",
            "3000",
        ],
    );
    assert!(e.contains("unstable without cutting"), "{e}");
}

/// Sampled at 100 Hz the controller cannot act on the 233 Hz mode: refused at design (with the
/// plant file named), and a 10 Hz file never reaches the cut's simulation.
#[test]
fn a_controller_sampled_too_slowly_for_its_modes_is_refused() {
    let tmp = TempDir::new("robust-sampling");
    for rate in ["100.0", "10.0"] {
        let t = blade_text().replace(
            "sample_rate_hz = 50000.0",
            &format!("sample_rate_hz = {rate}"),
        );
        std::fs::write(tmp.path().join("slow.toml"), t).unwrap();
        let e = refused(
            tmp.path(),
            &[
                "control",
                "design",
                "--plant",
                "slow.toml",
                "--controller",
                "lqg",
                "-o",
                "c.json",
            ],
        );
        assert!(
            e.contains("slow.toml") && e.contains("233.0 Hz mode"),
            "{e}"
        );
        assert!(!tmp.path().join("c.json").exists());
    }
}

/// A zero weight names the file and the field; a speed below 1 rpm says why.
#[test]
fn a_zero_weight_and_a_crawling_spindle_are_refused_with_the_reason() {
    let tmp = TempDir::new("robust-bad");
    let t = blade_text().replace("effort_weight_per_v2 = 10.0", "effort_weight_per_v2 = 0.0");
    std::fs::write(tmp.path().join("zero.toml"), t).unwrap();
    let e = refused(
        tmp.path(),
        &[
            "control",
            "design",
            "--plant",
            "zero.toml",
            "--controller",
            "lqg",
        ],
    );
    assert!(
        e.contains("zero.toml") && e.contains("lqg.effort_weight_per_v2"),
        "{e}"
    );
    let e = refused(tmp.path(), &["cut", "--rpm", "1e-9", "--depth-mm", "1"]);
    assert!(e.contains("below 1 rpm"), "{e}");
    assert!(!e.contains("resonates"), "{e}");
}
