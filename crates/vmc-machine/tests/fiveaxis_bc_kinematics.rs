//! The B/C example program against the chain: the axis positions that
//! `trajectories/generate_5axis_bc.py` wrote (its own rotation matrices) are those the nominal
//! chain of `machines/trunnion-bc.toml` gives for the same workpiece points.

use nalgebra::Vector3;

use vmc_identify::inverse::nominal_linear_axes;
use vmc_machine::fiveaxis::FiveAxisSpec;

#[test]
fn the_b_c_program_puts_the_tool_on_the_block_faces_it_names() {
    let spec = FiveAxisSpec::from_toml_str(
        include_str!("../../../machines/trunnion-bc.toml"),
        "trunnion-bc.toml",
    )
    .unwrap();
    let geom = spec.geometry();
    let letters: Vec<char> = geom.rotary.iter().map(|r| r.axis.letter()).collect();
    assert_eq!(letters, ['C', 'B']);
    let program = include_str!("../../../trajectories/trunnion_bc_5axis.ngc");
    // (workpiece point, [C, B], the program's first G1 of that face)
    let cases = [
        (
            [-190.0, 30.0, -90.0],
            [0.0, -30.0],
            "G1 X-4.641 Y30.000 Z-278.038 B-30.000 C0.000 F1500",
        ),
        (
            [-180.0, -40.0, -90.0],
            [90.0, -30.0],
            "G1 X-4.641 Y30.000 Z-278.038 B-30.000 C90.000 F1500",
        ),
    ];
    for (target, rot, line) in cases {
        assert!(program.contains(line), "{line}");
        let q = nominal_linear_axes(&geom, rot, Vector3::from(target));
        let words: Vec<f64> = line
            .split_whitespace()
            .skip(1)
            .take(3)
            .map(|w| w[1..].parse().unwrap())
            .collect();
        for i in 0..3 {
            // 0.5 µm: the program's three decimals.
            assert!((q[i] - words[i]).abs() < 5e-4, "{line}: {q:?}");
        }
    }
    // The simultaneous move ends over the middle of the block's top face at B0 C360.
    let q = nominal_linear_axes(&geom, [360.0, 0.0], Vector3::new(-150.0, 0.0, -40.0));
    assert!(program.contains("G1 X0.000 Y0.000 Z-240.000 B0.000 C360.000"));
    assert!((Vector3::from(q) - Vector3::new(0.0, 0.0, -240.0)).norm() < 1e-9);
}
