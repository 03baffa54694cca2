//! Helical teeth: the straight-tooth results are unchanged at a helix of 0, semi-discretisation
//! with a helix meets the zero-order solution where the helix makes the force constant, and
//! agrees with the time domain.

use std::f64::consts::PI;

use vmc_dynamics::milling::{MillingSdm, SdmOptions};
use vmc_dynamics::time_domain::{ForceModel, TimeDomain, TimeOptions};
use vmc_dynamics::zoa::Zoa;
use vmc_dynamics::*;

fn benchmark_mode() -> Mode {
    Mode::from_mass(922.0, 0.011, 0.03993)
}

fn relative(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// Once-per-tooth rotation of a vibration at `f_hz`: the distance of f·τ to the nearest whole
/// number, in [0, ½] (aliases k/τ ± f share it).
fn rotation(f_hz: f64, period_s: f64) -> f64 {
    let x = (f_hz * period_s).fract();
    x.min(1.0 - x)
}

/// A helix of 0 gives the straight-tooth model bit for bit: values of semi-discretisation and
/// of both time-domain force models on a 3-tooth, 3-mode tool with edge forces and process
/// damping, recorded from the straight-tooth model, are reproduced to 1e-12 relative, the
/// semi-discretisation's to 2e-9: the critical multiplier of a non-normal monodromy matrix
/// amplifies rounding, and the order of the sums in its product (grouped free-flight steps,
/// blocked matrix products) moves it by up to 4e-10 here.
#[test]
fn helix_zero_reproduces_the_straight_tooth_results() {
    let mut tool = Tool::new(3, 16.0, 7e8, 2.1e8);
    tool.kte_n_per_m = 2e4;
    tool.kne_n_per_m = 1e4;
    tool.process_damping_n_per_m = 3e3;
    let modes = TipModes {
        x: vec![
            Mode::from_mass(700.0, 0.02, 0.05),
            Mode::from_mass(1500.0, 0.03, 0.08),
        ],
        y: vec![Mode::from_mass(820.0, 0.015, 0.06)],
    };
    let close = |a: f64, b: f64| assert!((a - b).abs() <= 1e-12 * b.abs(), "{a:e} vs {b:e}");
    let close_sdm = |a: f64, b: f64| assert!((a - b).abs() <= 2e-9 * b.abs(), "{a:e} vs {b:e}");
    #[allow(clippy::type_complexity)]
    let recorded: [(f64, Milling, f64, f64, f64, [f64; 2], f64); 2] = [
        (
            0.3,
            Milling::Up,
            1.097_955_892_016_256_7,
            1_509.196_955_848_098,
            73_429_766.457_764_31,
            [1.001_942_617_992_837_9e-5, -1.600_724_735_201_779_2e-5],
            1.370_396_993_369_904_9e-4,
        ),
        (
            0.05,
            Milling::Down,
            0.918_178_646_835_628_1,
            823.347_307_963_242_2,
            4.909_274_921_843_905_5e-8,
            [-2.942_309_987_323_032_6e-6, 2.335_449_124_168_728_1e-7],
            1.230_301_175_192_916_1e-5,
        ),
    ];
    for (imm, milling, rho, f_hz, growth, last, amp) in recorded {
        let sdm = MillingSdm::new(&tool, &modes, imm, milling, SdmOptions::default()).unwrap();
        let st = sdm.stability(9000.0, 0.35).unwrap();
        close_sdm(st.spectral_radius, rho);
        close_sdm(st.chatter_frequency_hz, f_hz);
        let td = TimeDomain::new(&tool, &modes, imm, milling, TimeOptions::default()).unwrap();
        close(td.growth_ratio(9000.0, 0.35).unwrap(), growth);
        let p = td
            .simulate(9000.0, 0.35, 0.08, ForceModel::Process)
            .unwrap();
        let end = p.displacement_m.last().unwrap();
        close(end[0], last[0]);
        close(end[1], last[1]);
        close(*p.amplitude_m.last().unwrap(), amp);
    }
}

/// At an axial depth of one helical pitch (k_β a_p = 2π/N) the teeth in cut sweep every angle
/// once, so the directional matrix is constant and equal to its mean A₀: the periodic delay
/// equation becomes the zero-order one, whose boundary ZOA gives exactly. The test makes the
/// ZOA critical depth equal to the pitch of a 30° two-tooth cutter (Ø20 mm, pitch 54.4 mm) by
/// stiffening the benchmark mode (modal mass scaled, same frequency and damping: the ZOA depth
/// scales with the stiffness) and checks that helical SDM (m = 80) finds the same boundary at
/// a_e/D = 0.05 down milling, where straight-tooth SDM finds flip lobes at about half that
/// depth: within 1.5 % in depth (observed 0.17–0.33 %; the first-order SDM error falls as m⁻²),
/// the same once-per-tooth rotation of the chatter to 0.005 cycles, and a Hopf boundary.
#[test]
fn at_one_axial_pitch_helical_sdm_meets_the_zero_order_solution() {
    let mut tool = Tool::new(2, 20.0, 6e8, 2e8);
    tool.helix_deg = 30.0;
    let pitch_mm = PI * tool.diameter_mm / (f64::from(tool.teeth) * 30f64.to_radians().tan());
    let (imm, milling) = (0.05, Milling::Down);
    for n in [7000.0, 10_000.0, 12_000.0] {
        let base = TipModes::x_only(vec![benchmark_mode()]);
        let a_base = Zoa::new(&tool, &base, imm, milling)
            .unwrap()
            .critical_depth(n)
            .unwrap()
            .unwrap()
            .critical_depth_mm;
        let scale = pitch_mm / a_base;
        let modes = TipModes::x_only(vec![Mode::from_mass(922.0, 0.011, 0.03993 * scale)]);
        let z = Zoa::new(&tool, &modes, imm, milling)
            .unwrap()
            .critical_depth(n)
            .unwrap()
            .unwrap();
        assert!(relative(z.critical_depth_mm, pitch_mm) < 1e-9, "{z:?}");
        let sdm = MillingSdm::new(
            &tool,
            &modes,
            imm,
            milling,
            SdmOptions {
                steps_per_period: 80,
            },
        )
        .unwrap();
        let at = sdm.at_speed(n).unwrap();
        let s = at
            .critical_depth(Some(pitch_mm), 3.0 * pitch_mm, 1e-4 * pitch_mm)
            .unwrap()
            .unwrap();
        let tau = tool.tooth_period_s(n);
        println!(
            "{n} rpm: helical SDM {:.4} mm vs ZOA {:.4} mm ({:+.2} %)",
            s.critical_depth_mm,
            z.critical_depth_mm,
            100.0 * (s.critical_depth_mm / z.critical_depth_mm - 1.0)
        );
        assert!(
            relative(s.critical_depth_mm, pitch_mm) < 0.015,
            "{n} rpm: SDM {s:?}, ZOA {z:?}"
        );
        assert_eq!(s.kind, BoundaryKind::Hopf, "{n} rpm");
        assert!(
            (rotation(s.chatter_frequency_hz, tau) - rotation(z.chatter_frequency_hz, tau)).abs()
                < 0.005,
            "{n} rpm: SDM {s:?}, ZOA {z:?}"
        );
        // Straight teeth on the same structure: a very different (flip or lower) boundary.
        let mut straight = tool;
        straight.helix_deg = 0.0;
        let s0 = MillingSdm::new(&straight, &modes, imm, milling, SdmOptions::default())
            .unwrap()
            .at_speed(n)
            .unwrap()
            .critical_depth(None, 3.0 * pitch_mm, 1e-3 * pitch_mm)
            .unwrap()
            .unwrap();
        assert!(
            relative(s0.critical_depth_mm, pitch_mm) > 0.05,
            "{n} rpm: straight {s0:?}"
        );
    }
}

/// Four teeth, 30° helix, Ø16 mm, the benchmark mode in x and y: 5 % under the helical SDM
/// boundary the linear time-domain vibration decays, 5 % over it grows, in down milling at
/// a_e/D = 0.05, up milling at 0.3 and slotting.
#[test]
fn helical_sdm_and_time_domain_agree() {
    let mut tool = Tool::new(4, 16.0, 6e8, 2e8);
    tool.helix_deg = 30.0;
    let modes = TipModes::symmetric(benchmark_mode());
    for (imm, milling, speeds) in [
        (0.05, Milling::Down, &[5000.0, 14_000.0][..]),
        (0.3, Milling::Up, &[8000.0, 11_000.0][..]),
        (1.0, Milling::Down, &[5000.0, 14_000.0][..]),
    ] {
        let sdm = MillingSdm::new(&tool, &modes, imm, milling, SdmOptions::default()).unwrap();
        let td = TimeDomain::new(&tool, &modes, imm, milling, TimeOptions::default()).unwrap();
        for &n in speeds {
            let p = sdm
                .at_speed(n)
                .unwrap()
                .critical_depth(None, 30.0, 1e-4)
                .unwrap()
                .unwrap();
            let under = td.growth_ratio(n, 0.95 * p.critical_depth_mm).unwrap();
            let over = td.growth_ratio(n, 1.05 * p.critical_depth_mm).unwrap();
            assert!(
                under < 1.0 && over > 1.0,
                "a_e/D {imm}, {n} rpm, {p:?}: {under} / {over}"
            );
        }
    }
}

/// The helix opens an unstable island: at a_e/D = 0.05 and 11 000 rpm the same 30° cutter is
/// unstable (flip) at 7.0–7.25 mm but stable at 6.5 and 7.5 mm, in both methods.
#[test]
fn a_helix_island_is_seen_by_both_methods() {
    let mut tool = Tool::new(4, 16.0, 6e8, 2e8);
    tool.helix_deg = 30.0;
    let modes = TipModes::symmetric(benchmark_mode());
    let sdm = MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
    let td = TimeDomain::new(&tool, &modes, 0.05, Milling::Down, TimeOptions::default()).unwrap();
    for (a, unstable) in [(6.5, false), (7.0, true), (7.25, true), (7.5, false)] {
        let st = sdm.stability(11_000.0, a).unwrap();
        let g = td.growth_ratio(11_000.0, a).unwrap();
        assert_eq!(!st.is_stable(), unstable, "SDM at {a} mm: {st:?}");
        assert_eq!(g > 1.0, unstable, "time domain at {a} mm: {g}");
        if unstable {
            assert_eq!(st.kind, BoundaryKind::Flip, "{a} mm");
        }
    }
    // The tracer of `lobes`, coming from 10 800 rpm, follows the Hopf boundary over the island
    // at 10 900 rpm; the scan of `sdm_lowest_critical_depth` finds the island's lower edge, and
    // the time domain confirms it (5 % under: decays, 5 % over: grows).
    let traced = lobes(
        Method::Sdm,
        &tool,
        &modes,
        0.05,
        Milling::Down,
        &[10_800.0, 10_900.0],
    )
    .unwrap();
    let lowest = sdm_lowest_critical_depth(&tool, &modes, 0.05, Milling::Down, 10_900.0)
        .unwrap()
        .unwrap();
    assert_eq!(lowest.kind, BoundaryKind::Flip);
    assert!(
        lowest.critical_depth_mm < 0.95 * traced[1].critical_depth_mm,
        "{lowest:?} vs {traced:?}"
    );
    assert!(
        td.growth_ratio(10_900.0, 0.95 * lowest.critical_depth_mm)
            .unwrap()
            < 1.0
    );
    assert!(
        td.growth_ratio(10_900.0, 1.05 * lowest.critical_depth_mm)
            .unwrap()
            > 1.0
    );
    // The same cutter with straight teeth has no boundary below 14 mm at this speed.
    let mut straight = tool;
    straight.helix_deg = 0.0;
    let s0 = MillingSdm::new(
        &straight,
        &modes,
        0.05,
        Milling::Down,
        SdmOptions::default(),
    )
    .unwrap();
    assert!(s0.stability(11_000.0, 7.0).unwrap().is_stable());
}

/// ZOA's mean directional matrix does not depend on the helix.
#[test]
fn the_zero_order_matrix_does_not_depend_on_the_helix() {
    let modes = TipModes::symmetric(benchmark_mode());
    let straight = Tool::new(3, 12.0, 6e8, 2e8);
    let mut helical = straight;
    helical.helix_deg = 45.0;
    let a = Zoa::new(&straight, &modes, 0.3, Milling::Up).unwrap();
    let b = Zoa::new(&helical, &modes, 0.3, Milling::Up).unwrap();
    assert_eq!(a.mean_directional_matrix(), b.mean_directional_matrix());
}
