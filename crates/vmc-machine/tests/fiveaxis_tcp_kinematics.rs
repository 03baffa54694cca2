//! G43.4 moves against the closed-form kinematics of the trunnion chains, written here from the
//! chain conventions alone (rotation matrices, no use of the crate's transforms): the axes the
//! interpreter and planner produce for programmed tool-tip poses in the part frame are those of
//! the closed-form inverse kinematics, and between the programmed poses the tip, by the
//! closed-form forward kinematics, runs along the programmed line with the rotary axes in step.
//!
//! Chains `w C A Y X b Z t` and `w C B X Y b Z t`: the table turns by −C about the C line
//! (point `p_C`, direction z) and, carried by the trunnion, by −A about x (−B about y) through
//! `p_T`; the workpiece-side slides move the table by −X, −Y; Z moves the spindle by +Z, the tip
//! `T = (0, 0, −L)` below the gauge point. A part-frame point `w` (origin at the datum `D`) sits
//! in the bed at `b(w) = p_T + R_T(−θ_T)·(p_C − p_T + R_z(−C)·(D + w − p_C)) − (X, Y, 0)`, and the
//! tip is there when `(0, 0, Z) + T = b(w)`.

use vmc_machine::fiveaxis::plan::plan_program;
use vmc_machine::fiveaxis::run::{commanded_points, Sampling};
use vmc_machine::fiveaxis::FiveAxisSpec;

type V = [f64; 3];

fn rot(axis: char, angle_deg: f64, v: V) -> V {
    let (s, c) = angle_deg.to_radians().sin_cos();
    match axis {
        'A' => [v[0], c * v[1] - s * v[2], s * v[1] + c * v[2]],
        'B' => [c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]],
        _ => [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]],
    }
}

fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The machines' nominal geometry, as their files give it.
struct Trunnion {
    /// `A` or `B`.
    tilt: char,
    p_c: V,
    p_t: V,
    datum: V,
    length_mm: f64,
}

impl Trunnion {
    fn angles(&self, abc: V) -> (f64, f64) {
        let t = if self.tilt == 'A' { abc[0] } else { abc[1] };
        (t, abc[2])
    }

    /// The bed position of part-frame point `w` with the linear axes at zero.
    fn table_point(&self, w: V, abc: V) -> V {
        let (t, c) = self.angles(abc);
        let on_c = rot('C', -c, sub(add(self.datum, w), self.p_c));
        add(
            self.p_t,
            rot(self.tilt, -t, add(sub(self.p_c, self.p_t), on_c)),
        )
    }

    /// Closed-form inverse kinematics: axes X, Y, Z for tip `w` at angles `abc`.
    fn inverse(&self, w: V, abc: V) -> V {
        let b = self.table_point(w, abc);
        [b[0], b[1], b[2] + self.length_mm]
    }

    /// Closed-form forward kinematics: the tip in the part frame for axes `q`, `abc`.
    fn forward(&self, q: V, abc: V) -> V {
        let (t, c) = self.angles(abc);
        // Undo b(w) = tip + (X, Y, 0): tip in the bed is (0, 0, Z − L).
        let b = [q[0], q[1], q[2] - self.length_mm];
        let on_t = rot(self.tilt, t, sub(b, self.p_t));
        let on_c = rot('C', c, sub(on_t, sub(self.p_c, self.p_t)));
        sub(add(on_c, self.p_c), self.datum)
    }
}

/// Both machine files: the trunnion tilting about `tilt`, C on it, the same sizes.
fn trunnion(tilt: char) -> Trunnion {
    Trunnion {
        tilt,
        p_c: [0.0, 0.0, -450.0],
        p_t: [0.0, 0.0, -500.0],
        datum: [150.0, 0.0, -350.0],
        length_mm: 150.0,
    }
}

fn spec(file: &str, text: &str) -> FiveAxisSpec {
    FiveAxisSpec::from_toml_str(text, file).unwrap()
}

/// Part zero 150 mm towards −X and 100 mm below the datum: the table's centre on its surface.
const OFFSET: V = [-150.0, 0.0, -100.0];

/// (part-frame tip as programmed, A B C) at each dwell of `program`.
fn check(spec: &FiveAxisSpec, machine: &Trunnion, program: &str, dwells: &[(V, V)]) {
    let plan = plan_program(program, "t.ngc", spec, "m.toml").unwrap();
    let points = commanded_points(&plan, Sampling::EveryCycle(0.005));
    let at_dwell: Vec<_> = points.iter().filter(|p| p.at_dwell).collect();
    assert_eq!(at_dwell.len(), dwells.len());
    for (p, (w, abc)) in at_dwell.iter().zip(dwells) {
        assert_eq!(p.abc_deg, *abc);
        let want = machine.inverse(add(*w, OFFSET), *abc);
        for i in 0..3 {
            assert!(
                (p.q_mm[i] - want[i]).abs() < 1e-9,
                "line {}: {:?} vs {want:?}",
                p.line,
                p.q_mm
            );
        }
    }
    // Between dwells k and k+1 (a G1 of line `line`): the tip on the straight line between the
    // programmed tips, at the fraction the rotary axes have turned.
    for (k, pair) in dwells.windows(2).enumerate() {
        let ((w0, abc0), (w1, abc1)) = (pair[0], pair[1]);
        let i_rot = (0..3).find(|&i| abc0[i] != abc1[i]).unwrap();
        let line = at_dwell[k + 1].line - 1;
        let moving: Vec<_> = points
            .iter()
            .filter(|p| !p.at_dwell && p.line == line)
            .collect();
        assert!(moving.len() > 10, "line {line}");
        for p in moving {
            let f = (p.abc_deg[i_rot] - abc0[i_rot]) / (abc1[i_rot] - abc0[i_rot]);
            let tip = sub(machine.forward(p.q_mm, p.abc_deg), OFFSET);
            for i in 0..3 {
                let want = w0[i] + f * (w1[i] - w0[i]);
                assert!(
                    (tip[i] - want).abs() < 1e-9,
                    "line {line}: {tip:?} at f = {f}"
                );
            }
        }
    }
}

const BC_PROGRAM: &str = "G10 L2 P1 X-150 Y0 Z-100
G53 G0 Z0
G43.4 H1
G0 X0 Y0 Z50 B0 C0
G4 P0.1
G1 X20 Y10 Z30 B-30 C45 F1500
G4 P0.1
G1 X-20 Y-25 Z40 B-60 C200
G4 P0.1
G1 X35 Y0 Z20 B-90 C330
G4 P0.1
G49
G53 G0 X0 Y0 Z0
M2
";

#[test]
fn g43_4_moves_on_the_b_c_machine_follow_its_closed_form_kinematics() {
    let s = spec(
        "trunnion-bc.toml",
        include_str!("../../../machines/trunnion-bc.toml"),
    );
    let m = trunnion('B');
    let dwells = [
        ([0.0, 0.0, 50.0], [0.0, 0.0, 0.0]),
        ([20.0, 10.0, 30.0], [0.0, -30.0, 45.0]),
        ([-20.0, -25.0, 40.0], [0.0, -60.0, 200.0]),
        ([35.0, 0.0, 20.0], [0.0, -90.0, 330.0]),
    ];
    check(&s, &m, BC_PROGRAM, &dwells);
}

#[test]
fn g43_4_moves_on_the_a_c_machine_follow_its_closed_form_kinematics() {
    let s = spec(
        "trunnion-ac.toml",
        include_str!("../../../machines/trunnion-ac.toml"),
    );
    let m = trunnion('A');
    let program = BC_PROGRAM.replace(" B", " A");
    let dwells = [
        ([0.0, 0.0, 50.0], [0.0, 0.0, 0.0]),
        ([20.0, 10.0, 30.0], [-30.0, 0.0, 45.0]),
        ([-20.0, -25.0, 40.0], [-60.0, 0.0, 200.0]),
        ([35.0, 0.0, 20.0], [-90.0, 0.0, 330.0]),
    ];
    check(&s, &m, &program, &dwells);
}

#[test]
fn a_rotary_turn_alone_under_g43_4_keeps_the_tip_on_its_point() {
    // The classic check of a TCP controller: the tip stays put on the part while B and C turn.
    let s = spec(
        "trunnion-bc.toml",
        include_str!("../../../machines/trunnion-bc.toml"),
    );
    let program = "G10 L2 P1 X-150 Y0 Z-100\nG43.4 H1\nG0 X10 Y-5 Z60 B0 C0\nG1 B-70 C120 F3600\nG4 P0.1\nM2\n";
    let plan = plan_program(program, "t.ngc", &s, "m.toml").unwrap();
    let geom = s.geometry();
    let points = commanded_points(&plan, Sampling::EveryCycle(0.005));
    let turning: Vec<_> = points.iter().filter(|p| p.line == 4).collect();
    assert!(turning.len() > 100);
    let m = trunnion('B');
    assert_eq!(geom.datum_mm, m.datum);
    for p in turning {
        let tip = sub(m.forward(p.q_mm, p.abc_deg), OFFSET);
        let d = sub(tip, [10.0, -5.0, 60.0]);
        assert!(
            d.iter().all(|x| x.abs() < 1e-9),
            "{tip:?} at {:?}",
            p.abc_deg
        );
    }
}

#[test]
fn a_g43_4_move_that_takes_an_axis_beyond_its_travel_is_refused_with_its_line() {
    let s = spec(
        "trunnion-bc.toml",
        include_str!("../../../machines/trunnion-bc.toml"),
    );
    // 300 mm from the C axis at C 0: X would go to +150 + 300 − 150… beyond +250 at B −90.
    let program = "G10 L2 P1 X-150 Y0 Z-100\nG43.4 H1\nG0 X0 Y0 Z50\nG1 X240 B-90 F2000\nM2\n";
    let e = plan_program(program, "t.ngc", &s, "m.toml").unwrap_err();
    assert!(
        e.to_string().starts_with("t.ngc: line 4: under G43.4 axis"),
        "{e}"
    );
}
