//! Rotary axes on the real binary: `interpret` prints A, B, C as `rs274` does; `run` and
//! `check` on the 3-axis reference machine refuse a program that turns a rotary axis with
//! one message naming the line and the axis, and accept rotary words that leave the axes at 0.

use std::path::PathBuf;
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_vmc-twin");
const PROGRAM: &str = "tests/data/rotary/index_a.ngc";

fn vmc(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(PathBuf::from(env!("CARGO_MANIFEST_DIR")))
        .output()
        .expect("run vmc-twin")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

#[test]
fn run_and_check_refuse_a_rotary_move_on_a_three_axis_machine_naming_line_and_axis() {
    for command in ["run", "check"] {
        let o = vmc(&[command, PROGRAM]);
        let err = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{command}: {err}");
        assert_eq!(
            err.trim_end(),
            format!(
                "vmc-twin: error: {PROGRAM}: line 7: the program moves the A axis; \
                 machine vmc-reference has no rotary axes"
            ),
            "{command}"
        );
    }
}

#[test]
fn interpret_prints_the_rotary_angles_of_every_move() {
    let o = vmc(&["interpret", PROGRAM]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    let moves: Vec<&str> = out
        .lines()
        .filter_map(|l| l.split_once("N..... ").map(|(_, call)| call))
        .filter(|c| c.starts_with("STRAIGHT_"))
        .collect();
    assert_eq!(
        moves,
        [
            "STRAIGHT_TRAVERSE(10.0000, 10.0000, 20.0000, 0.0000, 0.0000, 0.0000)",
            "STRAIGHT_TRAVERSE(10.0000, 10.0000, 20.0000, 0.0000, 0.0000, 0.0000)",
            "STRAIGHT_TRAVERSE(10.0000, 10.0000, 20.0000, 0.0000, 0.0000, 0.0000)",
            // G92 A5 made program A5 the machine's A0: A35 is machine A30.
            "STRAIGHT_FEED(20.0000, 10.0000, 20.0000, 30.0000, 0.0000, 0.0000)",
        ]
    );
}
