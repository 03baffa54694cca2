//! Property ("fuzz") tests of everything that reads user files: the G-code
//! front end (lexer, parser, interpreter, planner, travel and collision check), the machine
//! and fixture loaders, calibration datasets and measured thermal-drift files. Properties, for
//! every input: no panic; no hang (every accepted program is bounded in machine time, so the
//! check and a simulation of it end); every rejection is one line with a location — `line L,
//! column C` for syntax and semantics, `line L` for motion, the dotted field or the TOML line
//! and column for configuration files, the file (and for a bad cell its line and column) for
//! data files; accepted data files train (or refuse to) without a panic.
//!
//! Inputs are drawn by proptest from a fixed seed (deterministic in CI). The number of cases per
//! property is set so that the whole file runs in about 15 s in release on the 2-core CI machine;
//! the counts are the `cases` below (their total is stated in docs/results.md).

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

use vmc_machine::collision::{self, FixtureSpec, Scene};
use vmc_machine::machine::{MachineSpec, REFERENCE_TOML};
use vmc_machine::motion::MAX_PLAN_DURATION_S;
use vmc_machine::program::{self, ProgramError};

const VISE: &str = include_str!("data/collision/vise.toml");

/// Real programs the structured mutations start from.
const SEEDS: [&str; 8] = [
    include_str!("../trajectories/diag_xy.ngc"),
    include_str!("../trajectories/diag_ppn.ngc"),
    include_str!("../trajectories/cooldown_4h.ngc"),
    include_str!("data/collision/clean_pocket.ngc"),
    include_str!("data/collision/holder_into_stock.ngc"),
    include_str!("../crates/vmc-gcode/tests/data/linuxcnc/nc_files/3dtest.ngc"),
    include_str!("../crates/vmc-gcode/tests/data/linuxcnc/nc_files/plasmatest.ngc"),
    include_str!("data/g2_without_centre.ngc"),
];

/// A deterministic runner: the same inputs on every run.
fn runner(cases: u32) -> TestRunner {
    let cfg = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    TestRunner::new_with_rng(cfg, TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]))
}

/// Does `msg` start with `<file>: line N` (and, for G-code errors, `, column C`)?
fn has_line_location(msg: &str, file: &str) -> bool {
    let Some(rest) = msg.strip_prefix(&format!("{file}: line ")) else {
        return false;
    };
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    !digits.is_empty()
        && (rest[digits.len()..].starts_with(": ") || rest[digits.len()..].starts_with(", column "))
}

/// The whole front end on one text: plan (with travel check), and when the plan is accepted
/// without the travel check, the collision check on the reference machine with the vise.
fn front_end(text: &str) -> Result<(), TestCaseError> {
    let machine = MachineSpec::reference();
    let file = "fuzz.ngc";
    match program::plan_source_unchecked(text, file, &machine, machine.axes.home_mm) {
        Ok(plan) => {
            prop_assert!(
                plan.duration_s() <= MAX_PLAN_DURATION_S,
                "unbounded plan accepted"
            );
            let fixture = FixtureSpec::from_toml_str(VISE, "vise.toml").unwrap();
            let scene = Scene::new(&machine, Some(&fixture)).unwrap();
            let mut problems = Vec::new();
            let sum = collision::check_plan(&plan, &machine, Some(&scene), &mut problems)
                .map_err(|e| TestCaseError::fail(format!("check failed: {e}")))?;
            prop_assert_eq!(sum.collisions + sum.travel_violations, problems.len());
            for p in &problems {
                let msg = format!("{file}: {p}");
                prop_assert!(has_line_location(&msg, file), "{}", msg);
            }
            // The travel-checked path agrees with the check's travel verdict.
            let checked = program::plan_source(text, file, &machine, machine.axes.home_mm);
            prop_assert_eq!(checked.is_ok(), sum.travel_violations == 0);
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(!msg.contains('\n'), "one line: {}", msg);
            match &e {
                ProgramError::Gcode { .. }
                | ProgramError::Motion { .. }
                | ProgramError::UnknownTool { .. }
                | ProgramError::NoRotaryAxes { .. } => {
                    prop_assert!(has_line_location(&msg, file), "no location: {}", msg)
                }
                ProgramError::Io { .. } => prop_assert!(false, "no I/O here: {}", msg),
            }
        }
    }
    Ok(())
}

/// G-code-like text: words with ordinary, extreme and malformed numbers, comments, line breaks.
fn gcode_text() -> impl Strategy<Value = String> {
    let number = prop_oneof![
        (-600.0f64..600.0).prop_map(|v| format!("{v:.3}")),
        Just("0".to_string()),
        Just("-0".to_string()),
        Just("1e9".to_string()),
        Just("999999999".to_string()),
        Just("-999999999".to_string()),
        Just("0.0000001".to_string()),
        Just("100000".to_string()),
        Just("1000".to_string()),
        Just(".".to_string()),
        Just("-".to_string()),
        Just("".to_string()),
        (0u32..100).prop_map(|v| v.to_string()),
    ];
    let letter = prop::sample::select(vec![
        'G', 'G', 'G', 'X', 'Y', 'Z', 'A', 'C', 'I', 'J', 'K', 'R', 'F', 'S', 'P', 'M', 'T', 'N',
        'Q',
    ]);
    let code = prop::sample::select(vec![
        "0", "1", "2", "3", "4", "17", "18", "19", "20", "21", "53", "54", "59", "90", "91",
        "90.1", "91.1", "92", "92.1", "40", "49", "80", "94", "6", "5", "30", "2",
    ]);
    let word = prop_oneof![
        4 => (letter, number).prop_map(|(l, n)| format!("{l}{n}")),
        3 => (prop::sample::select(vec!['G', 'M']), code).prop_map(|(l, c)| format!("{l}{c}")),
        1 => Just("(comment)".to_string()),
        1 => Just("; rest".to_string()),
        1 => Just("%".to_string()),
        1 => Just("#1=2".to_string()),
        1 => Just("[1+2]".to_string()),
    ];
    prop::collection::vec(
        prop::collection::vec(word, 0..6).prop_map(|w| w.join(" ")),
        0..12,
    )
    .prop_map(|lines| lines.join("\n"))
}

/// One structured mutation of a real program.
#[derive(Debug, Clone)]
enum Mutation {
    DeleteChar(usize),
    InsertText(usize, &'static str),
    ReplaceNumber(usize, &'static str),
    DuplicateLine(usize),
    SwapLines(usize, usize),
    Truncate(usize),
}

const INSERTS: [&str; 14] = [
    "G2 X10 Y10 I0 J0 F100\n",
    "G3 X50 R0.001 F100\n",
    "G2 X0 Y0 I5 P1000 F0.001\n",
    "G4 P99999999\n",
    "G1 F0 X10\n",
    "S99999 M3\n",
    "S-5 M3\n",
    "G0 Z-445\n",
    "G0 X-1e9\n",
    "G91 G1 X600 F1000\n",
    "G20 G0 X30\n",
    "G53 G0 Z0\n",
    "\u{0}\u{feff}é\r\n",
    "G2 X10 Y10 I5 J5 F100\n",
];
const NUMBERS: [&str; 10] = [
    "1e9",
    "-1e9",
    "0",
    "1e-9",
    "99999999",
    "nan",
    "inf",
    "-0",
    "3.4028235e38",
    "1.7976931348623157e308",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::DeleteChar),
        (any::<usize>(), prop::sample::select(INSERTS.to_vec()))
            .prop_map(|(i, t)| Mutation::InsertText(i, t)),
        (any::<usize>(), prop::sample::select(NUMBERS.to_vec()))
            .prop_map(|(i, n)| Mutation::ReplaceNumber(i, n)),
        any::<usize>().prop_map(Mutation::DuplicateLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        any::<usize>().prop_map(Mutation::Truncate),
    ]
}

/// Byte offsets of the numbers (digit runs with sign and point) in `s`.
fn number_spans(s: &str) -> Vec<(usize, usize)> {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() {
            let mut j = i;
            while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.') {
                j += 1;
            }
            let start = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
            out.push((start, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// Nearest char boundary at or below `i`.
fn floor_boundary(s: &str, i: usize) -> usize {
    let mut i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(text: &str, m: &Mutation) -> String {
    let mut s = text.to_string();
    match *m {
        Mutation::DeleteChar(i) if !s.is_empty() => {
            let at = floor_boundary(&s, i % s.len());
            s.remove(at);
        }
        Mutation::DeleteChar(_) => {}
        Mutation::InsertText(i, t) => {
            // At the start of a line, so the insert is a block of its own.
            let lines: Vec<&str> = text.split_inclusive('\n').collect();
            let k = i % (lines.len() + 1);
            let mut out: String = lines[..k].concat();
            out.push_str(t);
            out.push_str(&lines[k..].concat());
            s = out;
        }
        Mutation::ReplaceNumber(i, n) => {
            let spans = number_spans(text);
            if !spans.is_empty() {
                let (a, b) = spans[i % spans.len()];
                s = format!("{}{}{}", &text[..a], n, &text[b..]);
            }
        }
        Mutation::DuplicateLine(i) => {
            let mut lines: Vec<&str> = text.lines().collect();
            if !lines.is_empty() {
                let k = i % lines.len();
                lines.insert(k, lines[k]);
            }
            s = lines.join("\n");
        }
        Mutation::SwapLines(a, b) => {
            let mut lines: Vec<&str> = text.lines().collect();
            if !lines.is_empty() {
                let n = lines.len();
                lines.swap(a % n, b % n);
            }
            s = lines.join("\n");
        }
        Mutation::Truncate(i) => {
            let at = floor_boundary(&s, i % (s.len() + 1));
            s.truncate(at);
        }
    }
    s
}

#[test]
fn gcode_arbitrary_bytes_never_panic_and_every_rejection_has_a_location() {
    runner(1500)
        .run(&prop::collection::vec(any::<u8>(), 0..300), |bytes| {
            front_end(&String::from_utf8_lossy(&bytes))
        })
        .unwrap();
}

#[test]
fn gcode_like_programs_never_panic_hang_or_reject_without_a_location() {
    runner(3000).run(&gcode_text(), |t| front_end(&t)).unwrap();
}

#[test]
fn mutated_real_programs_never_panic_hang_or_reject_without_a_location() {
    let strategy = (
        prop::sample::select(SEEDS.to_vec()),
        prop::collection::vec(mutation(), 1..4),
    );
    runner(1200)
        .run(&strategy, |(seed, muts)| {
            let text = muts.iter().fold(seed.to_string(), |t, m| apply(&t, m));
            front_end(&text)
        })
        .unwrap();
}

// ---------------------------------------------------------------------------------------------
// Machine and fixture files.

/// Accepted machines must build a twin and run a short program; rejected ones name the file and
/// a location (dotted field, or the TOML parser's line and column).
fn machine_file(text: &str) -> Result<(), TestCaseError> {
    match MachineSpec::from_toml_str(text, "m.toml") {
        Ok(spec) => {
            if let Ok(mut twin) = vmc_machine::twin::Twin::new(&spec, 1) {
                let prog = "G0 X10 Y10 Z-10\nG4 P2\nM30";
                if let Ok(plan) = program::plan_source(prog, "p.ngc", &spec, spec.axes.home_mm) {
                    let cfg = vmc_machine::sim::SimConfig::default().with_thermal_part(true);
                    let _ = vmc_machine::sim::execute(
                        &mut twin,
                        &plan,
                        &cfg,
                        None,
                        &mut vmc_machine::sim::NullObserver,
                    );
                }
            }
            if let Some(c) = &spec.collision {
                let _ = c;
                let scene = Scene::new(&spec, None);
                prop_assert!(scene.is_ok());
            }
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.starts_with("m.toml: "), "{}", msg);
            prop_assert!(!msg.contains('\n'), "one line: {}", msg);
            prop_assert!(
                msg.contains("field `") || msg.contains("line "),
                "no location: {}",
                msg
            );
        }
    }
    Ok(())
}

const VALUES: [&str; 14] = [
    "nan",
    "inf",
    "-inf",
    "-1.0",
    "0.0",
    "1e308",
    "-1e308",
    "1e-308",
    "\"x\"",
    "true",
    "[]",
    "1e12",
    "-0.0",
    "12345678901234567890",
];

#[test]
fn mutated_reference_machines_never_panic_and_every_rejection_names_a_field_or_line() {
    let spans = number_spans(REFERENCE_TOML);
    let n_lines = REFERENCE_TOML.lines().count();
    let strategy = prop_oneof![
        (0..spans.len(), prop::sample::select(VALUES.to_vec())).prop_map(move |(k, v)| {
            let (a, b) = spans[k];
            format!("{}{}{}", &REFERENCE_TOML[..a], v, &REFERENCE_TOML[b..])
        }),
        (0..n_lines).prop_map(|k| {
            REFERENCE_TOML
                .lines()
                .enumerate()
                .filter(|(i, _)| *i != k)
                .map(|(_, l)| l)
                .collect::<Vec<_>>()
                .join("\n")
        }),
        (0..n_lines).prop_map(|k| {
            let mut lines: Vec<&str> = REFERENCE_TOML.lines().collect();
            lines.insert(k, lines[k]);
            lines.join("\n")
        }),
        (0..REFERENCE_TOML.len())
            .prop_map(|k| REFERENCE_TOML[..floor_boundary(REFERENCE_TOML, k)].to_string()),
    ];
    runner(400).run(&strategy, |t| machine_file(&t)).unwrap();
}

#[test]
fn arbitrary_text_as_a_machine_or_fixture_file_is_rejected_with_a_location() {
    runner(1000)
        .run(&"[\\[\\]a-z_=.,{}\"0-9 \n-]{0,200}", |t| {
            machine_file(&t)?;
            if let Err(e) = FixtureSpec::from_toml_str(&t, "f.toml") {
                let msg = e.to_string();
                prop_assert!(
                    msg.starts_with("f.toml: ") && !msg.contains('\n'),
                    "{}",
                    msg
                );
                prop_assert!(msg.contains("field `") || msg.contains("line "), "{}", msg);
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn mutated_fixtures_never_panic_and_name_the_field() {
    let spans = number_spans(VISE);
    let strategy =
        (0..spans.len(), prop::sample::select(VALUES.to_vec())).prop_map(move |(k, v)| {
            let (a, b) = spans[k];
            format!("{}{}{}", &VISE[..a], v, &VISE[b..])
        });
    runner(300)
        .run(&strategy, |t| {
            match FixtureSpec::from_toml_str(&t, "f.toml") {
                Ok(f) => {
                    // Accepted: the check runs on it.
                    let m = MachineSpec::reference();
                    let scene = Scene::new(&m, Some(&f)).unwrap();
                    let plan =
                        program::plan_source_unchecked(SEEDS[3], "p.ngc", &m, m.axes.home_mm)
                            .unwrap();
                    let mut v = Vec::new();
                    collision::check_plan(&plan, &m, Some(&scene), &mut v).unwrap();
                }
                Err(e) => {
                    let msg = e.to_string();
                    prop_assert!(msg.contains("field `") || msg.contains("line "), "{}", msg);
                }
            }
            Ok(())
        })
        .unwrap();
}

// ---------------------------------------------------------------------------------------------
// Calibration datasets (`train --data`).

/// A small real dataset: every 25th record of the reference machine's calibration campaign
/// (all instruments, every cycle), as the CSV `calibrate` writes.
fn small_dataset_csv() -> String {
    use vmc_twin::studies::calibration::{self, CampaignConfig, ThermalCycle};
    let spec = MachineSpec::reference();
    let mut ds = calibration::calibrate(
        &spec,
        &ThermalCycle::calibration_plan(&spec),
        &CampaignConfig::new(1),
    )
    .unwrap();
    ds.records = ds.records.into_iter().step_by(25).collect();
    ds.to_csv()
}

/// Accepted datasets train the linear baseline or refuse with an error, never a panic; rejected
/// ones name the file, and a bad cell its line and column.
fn dataset_file(text: &str) -> Result<(), TestCaseError> {
    use vmc_twin::predict::dataset::{Dataset, DatasetError};
    use vmc_twin::predict::predictor::{self, Settings};
    match Dataset::from_csv(text, "cal.csv") {
        Ok(ds) => {
            let geometry = MachineSpec::reference().geometry();
            if let Err(e) = predictor::train_linear(&ds, &geometry, &Settings::default()) {
                let msg = e.to_string();
                prop_assert!(!msg.is_empty() && !msg.contains('\n'), "{}", msg);
            }
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.starts_with("cal.csv: "), "{}", msg);
            prop_assert!(!msg.contains('\n'), "{}", msg);
            if let DatasetError::BadCell { .. } = e {
                prop_assert!(has_line_location(&msg, "cal.csv"), "{}", msg);
            }
        }
    }
    Ok(())
}

#[test]
fn mutated_calibration_datasets_never_panic_and_every_rejection_names_the_file() {
    let csv = small_dataset_csv();
    // The unmutated file is accepted and trains: the property is not vacuous.
    let ds = vmc_twin::predict::dataset::Dataset::from_csv(&csv, "cal.csv").unwrap();
    let geometry = MachineSpec::reference().geometry();
    vmc_twin::predict::predictor::train_linear(&ds, &geometry, &Default::default()).unwrap();
    runner(1000)
        .run(&prop::collection::vec(mutation(), 1..4), |muts| {
            let text = muts.iter().fold(csv.clone(), |t, m| apply(&t, m));
            dataset_file(&text)
        })
        .unwrap();
}

// ---------------------------------------------------------------------------------------------
// Measured thermal-drift files (`fit-thermal --data`).

/// Every 8th row of the real spindle test slice (3 cycles, 8 min steps), four of its columns.
fn small_thermal_csv() -> String {
    let text = include_str!("data/spindle-thermal/train_every60s.csv");
    let keep = [0usize, 1, 2, 6, 7, 11]; // time_s, spindle_rpm, ch1, ch5, t1, t5
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        if i == 0 || i % 8 == 1 {
            let cells: Vec<&str> = line.split(',').collect();
            let row: Vec<&str> = keep.iter().map(|&k| cells[k]).collect();
            out.push_str(&row.join(","));
            out.push('\n');
        }
    }
    out
}

/// Read, split and fit (linear, the fast form) as `fit-thermal` does: accepted files fit or
/// refuse with an error; every error is one line, and table errors name the file.
fn thermal_file(text: &str) -> Result<(), TestCaseError> {
    use vmc_twin::predict::thermal_fit::{self, Architecture, FitSettings, Split, TableRequest};
    let inputs = vec![
        "t1_degc".to_string(),
        "t5_degc".into(),
        "spindle_rpm".into(),
    ];
    let outputs = vec!["ch1_um".to_string(), "ch5_um".into()];
    let request = TableRequest {
        time: None,
        required: inputs
            .iter()
            .map(|n| (n.clone(), "input"))
            .chain(outputs.iter().map(|n| (n.clone(), "output")))
            .collect(),
        optional: Vec::new(),
        min_rows: 20,
    };
    let table = match thermal_fit::read_csv(text, "t.csv", &request) {
        Ok(t) => t,
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.starts_with("t.csv: "), "{}", msg);
            prop_assert!(!msg.contains('\n'), "{}", msg);
            return Ok(());
        }
    };
    let settings = FitSettings {
        architecture: Architecture::Linear,
        ..FitSettings::default()
    };
    let fitted = Split::resolve(
        &table.time_s,
        None,
        table.column("spindle_rpm").map(|v| ("spindle_rpm", v)),
        settings.val_fraction,
    )
    .and_then(|split| thermal_fit::fit(&table, &inputs, &outputs, &split, &settings));
    if let Err(e) = fitted {
        let msg = e.to_string();
        prop_assert!(!msg.is_empty() && !msg.contains('\n'), "{}", msg);
    }
    Ok(())
}

/// The linear thermal-drift model of the small slice (two temperatures and the speed to two
/// channels).
fn fit_small_thermal_model(csv: &str) -> vmc_twin::predict::thermal_fit::ThermalModel {
    use vmc_twin::predict::thermal_fit::{self, Architecture, FitSettings, Split, TableRequest};
    let cols = ["t1_degc", "t5_degc", "spindle_rpm", "ch1_um", "ch5_um"];
    let request = TableRequest {
        time: None,
        required: cols.iter().map(|c| (c.to_string(), "input")).collect(),
        optional: Vec::new(),
        min_rows: 20,
    };
    let table = thermal_fit::read_csv(csv, "t.csv", &request).unwrap();
    let rpm = table.column("spindle_rpm").unwrap();
    let split = Split::resolve(&table.time_s, None, Some(("spindle_rpm", rpm)), 0.25).unwrap();
    let settings = FitSettings {
        architecture: Architecture::Linear,
        ..FitSettings::default()
    };
    let inputs: Vec<String> = cols[..3].iter().map(|c| c.to_string()).collect();
    let outputs: Vec<String> = cols[3..].iter().map(|c| c.to_string()).collect();
    thermal_fit::fit(&table, &inputs, &outputs, &split, &settings).unwrap()
}

#[test]
fn mutated_thermal_measurement_files_never_panic_and_every_rejection_is_one_line() {
    let csv = small_thermal_csv();
    // The unmutated slice reads and fits: the property is not vacuous.
    fit_small_thermal_model(&csv);
    runner(1000)
        .run(&prop::collection::vec(mutation(), 1..4), |muts| {
            let text = muts.iter().fold(csv.clone(), |t, m| apply(&t, m));
            thermal_file(&text)
        })
        .unwrap();
}

// ---------------------------------------------------------------------------------------------
// Model files (`run --model`, `predict-thermal --model`).

/// One mutation of a JSON text: a number replaced by an extreme value, a character deleted, the
/// text truncated, a line duplicated or deleted.
fn mutate_json(text: &str, muts: &[Mutation]) -> String {
    muts.iter().fold(text.to_string(), |t, m| apply(&t, m))
}

/// Accepted predictor models predict (a finite or NaN error, never a panic) from readings;
/// rejected ones give a one-line error.
fn predictor_file(text: &str, n_sensors: usize) -> Result<(), TestCaseError> {
    use vmc_twin::predict::predictor::{AnyPredictor, ErrorPredictor};
    match AnyPredictor::from_json_str(text) {
        Ok(mut p) => {
            let n = p.sensor_names().len().min(4 * n_sensors);
            p.observe_readings(0.0, &vec![21.0; n]);
            p.observe_readings(60.0, &vec![22.0; n]);
            let _ = p.predict_error_mm([280.0, 200.0, -225.0]);
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(!msg.is_empty() && !msg.contains('\n'), "{}", msg);
        }
    }
    Ok(())
}

#[test]
fn mutated_predictor_model_files_never_panic_and_every_rejection_is_one_line() {
    use vmc_twin::predict::predictor::{self, AnyPredictor};
    let csv = small_dataset_csv();
    let ds = vmc_twin::predict::dataset::Dataset::from_csv(&csv, "cal.csv").unwrap();
    let geometry = MachineSpec::reference().geometry();
    let (model, _) = predictor::train_linear(&ds, &geometry, &Default::default()).unwrap();
    let n_sensors = ds.sensor_names.len();
    let json = AnyPredictor::Linear(model).to_json_string().unwrap();
    // The unmutated file loads: the property is not vacuous.
    AnyPredictor::from_json_str(&json).unwrap();
    runner(600)
        .run(&prop::collection::vec(mutation(), 1..4), |muts| {
            predictor_file(&mutate_json(&json, &muts), n_sensors)
        })
        .unwrap();
}

#[test]
fn mutated_thermal_model_files_never_panic_and_every_rejection_names_the_file() {
    use vmc_twin::predict::thermal_fit::ThermalModel;
    let model = fit_small_thermal_model(&small_thermal_csv());
    let json = model.to_json();
    ThermalModel::from_json(&json, "m.json").unwrap();
    let time_s: Vec<f64> = (0..50).map(|i| 60.0 * f64::from(i)).collect();
    let column = vec![25.0; time_s.len()];
    runner(600)
        .run(&prop::collection::vec(mutation(), 1..4), |muts| {
            match ThermalModel::from_json(&mutate_json(&json, &muts), "m.json") {
                Ok(m) => {
                    let cols: Vec<&[f64]> = m.inputs.iter().map(|_| column.as_slice()).collect();
                    if let Err(e) = m.predict(&time_s, &cols) {
                        prop_assert!(!e.to_string().contains('\n'), "{}", e);
                    }
                }
                Err(e) => {
                    let msg = e.to_string();
                    prop_assert!(
                        msg.starts_with("m.json: ") || msg.contains("m.json"),
                        "{}",
                        msg
                    );
                    prop_assert!(!msg.contains('\n'), "{}", msg);
                }
            }
            Ok(())
        })
        .unwrap();
}
