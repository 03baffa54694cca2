//! Exact rigid-body kinematics of the 3-axis machine: the twin's truth.
//!
//! The tool tip relative to the workpiece is the full product of homogeneous transforms along the
//! chain, with exact rotations built from the error angles (no small-angle linearisation):
//!
//! ```text
//! workpiece_from_tool = bed_from_workpiece⁻¹ · bed_from_tool
//! bed_from_workpiece  = bed_from_A_k · … · A_2_from_A_1 · Trans(T)      (A_1 carries w, A_k on b)
//! bed_from_tool       = bed_from_B_1 · … · B_{m−1}_from_B_m · B_m_from_spindle · Trans(T)
//! parent_from_carriage = Trans(s·q·d + δ) · Rot(ε),   Rot(ε) = R_z(ε_z)·R_y(ε_y)·R_x(ε_x)
//! B_m_from_spindle    = Trans(δ_b) · R_y(ε_yb)·R_x(ε_xb)
//! E = translation(workpiece_from_tool) − q
//! ```
//!
//! Conventions (the same as `vmc_predict::synthesis`, whose module doc also gives the first-order
//! equations; lengths in mm, angles in rad):
//! - Bed frame right-handed along the nominal X, Y, Z travels, origin at the spindle gauge point
//!   at machine zero (all axes at 0).
//! - Axis positions `q = (X, Y, Z)` are tool relative to workpiece (ISO 841): a tool-side
//!   carriage moves `+q` along its travel direction `d` relative to its parent (`s = +1`), a
//!   workpiece-side carriage (table, saddle) physically moves `−q` (`s = −1`).
//! - Every carriage frame has its origin at the axis's reference point: the carriage's material
//!   point that sits at the bed origin at machine zero (for the spindle carriage, the gauge point).
//!   The motion errors `δ` (translation of that point, in the parent frame) and `ε` (rotation
//!   about that point) are physical carriage motions, so a table axis's error enters the
//!   tool-to-workpiece error with the opposite sign of a head axis's error.
//! - Squareness tilts the travel direction only (the carriage keeps its orientation), X being the
//!   reference: `d_X = e_x`, `d_Y = R_z(α_xy)·e_y = (−sin α_xy, cos α_xy, 0)`,
//!   `d_Z = R_x(α_yz)·R_y(α_xz)·e_z = (sin α_xz, −cos α_xz·sin α_yz, cos α_xz·cos α_yz)`.
//! - The spindle sits on the last tool-side carriage (or on the bed); its drifts translate the
//!   gauge point and tilt the tool axis about it. The tool tip is `T` from the gauge point in
//!   the (tilted) spindle frame.
//! - The workpiece frame is fixed to the carriage carrying `w` (or the bed) with its origin where
//!   the tool tip sits at machine zero, so the nominal tool tip in the workpiece frame is `q`.
//! - `E` is expressed in the (actual) workpiece frame.
//!
//! Transforms are `Isometry3<f64>` named `a_from_b` (maps coordinates in `b` to coordinates in
//! `a`) and composed right to left.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use vmc_predict::synthesis::{
    AxisErrors, ElementaryErrors, LinearAxis, MachineGeometry, Side, SpindleDrift, Squareness,
};

/// Exact unit direction of travel of `axis` in its parent's frame, tilted by the squareness errors.
#[must_use]
pub fn travel_direction(axis: LinearAxis, squareness: &Squareness) -> Vector3<f64> {
    match axis {
        LinearAxis::X => Vector3::x(),
        LinearAxis::Y => {
            let (s, c) = squareness.xy_rad.sin_cos();
            Vector3::new(-s, c, 0.0)
        }
        LinearAxis::Z => {
            let (sa, ca) = squareness.xz_rad.sin_cos();
            let (sb, cb) = squareness.yz_rad.sin_cos();
            Vector3::new(sa, -ca * sb, ca * cb)
        }
    }
}

/// Exact rotation `R_z(ε_z)·R_y(ε_y)·R_x(ε_x)` from a carriage's three angular errors (rad).
#[must_use]
pub fn error_rotation(ang_rad: [f64; 3]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_euler_angles(ang_rad[0], ang_rad[1], ang_rad[2])
}

/// Pose of a carriage relative to the element it rides on: `Trans(s·q·d + δ) · Rot(ε)`.
#[must_use]
pub fn parent_from_carriage(
    axis: LinearAxis,
    side: Side,
    pos_mm: f64,
    errors: &AxisErrors,
    squareness: &Squareness,
) -> Isometry3<f64> {
    let travel_mm = travel_direction(axis, squareness) * (side.sign() * pos_mm);
    let delta_mm = Vector3::from(errors.lin_mm);
    Isometry3::from_parts(
        Translation3::from(travel_mm + delta_mm),
        error_rotation(errors.ang_rad),
    )
}

/// Pose of the spindle frame (origin at the gauge point) relative to the carriage holding it:
/// translation by the drifts `δ_b`, tilt `R_y(ε_yb)·R_x(ε_xb)` about the gauge point.
#[must_use]
pub fn carriage_from_spindle(drift: &SpindleDrift) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(Vector3::from(drift.lin_mm)),
        error_rotation([drift.tilt_rad[0], drift.tilt_rad[1], 0.0]),
    )
}

/// Every frame of the machine at one pose, in bed coordinates (for the error model, the
/// visualisation and the collision checks alike).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MachinePose {
    /// Each carriage's frame (origin at its reference point), indexed by axis X, Y, Z.
    pub bed_from_carriage: [Isometry3<f64>; 3],
    /// Spindle frame, origin at the gauge point, z along the tool axis.
    pub bed_from_spindle: Isometry3<f64>,
    /// Tool frame, origin at the tool tip, oriented like the spindle.
    pub bed_from_tool: Isometry3<f64>,
    /// Workpiece frame, origin where the tool tip sits at machine zero.
    pub bed_from_workpiece: Isometry3<f64>,
}

impl MachinePose {
    /// The tool frame seen from the workpiece frame.
    #[must_use]
    pub fn workpiece_from_tool(&self) -> Isometry3<f64> {
        self.bed_from_workpiece.inverse() * self.bed_from_tool
    }
}

/// All frames at axis positions `axis_pos_mm` with the elementary errors `e` (exact HTM product).
#[must_use]
pub fn machine_pose(
    geom: &MachineGeometry,
    axis_pos_mm: [f64; 3],
    e: &ElementaryErrors,
) -> MachinePose {
    let chain = &geom.chain;
    let tool_from_gauge = Translation3::from(Vector3::from(geom.tool_offset_mm));
    let mut bed_from_carriage = [Isometry3::identity(); 3];

    // Workpiece side, walked from the bed outwards to the carriage holding the workpiece.
    let mut bed_from_outer = Isometry3::identity();
    for &axis in chain.workpiece_side().iter().rev() {
        let k = axis.index();
        bed_from_outer *= parent_from_carriage(
            axis,
            Side::Workpiece,
            axis_pos_mm[k],
            &e.axes[k],
            &e.squareness,
        );
        bed_from_carriage[k] = bed_from_outer;
    }
    let bed_from_workpiece = bed_from_outer * tool_from_gauge;

    // Tool side, walked from the bed outwards to the carriage holding the spindle.
    let mut bed_from_outer = Isometry3::identity();
    for &axis in chain.tool_side() {
        let k = axis.index();
        bed_from_outer *=
            parent_from_carriage(axis, Side::Tool, axis_pos_mm[k], &e.axes[k], &e.squareness);
        bed_from_carriage[k] = bed_from_outer;
    }
    let bed_from_spindle = bed_from_outer * carriage_from_spindle(&e.spindle);
    let bed_from_tool = bed_from_spindle * tool_from_gauge;

    MachinePose {
        bed_from_carriage,
        bed_from_spindle,
        bed_from_tool,
        bed_from_workpiece,
    }
}

/// All frames with no errors at all.
#[must_use]
pub fn nominal_machine_pose(geom: &MachineGeometry, axis_pos_mm: [f64; 3]) -> MachinePose {
    machine_pose(geom, axis_pos_mm, &ElementaryErrors::default())
}

/// Actual workpiece frame in bed coordinates.
#[must_use]
pub fn bed_from_workpiece(
    geom: &MachineGeometry,
    axis_pos_mm: [f64; 3],
    e: &ElementaryErrors,
) -> Isometry3<f64> {
    machine_pose(geom, axis_pos_mm, e).bed_from_workpiece
}

/// Actual tool frame (origin at the tip) in bed coordinates.
#[must_use]
pub fn bed_from_tool(
    geom: &MachineGeometry,
    axis_pos_mm: [f64; 3],
    e: &ElementaryErrors,
) -> Isometry3<f64> {
    machine_pose(geom, axis_pos_mm, e).bed_from_tool
}

/// Actual tool frame in workpiece coordinates.
#[must_use]
pub fn workpiece_from_tool(
    geom: &MachineGeometry,
    axis_pos_mm: [f64; 3],
    e: &ElementaryErrors,
) -> Isometry3<f64> {
    machine_pose(geom, axis_pos_mm, e).workpiece_from_tool()
}

/// Nominal tool frame in workpiece coordinates: a pure translation by the axis positions.
#[must_use]
pub fn nominal_workpiece_from_tool(axis_pos_mm: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(Vector3::from(axis_pos_mm)),
        UnitQuaternion::identity(),
    )
}

/// Where the tool tip really is, in workpiece coordinates (mm).
#[must_use]
pub fn tool_tip_in_workpiece_mm(
    geom: &MachineGeometry,
    axis_pos_mm: [f64; 3],
    e: &ElementaryErrors,
) -> Point3<f64> {
    Point3::from(workpiece_from_tool(geom, axis_pos_mm, e).translation.vector)
}

/// Volumetric error by the exact HTM product: actual − nominal tool tip relative to the
/// workpiece, in the workpiece frame (mm).
#[must_use]
pub fn full_error_mm(
    geom: &MachineGeometry,
    axis_pos_mm: [f64; 3],
    e: &ElementaryErrors,
) -> Vector3<f64> {
    tool_tip_in_workpiece_mm(geom, axis_pos_mm, e) - Point3::from(axis_pos_mm)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use vmc_predict::synthesis::reference_cases::{
        single_error as only, SingleError as One, CASE_CHAIN, CASE_Q_MM, CASE_TOOL_MM,
        SINGLE_ERROR_CASES,
    };
    use vmc_predict::synthesis::{first_order_error_mm, Chain};

    /// 1e-9 mm = 1 pm: float rounding on ~1 m coordinates, far below anything physical.
    const EXACT_MM: f64 = 1e-9;

    fn geometry(chain: &str, tool_offset_mm: [f64; 3]) -> MachineGeometry {
        MachineGeometry {
            chain: Chain::parse(chain).unwrap(),
            tool_offset_mm,
        }
    }

    /// All 24 chains: 3! axis orders × 4 places for the bed.
    fn all_chains() -> Vec<Chain> {
        let orders = ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"];
        let mut chains = Vec::new();
        for order in orders {
            for bed in 0..=3 {
                let mut s = String::from("w");
                s.push_str(&order[..bed]);
                s.push('b');
                s.push_str(&order[bed..]);
                s.push('t');
                chains.push(Chain::parse(&s).unwrap());
            }
        }
        chains
    }

    fn assert_close(got: Vector3<f64>, want: [f64; 3], tol_mm: f64, what: &str) {
        for i in 0..3 {
            assert!(
                (got[i] - want[i]).abs() < tol_mm,
                "{what}: got {got:?}, want {want:?} (tolerance {tol_mm} mm)"
            );
        }
    }

    #[test]
    fn nominal_poses_of_three_chains_match_hand_computation() {
        let q = [100.0, 200.0, -300.0];
        let t = [0.0, 0.0, -150.0];
        // (chain, workpiece origin in bed, tool tip in bed), worked by hand: workpiece-side axes
        // move the workpiece by −q, tool-side axes move the tip by +q, both start at T.
        let cases = [
            ("w X Y b Z t", [-100.0, -200.0, -150.0], [0.0, 0.0, -450.0]),
            ("w b X Y Z t", [0.0, 0.0, -150.0], [100.0, 200.0, -450.0]),
            ("w X Y Z b t", [-100.0, -200.0, 150.0], [0.0, 0.0, -150.0]),
            ("w Y b X Z t", [0.0, -200.0, -150.0], [100.0, 0.0, -450.0]),
        ];
        for (chain, workpiece, tip) in cases {
            let pose = nominal_machine_pose(&geometry(chain, t), q);
            assert_close(
                pose.bed_from_workpiece.translation.vector,
                workpiece,
                EXACT_MM,
                chain,
            );
            assert_close(pose.bed_from_tool.translation.vector, tip, EXACT_MM, chain);
            let gauge = pose.bed_from_spindle.translation.vector;
            assert_close(gauge, [tip[0], tip[1], tip[2] + 150.0], EXACT_MM, chain);
            let tip_in_workpiece = pose.workpiece_from_tool().translation.vector;
            assert_close(tip_in_workpiece, q, EXACT_MM, chain);
        }
    }

    #[test]
    fn nominal_carriage_frames_sit_at_their_signed_positions() {
        // w X Y b Z t: the saddle moves by −Y, the table by −Y − X, the head by +Z.
        let pose = nominal_machine_pose(&geometry("w X Y b Z t", [0.0; 3]), [100.0, 200.0, -300.0]);
        let at = |k: usize| pose.bed_from_carriage[k].translation.vector;
        assert_close(at(0), [-100.0, -200.0, 0.0], EXACT_MM, "X table");
        assert_close(at(1), [0.0, -200.0, 0.0], EXACT_MM, "Y saddle");
        assert_close(at(2), [0.0, 0.0, -300.0], EXACT_MM, "Z head");
    }

    /// 1e-7 mm = 0.1 nm: the second-order remainder of one 1e-5 rad angle on a 0.5 m arm
    /// (ε²·a/2 ≈ 2.5e-8 mm) passes, any sign or arm mistake (≥ 1e-4 mm here) does not.
    const SINGLE_ERROR_TOL_MM: f64 = 1e-7;

    #[test]
    fn each_of_the_26_errors_alone_moves_the_true_tool_tip_as_derived_by_hand() {
        let geom = geometry(CASE_CHAIN, CASE_TOOL_MM);
        for (name, which, value, want) in SINGLE_ERROR_CASES {
            let got = full_error_mm(&geom, CASE_Q_MM, &only(which, value));
            assert_close(got, want, SINGLE_ERROR_TOL_MM, name);
        }
    }

    #[test]
    fn single_errors_on_a_gantry_style_chain_follow_the_same_rules() {
        // w Y b X Z t: Y table (workpiece side), X then Z on the tool side. q = (100, 200, −300),
        // T = (0, 0, −150). Arms: Y (100, 200, −450) [Y carries nothing: every position enters],
        // X (0, 0, −450) [carries Z], Z (0, 0, −150).
        let geom = geometry("w Y b X Z t", [0.0, 0.0, -150.0]);
        let q = [100.0, 200.0, -300.0];
        let rows = [
            ("δ_xx tool side", One::Lin(0, 0), 0.002, [0.002, 0.0, 0.0]),
            ("δ_yy table", One::Lin(1, 1), 0.002, [0.0, -0.002, 0.0]),
            // +ε_y × (0, 0, −450) = (−4.5e-3, 0, 0).
            ("ε_yx tool side", One::Ang(0, 1), 1e-5, [-4.5e-3, 0.0, 0.0]),
            // −ε_x × (0, 200, −450) = −(0, 4.5e-3, 2e-3).
            ("ε_xy table", One::Ang(1, 0), 1e-5, [0.0, -4.5e-3, -2e-3]),
            // −ε_z × (100, 200, −450) = −(−2e-3, 1e-3, 0).
            ("ε_zy table", One::Ang(1, 2), 1e-5, [2e-3, -1e-3, 0.0]),
            ("α_xy", One::SqXy, 2e-5, [-4e-3, 0.0, 0.0]),
        ];
        for (name, which, value, want) in rows {
            let e = only(which, value);
            assert_close(full_error_mm(&geom, q, &e), want, SINGLE_ERROR_TOL_MM, name);
            let first = first_order_error_mm(&geom, q, &e);
            assert_close(first, want, EXACT_MM, name);
        }
    }

    #[test]
    fn four_arcsec_z_pitch_on_a_300_mm_tool_moves_the_tip_5_8_um() {
        let geom = geometry("w X Y b Z t", [0.0, 0.0, -300.0]);
        let four_arcsec_rad = 4.0 / 3600.0 * std::f64::consts::PI / 180.0;
        let got = full_error_mm(
            &geom,
            [250.0, 150.0, -100.0],
            &only(One::Ang(2, 1), four_arcsec_rad),
        );
        // 300 mm · 19.39 µrad = 5.818 µm towards −X; checked to 1 nm.
        assert_close(got, [-5.818e-3, 0.0, 0.0], 1e-6, "4″ Z pitch");
    }

    /// Elementary errors drawn uniformly within the given envelopes: positioning errors (δ_jj)
    /// and spindle drifts ±`positioning_mm`, straightness ±`straightness_mm`, motion angles and
    /// spindle tilts ±`angle_rad`, squareness ±20 µrad.
    fn errors_within(
        positioning_mm: f64,
        straightness_mm: f64,
        angle_rad: f64,
    ) -> impl Strategy<Value = ElementaryErrors> {
        let axis = move |k: usize| {
            (
                prop::array::uniform3(-straightness_mm..straightness_mm),
                -positioning_mm..positioning_mm,
                prop::array::uniform3(-angle_rad..angle_rad),
            )
                .prop_map(move |(mut lin_mm, positioning, ang_rad)| {
                    lin_mm[k] = positioning;
                    AxisErrors { lin_mm, ang_rad }
                })
        };
        (
            [axis(0), axis(1), axis(2)],
            prop::array::uniform3(-20e-6f64..20e-6),
            prop::array::uniform3(-positioning_mm..positioning_mm),
            prop::array::uniform2(-angle_rad..angle_rad),
        )
            .prop_map(|(axes, sq, sp_lin, sp_tilt)| ElementaryErrors {
                axes,
                squareness: Squareness {
                    xy_rad: sq[0],
                    xz_rad: sq[1],
                    yz_rad: sq[2],
                },
                spindle: SpindleDrift {
                    lin_mm: sp_lin,
                    tilt_rad: sp_tilt,
                },
            })
    }

    /// Second-order size of the linearisation remainder: θ·D + θ²·R with θ the sum of all angle
    /// magnitudes (rad), D the sum of all translation magnitudes (mm) and R = |q| + |T| ≥ every
    /// Abbe arm (mm). Every neglected term is a product ε·δ or ε·ε·a, so the gap stays below it
    /// (a scan of 10⁶ random cases found gap/bound ≤ 0.19, at 10″ and at 100× that).
    fn second_order_bound_mm(geom: &MachineGeometry, q: [f64; 3], e: &ElementaryErrors) -> f64 {
        let sum_abs = |v: &[f64]| v.iter().map(|x| x.abs()).sum::<f64>();
        let sq = e.squareness;
        let mut theta = sq.xy_rad.abs() + sq.xz_rad.abs() + sq.yz_rad.abs();
        theta += sum_abs(&e.spindle.tilt_rad);
        let mut d = sum_abs(&e.spindle.lin_mm);
        for axis in &e.axes {
            theta += sum_abs(&axis.ang_rad);
            d += sum_abs(&axis.lin_mm);
        }
        let r = Vector3::from(q).norm() + Vector3::from(geom.tool_offset_mm).norm();
        theta * d + theta * theta * r
    }

    /// 4″ in rad: the upper end of the reference machine's angular errors.
    const FOUR_ARCSEC_RAD: f64 = 19.39e-6;
    /// 10″ in rad: two and a half times the largest angle the reference machine has (4″).
    const TEN_ARCSEC_RAD: f64 = 48.48e-6;

    fn travel_pose() -> impl Strategy<Value = [f64; 3]> {
        (0.0f64..560.0, 0.0f64..400.0, -450.0f64..0.0).prop_map(|(x, y, z)| [x, y, z])
    }

    fn tool_offset() -> impl Strategy<Value = [f64; 3]> {
        (-5.0f64..5.0, -5.0f64..5.0, -200.0f64..-100.0).prop_map(|(x, y, z)| [x, y, z])
    }

    proptest! {
        // Fixed seed: the same cases on every run (determinism rule), no regression files.
        #![proptest_config(ProptestConfig {
            cases: 512,
            rng_seed: proptest::test_runner::RngSeed::Fixed(0x6b69_6e65),
            failure_persistence: None,
            ..ProptestConfig::default()
        })]

        #[test]
        fn with_no_errors_the_tool_tip_is_at_the_commanded_position_on_every_chain(
            chain in 0usize..24, q in travel_pose(), t in tool_offset(),
        ) {
            let geom = MachineGeometry { chain: all_chains()[chain], tool_offset_mm: t };
            let tip = tool_tip_in_workpiece_mm(&geom, q, &ElementaryErrors::default());
            prop_assert!((tip - Point3::from(q)).norm() < EXACT_MM);
            let nominal = nominal_workpiece_from_tool(q);
            prop_assert!((nominal.translation.vector - tip.coords).norm() < EXACT_MM);
        }

        /// Reference machine: positioning ±50 µm, straightness ±5 µm, angles ±4″,
        /// squareness ±20 µrad. 1e-5 mm = 0.01 µm is Appendix A's bound; a 5×10⁵-case scan
        /// peaked at 0.0044 µm.
        #[test]
        fn full_model_and_first_order_agree_to_0_01_um_on_the_reference_machine(
            chain in 0usize..24, q in travel_pose(), t in tool_offset(),
            e in errors_within(0.05, 0.005, FOUR_ARCSEC_RAD),
        ) {
            let geom = MachineGeometry { chain: all_chains()[chain], tool_offset_mm: t };
            let gap = full_error_mm(&geom, q, &e) - first_order_error_mm(&geom, q, &e);
            prop_assert!(gap.amax() < 1e-5, "{}: gap {} mm", geom.chain, gap);
        }

        /// Every translation ±50 µm and every angle ±10″ at once: the remainder is no longer
        /// always under 0.01 µm (scan: median 0.0036 µm, 99th percentile 0.012 µm, max 0.023 µm),
        /// but it must stay second order, i.e. under θ·D + θ²·R (≈ 0.2 µm here), while any
        /// wrong first-order term would show as ε·a ≈ 48 µrad · 500 mm = 24 µm.
        #[test]
        fn full_model_and_first_order_differ_only_at_second_order_with_10_arcsec_angles(
            chain in 0usize..24, q in travel_pose(), t in tool_offset(),
            e in errors_within(0.05, 0.05, TEN_ARCSEC_RAD),
        ) {
            let geom = MachineGeometry { chain: all_chains()[chain], tool_offset_mm: t };
            let gap = (full_error_mm(&geom, q, &e) - first_order_error_mm(&geom, q, &e)).amax();
            let bound = second_order_bound_mm(&geom, q, &e);
            prop_assert!(gap < bound, "{}: gap {gap} mm over bound {bound} mm", geom.chain);
            prop_assert!(gap < 5e-5, "{}: gap {gap} mm", geom.chain);
        }
    }

    #[test]
    fn full_model_and_first_order_part_at_absurd_angles() {
        // 0.01 rad on every angle: second-order terms ε²·a ≈ 1e-4 · 500 mm = 0.05 mm.
        let geom = geometry("w X Y b Z t", [0.0, 0.0, -150.0]);
        let mut e = ElementaryErrors::default();
        for axis in &mut e.axes {
            axis.ang_rad = [0.01; 3];
        }
        e.spindle.tilt_rad = [0.01; 2];
        let q = [500.0, 350.0, -400.0];
        let gap_mm = (full_error_mm(&geom, q, &e) - first_order_error_mm(&geom, q, &e)).amax();
        assert!(gap_mm > 1e-3, "gap only {gap_mm} mm");
    }
}
