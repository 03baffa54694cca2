//! `run` of the B/C example written in the part frame with G43.4, compensated by the model
//! identified from the same realisation's probing, with the rotary axes corrected and not; and
//! G43.4's refusals as the user sees them.

mod common;

use common::{ok, refused, repo_file, summary_json as summary, vmc, TempDir};

fn path(rel: &str) -> String {
    repo_file(rel).display().to_string()
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap()
}

#[test]
fn the_g43_4_program_is_compensated_in_position_and_tool_axis_on_the_b_c_machine() {
    let dir = TempDir::new("tcp");
    let (m, p) = (
        path("machines/trunnion-bc.toml"),
        path("trajectories/trunnion_bc_tcp.ngc"),
    );
    let seed = "2";
    let run = |args: &[&str], what: &str| ok(&vmc(dir.path(), args), what);
    run(
        &[
            "probe-campaign",
            "--machine",
            &m,
            "--seed",
            seed,
            "-o",
            "p.csv",
        ],
        "probe-campaign",
    );
    run(
        &[
            "identify",
            "--data",
            "p.csv",
            "--machine",
            &m,
            "-o",
            "id.json",
            "--heldout-poses",
            "50",
        ],
        "identify",
    );
    let mut reports = Vec::new();
    for rc in ["on", "off"] {
        let args = [
            "run",
            &p,
            "--machine",
            &m,
            "--seed",
            seed,
            "--identified",
            "id.json",
            "--rotary-comp",
            rc,
            "--out",
            rc,
        ];
        reports.push(run(&args, "run"));
    }
    assert!(reports[0].contains("the controller corrects X, Y, Z and the rotary axes"));
    assert!(reports[0].contains("tool-centre-point control: under G43.4"));
    // The rapids that swing the table's side faces into place drag X beyond its speed limit
    // at their programmed timing: they are slowed.
    assert!(
        reports[0].contains("G43.4: feed limited by the axes' limits on 2 moves, slowest 78 % of programmed (line 36, axis X velocity)"),
        "{}",
        reports[0].lines().take(6).collect::<Vec<_>>().join("\n")
    );
    assert!(reports[1].contains("the controller corrects X, Y, Z (--rotary-comp off)"));
    let (on, off) = (summary(dir.path(), "on"), summary(dir.path(), "off"));
    // One point per dwell of the program.
    let dwells = std::fs::read_to_string(repo_file("trajectories/trunnion_bc_tcp.ngc"))
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("G4 P"))
        .count();
    assert_eq!(on["points"].as_u64().unwrap() as usize, dwells);
    for s in [&on, &off] {
        assert!(f(&s["reduction"]) >= 0.9, "{s}");
        // The table's location errors tilt the tool by tens of µrad.
        assert!(f(&s["axis_before"]["rms_urad"]) > 30.0, "{s}");
    }
    // Linear axes alone cannot turn the tool: the tool-axis error stays where it was.
    assert!(f(&off["axis_reduction"]).abs() < 0.01, "{off}");
    // Turning the rotary axes removes most of it (the B = 0 point, a singularity, keeps its
    // part that only a quarter turn of C could correct).
    assert!(f(&on["axis_reduction"]) > 0.7, "{on}");
    assert_eq!(on["rotary_compensation"], serde_json::json!(true));
    // The position is solved at the corrected angles as precisely as without.
    let rms = |s: &serde_json::Value| f(&s["after"]["rms_um"][3]);
    assert!(
        rms(&on) < 1.2 * rms(&off) + 0.1,
        "{} vs {}",
        rms(&on),
        rms(&off)
    );
    let csv = std::fs::read_to_string(dir.path().join("on/samples.csv")).unwrap();
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .ends_with(",b_comp_deg,c_comp_deg,axis_err_comp_urad"),
        "{csv}"
    );
}

#[test]
fn g43_4_is_refused_where_it_cannot_work_with_line_and_column() {
    let dir = TempDir::new("tcp-refused");
    let write = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    write("h.ngc", "G0 Z0\nG43.4 H7\nM2\n");
    write("a.ngc", "G43.4 H1\nG0 X0 Y0 Z50 A10\nM2\n");
    write("v.ngc", "G0 Z0\nG43.5 H1 I0 J0 K1\nM2\n");
    let bc = path("machines/trunnion-bc.toml");
    let err = refused(
        &vmc(dir.path(), &["run", "h.ngc", "--machine", &bc]),
        "tool 7",
    );
    assert!(
        err.contains("h.ngc: line 2, column 1: G43.4 needs the tool's length: tool 7 has none"),
        "{err}"
    );
    let err = refused(
        &vmc(dir.path(), &["run", "a.ngc", "--machine", &bc]),
        "A word",
    );
    assert!(
        err.contains("line 2, column 14: G43.4: this machine has no A axis"),
        "{err}"
    );
    // The tool axis as a vector (Fanuc's G43.5) is not implemented: angles under G43.4 are.
    let err = refused(
        &vmc(dir.path(), &["run", "v.ngc", "--machine", &bc]),
        "G43.5",
    );
    assert!(
        err.contains("v.ngc: line 2, column 1: G43.5 (tool centre point control with the tool axis as a vector I J K; program the rotary angles under G43.4) is not supported"),
        "{err}"
    );
    // The three-axis machine has no kinematics for it.
    let err = refused(&vmc(dir.path(), &["run", "a.ngc"]), "three axes");
    assert!(
        err.contains("line 1, column 1: G43.4 (tool centre point control) needs a five-axis machine's kinematics"),
        "{err}"
    );
}
