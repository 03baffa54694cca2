//! Collision tests on the reference machine: exact depths on simple geometry, the crash rules
//! (rapid vs feed, spindle, retraction), the 0.1 mm sampling bound, and field-named errors.

use super::*;
use crate::program;

const VISE: &str = include_str!("../../../../tests/data/collision/vise.toml");

fn machine() -> MachineSpec {
    MachineSpec::reference()
}

fn scene(fixture: &str) -> (MachineSpec, Scene) {
    let m = machine();
    let f = FixtureSpec::from_toml_str(fixture, "f.toml").expect("valid fixture");
    let s = Scene::new(&m, Some(&f)).expect("scene");
    (m, s)
}

fn problems(src: &str, fixture: &str) -> Vec<Problem> {
    let (m, s) = scene(fixture);
    let plan = program::plan_source_unchecked(src, "p.ngc", &m, m.axes.home_mm).expect("plan");
    let mut out = Vec::new();
    let sum = check_plan(&plan, &m, Some(&s), &mut out).expect("check");
    assert_eq!(sum.collisions + sum.travel_violations, out.len());
    out
}

fn collisions(src: &str, fixture: &str) -> Vec<Collision> {
    problems(src, fixture)
        .into_iter()
        .filter_map(|p| match p {
            Problem::Collision(c) => Some(c),
            Problem::Travel(_) => None,
        })
        .collect()
}

/// A 100 × 80 × 40 mm stock block on the table, top at Z −400.
const BLOCK: &str = r#"bodies = [
  { name = "block", role = "stock", shape = "box", min_mm = [100.0, 100.0, -440.0], max_mm = [200.0, 180.0, -400.0] },
]"#;

#[test]
fn the_reference_machine_has_collision_geometry_and_its_diagonals_are_clean() {
    let m = machine();
    let s = Scene::new(&m, None).expect("reference has [collision]");
    // The geometry is there: the tool plunged to the bottom of the Z travel is 10 mm into the
    // table (its top is 10 mm below the diagonals' lowest tool tip, Z −430).
    let c = collisions(
        "S3000 M3\nG0 X100 Y100 Z-400\nG1 Z-450 F300\nM30",
        "bodies = []",
    );
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!(
        (c[0].head_body, c[0].other_body.as_str()),
        (HeadBody::Tool, "table")
    );
    assert!((c[0].depth_mm - 10.0).abs() < 1e-6, "{}", c[0].depth_mm);
    for (name, text) in crate::program::DIAGONALS {
        let plan = program::plan_source_unchecked(text, name, &m, m.axes.home_mm).unwrap();
        let mut out = Vec::new();
        let sum = check_plan(&plan, &m, Some(&s), &mut out).unwrap();
        assert!(sum.is_clean(), "{name}: {out:?}");
        assert!(sum.segments >= 10, "{name}");
    }
}

#[test]
fn a_rapid_into_the_stock_is_a_crash_with_its_exact_depth_and_line() {
    let c = collisions("G0 X150 Y140\nG0 Z-403\nM30", BLOCK);
    assert_eq!(c.len(), 1, "{c:?}");
    let c = &c[0];
    assert_eq!(
        (c.line, c.move_kind, c.head_body, c.other_body.as_str()),
        (2, MoveKind::Rapid, HeadBody::Tool, "block")
    );
    assert_eq!(c.reason, "rapid into the stock");
    assert!((c.depth_mm - 3.0).abs() < 1e-6, "{}", c.depth_mm);
    assert_eq!(c.tip_mm, [150.0, 140.0, -403.0]);
    // First contact within one sample step (0.2 mm) below the top face.
    assert!(c.first_contact_tip_mm[2] < -400.0 && c.first_contact_tip_mm[2] >= -400.2 - 1e-9);
    assert!(c.first_contact_time_s < c.time_s);
    assert!((c.contact_point_mm[2] + 400.0).abs() < 1e-6);
}

#[test]
fn cutting_at_feed_is_allowed_but_not_with_the_spindle_stopped() {
    let cut = "S5000 M3\nG0 X150 Y140 Z-390\nG1 Z-410 F200\nG1 X160\nG2 X150 I-5\nG0 Z-300\nM30";
    assert!(collisions(cut, BLOCK).is_empty());
    let stopped = "G0 X150 Y140 Z-390\nG1 Z-410 F200\nM30";
    let c = collisions(stopped, BLOCK);
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!(c[0].reason, "cut with the spindle stopped");
    assert!((c[0].depth_mm - 10.0).abs() < 1e-6);
}

#[test]
fn a_pure_retraction_out_of_the_cut_is_not_a_crash_but_a_sideways_rapid_is() {
    let retract = "S5000 M3\nG0 X150 Y140 Z-390\nG1 Z-410 F200\nG0 Z-300\nM30";
    assert!(collisions(retract, BLOCK).is_empty());
    let sideways = "S5000 M3\nG0 X150 Y140 Z-390\nG1 Z-410 F200\nG0 X170 Z-300\nM30";
    let c = collisions(sideways, BLOCK);
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!((c[0].line, c[0].reason), (4, "rapid into the stock"));
}

#[test]
fn material_cut_by_the_program_is_gone_for_later_rapids_but_uncut_material_is_not() {
    // A hole drilled at (150, 140) to Z −410, then a rapid back down into it (a peck
    // cycle's re-entry), and a slot cut along X to (170, 140): a rapid along the slot is free.
    let src = "S5000 M3\nG0 X150 Y140 Z-390\nG1 Z-410 F200\nG0 Z-395\nG0 Z-409\n\
               G1 X170 F500\nG0 X150 Z-405\nG0 Z-300\nM30";
    assert!(collisions(src, BLOCK).is_empty());
    // Beside the hole, by half a tool diameter: uncut material, a crash 3 mm deep (the
    // vertical overlap with the block's top at −400), reported on the rapid's line.
    let src = "S5000 M3\nG0 X150 Y140 Z-390\nG1 Z-410 F200\nG0 Z-395\nG0 X156\nG0 Z-403\nM30";
    let c = collisions(src, BLOCK);
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!((c[0].line, c[0].reason), (6, "rapid into the stock"));
    assert!((c[0].depth_mm - 3.0).abs() < 1e-9, "{}", c[0].depth_mm);
    // Material removed with the spindle stopped does not count: the feed move is itself
    // reported and the material stays for the next rapid.
    let src = "G0 X150 Y140 Z-390\nG1 Z-410 F200\nG0 Z-395\nG0 Z-409\nM30";
    let lines: Vec<usize> = collisions(src, BLOCK).iter().map(|c| c.line).collect();
    assert_eq!(lines, [2, 4]);
}

#[test]
fn the_tool_body_follows_the_tool_table() {
    // Positions are those of the machine's 150 mm tool tip. A 200 mm tool loaded without G43
    // reaches 50 mm lower: its rapid to 10 mm above the block is 40 mm into it. With G43 H2
    // it stops where the program says. A Ø40 tool clips the block on a rapid beside it.
    let table = "[[tool]]\nnumber = 2\nlength_mm = 200.0\ndiameter_mm = 10.0\n\
                 [[tool]]\nnumber = 3\nlength_mm = 150.0\ndiameter_mm = 40.0\n";
    let m = machine();
    let f = FixtureSpec::from_toml_str(BLOCK, "f.toml").unwrap();
    let tools = crate::tools::ToolTable::from_toml_str(table, "t.toml").unwrap();
    let s = Scene::new(&m, Some(&f)).unwrap().with_tools(tools.clone());
    let run = |src: &str| {
        let plan =
            program::plan_source_unchecked_with_tools(src, "p.ngc", &m, m.axes.home_mm, &tools)
                .expect("plan");
        let mut out = Vec::new();
        check_plan(&plan, &m, Some(&s), &mut out).expect("check");
        out.into_iter()
            .filter_map(|p| match p {
                Problem::Collision(c) => Some(c),
                Problem::Travel(_) => None,
            })
            .collect::<Vec<_>>()
    };
    let c = run("T2 M6\nG0 X150 Y140 Z-390\nM30");
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!((c[0].line, c[0].head_body), (2, HeadBody::Tool));
    assert!((c[0].depth_mm - 40.0).abs() < 1e-6, "{}", c[0].depth_mm);
    assert!(run("T2 M6\nG43 H2\nG0 X150 Y140 Z-390\nM30").is_empty());
    // 6 mm from the block's edge at X 100: the Ø12 tool clears it; the Ø40 tool overlaps it by
    // 14 mm sideways and, going down to 20 mm below its top, meets it (the stock's depth is the
    // vertical overlap, 20 mm).
    assert!(run("G0 X94 Y140 Z-380\nG0 Z-420\nM30").is_empty());
    let c = run("T3 M6\nG0 X94 Y140 Z-380\nG0 Z-420\nM30");
    assert_eq!(c.len(), 1, "{c:?}");
    assert!((c[0].depth_mm - 20.0).abs() < 1e-6, "{}", c[0].depth_mm);
}

#[test]
fn the_holder_and_the_spindle_nose_in_the_stock_are_crashes_even_at_feed() {
    // Tool 105 mm exposed: the holder enters the block top (Z −400) when the tip is below −505,
    // which is out of travel; use a tall cylinder stock instead: top at −250, tip down to −370.
    let tall = r#"bodies = [
      { name = "bar", role = "stock", shape = "cylinder", base_center_mm = [300.0, 200.0, -440.0], radius_mm = 60.0, height_mm = 190.0 },
    ]"#;
    let c = collisions("S5000 M3\nG0 X300 Y200 Z-200\nG1 Z-370 F300\nM30", tall);
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!(c[0].head_body, HeadBody::Holder);
    assert!((c[0].depth_mm - 15.0).abs() < 1e-6, "{}", c[0].depth_mm);
    // Further down, the spindle nose (from 150 mm above the tip) reaches it too.
    let c = collisions("S5000 M3\nG0 X300 Y200 Z-200\nG1 Z-420 F300\nM30", tall);
    let bodies: Vec<HeadBody> = c.iter().map(|c| c.head_body).collect();
    assert_eq!(bodies, [HeadBody::Holder, HeadBody::SpindleNose], "{c:?}");
    assert!((c[1].depth_mm - 20.0).abs() < 1e-6, "{}", c[1].depth_mm);
}

#[test]
fn a_crash_that_continues_into_the_next_move_is_reported_once_unless_it_deepens() {
    let src = "G0 X100 Y100 Z-400\nG1 Z-445 F300\nG1 X120 F300\nG1 Z-447\nG0 Z0\nM30";
    let c = collisions(src, "bodies = []");
    let lines: Vec<usize> = c.iter().map(|c| c.line).collect();
    // Line 3 stays 5 mm deep (continuing), line 4 goes deeper, line 5 leaves.
    assert_eq!(lines, [2, 4], "{c:?}");
    assert!((c[1].depth_mm - 7.0).abs() < 1e-6);
}

#[test]
fn contacts_on_arcs_are_found_on_the_arc_itself() {
    // A post of radius 10 at (450, 200); a G2 full circle of radius 30 around it with a Ø12
    // tool passes 14 mm from the post's axis: 10 + 6 − 14 = 2 mm deep, in the post's height.
    let post = r#"bodies = [
      { name = "post", role = "fixture", shape = "cylinder", base_center_mm = [450.0, 200.0, -440.0], radius_mm = 10.0, height_mm = 60.0 },
    ]"#;
    // Arc centre (466, 200), radius 30: its leftmost point X436 is 14 mm from the post axis.
    let src = "S3000 M3\nG0 X496 Y200 Z-400\nG2 X496 Y200 I-30 J0 F500\nM30";
    let c = collisions(src, post);
    assert_eq!(c.len(), 1, "{c:?}");
    assert_eq!((c[0].line, c[0].move_kind), (3, MoveKind::Arc));
    // Sampled at ≤ 0.2 mm along the path: the deepest sample is within the bound of the truth.
    assert!(
        c[0].depth_mm <= 2.0 + 1e-6 && c[0].depth_mm > 2.0 - 0.1,
        "{}",
        c[0].depth_mm
    );
}

proptest::proptest! {
    // Fixed seed: the same cases on every run (determinism rule), no regression files.
    #![proptest_config(proptest::prelude::ProptestConfig {
        cases: 96,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x636f_6c6c),
        failure_persistence: None,
        ..Default::default()
    })]
    /// The sampling bound, against a reference 200 times denser (1 µm steps): whenever the
    /// reference finds a contact deeper than 0.1 mm the check reports it, and never more than
    /// 0.1 mm shallower than the reference's deepest. Random short moves around a fixture corner.
    /// The reference is itself sampled: the penetration depth changes by at most the distance
    /// the tool moves (1-Lipschitz in translation), so the true deepest contact lies within half
    /// a reference step (0.5 µm) above the reference's, and the check may find up to that much
    /// more.
    #[test]
    fn no_contact_deeper_than_a_tenth_of_a_millimetre_is_missed(
        a in proptest::array::uniform3(-12.0f64..12.0),
        b in proptest::array::uniform3(-12.0f64..12.0),
    ) {
        let corner = r#"bodies = [
          { name = "corner", role = "fixture", shape = "box", min_mm = [100.0, 100.0, -440.0], max_mm = [200.0, 180.0, -400.0] },
        ]"#;
        let (m, scene) = scene(corner);
        // Around the block's corner (100, 100, −400), shifted so the tool's side and tip graze it.
        let start = [100.0 + a[0], 100.0 + a[1], -400.0 + a[2].abs()];
        let end = [100.0 + b[0], 100.0 + b[1], -400.0 + b[2].abs() - 4.0];
        let src = format!(
            "G0 X{:.4} Y{:.4} Z{:.4}\nG1 X{:.4} Y{:.4} Z{:.4} F1000\nM30",
            start[0], start[1], start[2], end[0], end[1], end[2]
        );
        let plan = program::plan_source_unchecked(&src, "p.ngc", &m, m.axes.home_mm).unwrap();
        let seg = plan.segments().iter().find(|s| s.line == 2).unwrap().clone();
        let tool = &scene.moving[0];
        let block = &scene.statics[1];
        let n = (seg.geometry.length_mm() / 0.001).ceil().max(1.0) as usize;
        let mut reference_mm: f64 = 0.0;
        for k in 0..=n {
            let tip = seg.geometry.point_at(seg.start_mm, seg.geometry.length_mm() * k as f64 / n as f64);
            if let Some((d, _)) = scene.penetration(tool, block, tip).unwrap() {
                reference_mm = reference_mm.max(d);
            }
        }
        let mut out = Vec::new();
        check_plan(&plan, &m, Some(&scene), &mut out).unwrap();
        let found_mm = out
            .iter()
            .filter_map(|p| match p {
                Problem::Collision(c) if c.line == 2 && c.head_body == HeadBody::Tool => Some(c.depth_mm),
                _ => None,
            })
            .fold(0.0, f64::max);
        if reference_mm > 0.1 {
            proptest::prop_assert!(found_mm > 0.0, "missed a {reference_mm} mm contact");
        }
        proptest::prop_assert!(found_mm >= reference_mm - 0.1 - 1e-9, "found {found_mm}, reference {reference_mm}");
        proptest::prop_assert!(found_mm <= reference_mm + 0.0005 + 1e-9, "found {found_mm}, reference {reference_mm}");
    }
}

#[test]
fn travel_violations_carry_the_same_message_as_the_planner() {
    let p = problems(
        "G0 X100 Y100 Z-100\nG1 X580 F2000\nG0 X100 Y-5\nM30",
        "bodies = []",
    );
    let msgs: Vec<String> = p.iter().map(|p| p.to_string()).collect();
    assert_eq!(
        msgs,
        [
            "line 2: axis X reaches 580 mm, outside travel [0, 560] mm",
            "line 3: axis X reaches 580 mm, outside travel [0, 560] mm",
            "line 3: axis Y reaches -5 mm, outside travel [0, 400] mm",
        ]
    );
    let m = machine();
    let err = program::plan_source(
        "G0 X100 Y100 Z-100\nG1 X580 F2000\nM30",
        "p.ngc",
        &m,
        m.axes.home_mm,
    )
    .unwrap_err();
    assert_eq!(err.to_string(), format!("p.ngc: {}", msgs[0]));
}

#[test]
fn the_vise_fixture_loads_and_bad_fixtures_name_the_field() {
    FixtureSpec::from_toml_str(VISE, "vise.toml").unwrap();
    let bad = |text: &str| {
        FixtureSpec::from_toml_str(text, "f.toml")
            .unwrap_err()
            .to_string()
    };
    let one = |body: &str| bad(&format!("bodies = [ {{ name = \"b\", {body} }} ]"));
    let m = one(
        r#"role = "fixture", shape = "box", min_mm = [0.0, 0.0, 0.0], max_mm = [1.0, -1.0, 1.0]"#,
    );
    assert!(m.contains("f.toml: field `bodies[0].max_mm[1]`"), "{m}");
    let m = one(
        r#"role = "fixture", shape = "cylinder", base_center_mm = [0.0, 0.0, 0.0], height_mm = 1.0"#,
    );
    assert!(
        m.contains("`bodies[0].radius_mm`") && m.contains("missing"),
        "{m}"
    );
    let m = one(
        r#"role = "stock", shape = "cylinder", base_center_mm = [0.0, 0.0, 0.0], radius_mm = nan, height_mm = 1.0"#,
    );
    assert!(m.contains("`bodies[0].radius_mm`"), "{m}");
    let m =
        one(r#"role = "stock", shape = "box", min_mm = [0.0, 0.0, inf], max_mm = [1.0, 1.0, 1.0]"#);
    assert!(m.contains("`bodies[0].min_mm[2]`"), "{m}");
    let m = one(
        r#"role = "stock", shape = "box", min_mm = [0.0, 0.0, 0.0], max_mm = [1.0, 1.0, 1.0], radius_mm = 3.0"#,
    );
    assert!(
        m.contains("`bodies[0].radius_mm`") && m.contains("not a field"),
        "{m}"
    );
    let m =
        one(r#"role = "clamp", shape = "box", min_mm = [0.0, 0.0, 0.0], max_mm = [1.0, 1.0, 1.0]"#);
    assert!(
        m.contains("f.toml") && m.contains("clamp") && m.contains("line 1"),
        "{m}"
    );
    let m = bad("bodies = [ { name = \"a\", role = \"stock\", shape = \"box\", min_mm = [0.0, 0.0, 0.0], max_mm = [1.0, 1.0, 1.0] }, { name = \"a\", role = \"stock\", shape = \"box\", min_mm = [0.0, 0.0, 0.0], max_mm = [1.0, 1.0, 1.0] } ]");
    assert!(
        m.contains("`bodies[1].name`") && m.contains("duplicate"),
        "{m}"
    );
}

#[test]
fn a_bad_collision_section_in_the_machine_file_names_the_field() {
    let mut m = machine();
    m.collision.as_mut().unwrap().holder.length_mm = 150.0;
    let e = m.validate("m.toml").unwrap_err().to_string();
    assert!(e.contains("`collision.holder.length_mm`"), "{e}");
    let mut m = machine();
    m.collision.as_mut().unwrap().spindle_nose.diameter_mm = f64::NAN;
    let e = m.validate("m.toml").unwrap_err().to_string();
    assert!(e.contains("`collision.spindle_nose.diameter_mm`"), "{e}");
    let mut m = machine();
    m.collision.as_mut().unwrap().bodies[0].max_mm = Some([1.0, 1.0, -600.0]);
    let e = m.validate("m.toml").unwrap_err().to_string();
    assert!(e.contains("`collision.bodies[0].max_mm[2]`"), "{e}");
    let mut m = machine();
    m.collision = None;
    assert!(Scene::new(&m, None).is_err());
}

#[test]
fn a_program_checked_piece_by_piece_reports_what_its_whole_plan_reports() {
    // A hole drilled, a rapid back into it (free: the Z-map carries the cut across pieces), a
    // rapid beside it (a crash), a crash into the table that continues on the next move (one
    // report, even when the two moves fall in different pieces) and a move beyond the travel.
    let src = "S5000 M3\nG0 X150 Y140 Z-390\nG1 Z-410 F200\nG0 Z-395\nG0 Z-409\nG0 Z-395\n\
               G0 X156\nG0 Z-403\nG0 Z-300\nG0 X250 Y250\nG1 Z-445 F300\nG1 X270 F300\n\
               G1 Z-447\nG0 Z0\nG0 X800\nG0 X300\nM30";
    let (m, s) = scene(BLOCK);
    let plan = program::plan_source_unchecked(src, "p.ngc", &m, m.axes.home_mm).expect("plan");
    let mut whole = Vec::new();
    let whole_sum = check_plan(&plan, &m, Some(&s), &mut whole).expect("check");
    assert_eq!((whole_sum.collisions, whole_sum.travel_violations), (3, 2));
    let placement = crate::setup::Placement::of_machine(&m);
    let tools = ToolTable::default();
    for moves_per_piece in [1, 2, 3, 5] {
        let source = program::Source {
            text: src,
            file: "p.ngc",
            placement: &placement,
            subroutine_dirs: Vec::new(),
        };
        let stream =
            program::PlanStream::from_source(source, &m, m.axes.home_mm, &tools, moves_per_piece)
                .expect("stream")
                .without_travel_check();
        let mut checker = PlanChecker::new(&m, Some(&s)).expect("checker");
        let mut pieces = Vec::new();
        for piece in stream {
            checker
                .check(&piece.expect("piece"), &mut pieces)
                .expect("check");
        }
        let sum = checker.summary();
        assert_eq!(
            (
                sum.segments,
                sum.samples,
                sum.collisions,
                sum.travel_violations
            ),
            (
                whole_sum.segments,
                whole_sum.samples,
                whole_sum.collisions,
                whole_sum.travel_violations
            ),
            "{moves_per_piece} moves a piece"
        );
        assert!((sum.path_mm - whole_sum.path_mm).abs() < 1e-9);
        assert_eq!(pieces.len(), whole.len(), "{moves_per_piece} moves a piece");
        for (p, w) in pieces.iter().zip(&whole) {
            // Times from the first piece's start, as in the whole plan.
            let time_s = |p: &Problem| match p {
                Problem::Collision(c) => c.time_s,
                Problem::Travel(t) => t.time_s,
            };
            assert!((time_s(p) - time_s(w)).abs() < 1e-6, "{p} / {w}");
            match (p, w) {
                (Problem::Collision(p), Problem::Collision(w)) => {
                    assert_eq!(
                        (p.line, &p.other_body, p.reason),
                        (w.line, &w.other_body, w.reason)
                    );
                    assert!((p.depth_mm - w.depth_mm).abs() < 1e-9, "{p:?} / {w:?}");
                }
                (Problem::Travel(p), Problem::Travel(w)) => assert_eq!(p.line, w.line),
                _ => panic!("{p} / {w}"),
            }
        }
    }
}
