//! Sensor placement through the real binary: `select-sensors` ranks the
//! candidate locations, writes a sensor set that the other commands accept with `--sensors`,
//! compares compensation quality on held-out runs, and rejects bad requests clearly.

use std::process::Output;
use vmc_machine::machine::MachineSpec;

mod common;
use common::*;

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn diag_xy() -> String {
    repo_file("trajectories/diag_xy.ngc").display().to_string()
}

#[test]
fn select_sensors_ranks_candidates_and_writes_a_set_that_run_accepts() {
    let tmp = TempDir::new("select");
    let dir = tmp.path();
    let o = vmc(
        dir,
        &[
            "select-sensors",
            "--count",
            "4",
            "--no-compare",
            "-o",
            "s.toml",
        ],
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    // Every thermal node of the machine and the ambient air.
    let candidates = vmc_machine::machine::MachineSpec::reference()
        .thermal
        .nodes
        .len()
        + 1;
    assert!(
        out.contains(&format!("{candidates} candidate locations")),
        "{out}"
    );
    // Five proposals, validated on selection-only states; exactly one is chosen.
    let head = out.find("proposals (").expect("proposals table");
    let proposals: Vec<&str> = out[head..]
        .lines()
        .skip(2)
        .take_while(|l| !l.starts_with("chosen:"))
        .collect();
    assert_eq!(proposals.len(), 5, "{out}");
    assert_eq!(
        proposals.iter().filter(|l| l.starts_with('*')).count(),
        1,
        "{out}"
    );
    // Reference first, then 4 ranked locations with their evidence.
    let start = out.find("chosen:").expect("chosen line");
    let ranked: Vec<&str> = out[start..]
        .lines()
        .take_while(|l| !l.starts_with("clusters:"))
        .filter(|l| l.trim_start().starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    assert_eq!(ranked.len(), 4, "{out}");
    let chosen_rule = out[start..].lines().next().unwrap();
    if chosen_rule.contains("clusters(") {
        // One sensor per cluster: the cluster column holds 1..=4, each once.
        let mut cl: Vec<&str> = ranked
            .iter()
            .map(|l| l.split_whitespace().last().unwrap())
            .collect();
        cl.sort();
        assert_eq!(cl, ["1", "2", "3", "4"], "{out}");
    }
    let set = std::fs::read_to_string(dir.join("s.toml")).unwrap();
    assert_eq!(set.matches("[[sensors]]").count(), 5, "{set}");
    assert!(set.contains("node = \"ambient\""), "{set}");
    // The set drives a run: the sensor line names the chosen locations.
    let o = vmc(dir, &["run", &diag_xy(), "--sensors", "s.toml"]);
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let first_chosen = ranked[0].split_whitespace().nth(1).unwrap();
    assert!(out.contains(first_chosen), "{first_chosen} not in\n{out}");
    // Nothing is overwritten without --force.
    let o = vmc(
        dir,
        &[
            "select-sensors",
            "--count",
            "4",
            "--no-compare",
            "-o",
            "s.toml",
        ],
    );
    assert!(!o.status.success());
    assert!(text(&o).1.contains("--force"), "{}", text(&o).1);
}

#[test]
fn the_comparison_reports_each_sensor_set_on_held_out_runs() {
    let tmp = TempDir::new("compare");
    let dir = tmp.path();
    let o = vmc(
        dir,
        &[
            "select-sensors",
            "--count",
            "3",
            "--random-draws",
            "1",
            "-o",
            "s.toml",
            "--json",
            "study.json",
        ],
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    for label in ["selected", "study default", "random #1", "all candidates"] {
        let line = out
            .lines()
            .find(|l| l.trim_start().starts_with(label))
            .unwrap_or_else(|| panic!("no `{label}` row in\n{out}"));
        // 7 diagonals × the held-out states of one seed (atypical and stress states).
        let runs =
            7 * vmc_twin::studies::calibration::evaluation_states(&MachineSpec::reference(), 1)
                .len();
        assert!(line.contains(&format!(" {runs} ")), "{line}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("study.json")).unwrap()).unwrap();
    let cmp = json["comparison"].as_array().unwrap();
    assert_eq!(cmp.len(), 4);
    for c in cmp {
        let red = c["median_reduction"].as_f64().unwrap();
        // Any set with ambient + 3 locations removes part of the error, none all of it.
        assert!(red > 0.0 && red < 1.0, "{c}");
    }
    assert_eq!(cmp[0]["sensors"].as_array().unwrap().len(), 4);
    let candidates = vmc_machine::machine::MachineSpec::reference()
        .thermal
        .nodes
        .len()
        + 1;
    assert_eq!(cmp[3]["sensors"].as_array().unwrap().len(), candidates);
}

#[test]
fn a_comparison_among_restricted_candidates_says_why_the_machines_own_set_is_not_compared() {
    let tmp = TempDir::new("restricted");
    let dir = tmp.path();
    // Two of the machine's own locations and two others: the study default set (11 locations)
    // cannot be trained on these candidates' columns.
    let o = vmc(
        dir,
        &[
            "select-sensors",
            "--count",
            "2",
            "--candidates",
            "spindle_housing,x_motor,spindle_front_bearing,saddle",
            "--random-draws",
            "1",
            "-o",
            "s.toml",
            "--json",
            "study.json",
        ],
    );
    let (out, err) = text(&o);
    assert!(o.status.success(), "{out}\n{err}");
    let note = out
        .lines()
        .find(|l| l.contains("(study default) is not compared"))
        .unwrap_or_else(|| panic!("no note on the study default set in\n{out}"));
    for missing in ["headstock_right", "work_zone", "column_top_front"] {
        assert!(note.contains(missing), "{note}");
    }
    assert!(
        !note.contains("spindle_housing") && !note.contains("x_motor"),
        "{note}"
    );
    assert!(
        !out.lines()
            .any(|l| l.trim_start().starts_with("study default")),
        "{out}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("study.json")).unwrap()).unwrap();
    let labels: Vec<&str> = json["comparison"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["label"].as_str().unwrap())
        .collect();
    assert_eq!(labels, ["selected", "random #1", "all candidates"]);
    // Ambient and the four candidates.
    assert_eq!(
        json["comparison"][2]["sensors"].as_array().unwrap().len(),
        5
    );
}

#[test]
fn bad_selection_requests_are_clear_errors() {
    let tmp = TempDir::new("bad");
    let dir = tmp.path();
    let o = vmc(
        dir,
        &[
            "select-sensors",
            "--candidates",
            "spindle_nose,spindel_motor",
            "--no-compare",
        ],
    );
    let err = text(&o).1;
    assert!(!o.status.success());
    assert!(
        err.contains("`spindel_motor` is not a thermal node") && err.contains("spindle_motor"),
        "{err}"
    );

    let o = vmc(
        dir,
        &[
            "select-sensors",
            "--candidates",
            "spindle_nose,x_motor",
            "--count",
            "3",
            "--no-compare",
        ],
    );
    let err = text(&o).1;
    assert!(!o.status.success());
    assert!(
        err.contains("--count 3: there are only 2 candidate locations besides ambient"),
        "{err}"
    );

    let o = vmc(dir, &["select-sensors", "--count", "0", "--no-compare"]);
    assert!(
        text(&o).1.contains("--count must be at least 1"),
        "{}",
        text(&o).1
    );

    std::fs::write(
        dir.join("bad.toml"),
        "[[sensors]]\nname = \"S1\"\nnode = \"spindle_nosee\"\n",
    )
    .unwrap();
    let o = vmc(dir, &["run", &diag_xy(), "--sensors", "bad.toml"]);
    let err = text(&o).1;
    assert!(!o.status.success());
    assert!(
        err.contains("bad.toml") && err.contains("spindle_nosee"),
        "{err}"
    );
}
