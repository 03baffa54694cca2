//! Cross-checks of the three stability methods on the Insperger–Stépán benchmark
//! (N = 2, K_t = 6e8 N/m², K_n = 2e8 N/m², f_n = 922 Hz, ζ = 0.011, m = 0.03993 kg).

use vmc_dynamics::milling::{MillingSdm, SdmOptions};
use vmc_dynamics::time_domain::{ForceModel, TimeDomain, TimeOptions};
use vmc_dynamics::zoa::Zoa;
use vmc_dynamics::*;

fn benchmark_tool() -> Tool {
    Tool::new(2, 20.0, 6e8, 2e8)
}

fn benchmark_mode() -> Mode {
    Mode::from_mass(922.0, 0.011, 0.03993)
}

/// The SDM boundary at `rpm`, searched up to 20 mm to 1e-4 mm.
fn limit_at(sdm: &MillingSdm, rpm: f64) -> LobePoint {
    limit_below(sdm, rpm, 20.0)
}

/// The SDM boundary at `rpm`, searched up to `max_mm` to 1e-4 mm.
fn limit_below(sdm: &MillingSdm, rpm: f64, max_mm: f64) -> LobePoint {
    sdm.at_speed(rpm)
        .unwrap()
        .critical_depth(None, max_mm, 1e-4)
        .unwrap()
        .unwrap()
}

fn benchmark_modes() -> TipModes {
    TipModes::x_only(vec![benchmark_mode()])
}

/// 5 % under the SDM boundary the linear time-domain vibration decays, 5 % over it grows, at
/// Hopf and flip speeds of the a_e/D = 0.05 down-milling benchmark.
#[test]
fn sdm_and_time_domain_agree_on_benchmark() {
    let (tool, modes) = (benchmark_tool(), benchmark_modes());
    let sdm = MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
    let td = TimeDomain::new(&tool, &modes, 0.05, Milling::Down, TimeOptions::default()).unwrap();
    for n in [6000.0, 9000.0, 10000.0, 12000.0, 14500.0] {
        let p = limit_below(&sdm, n, 20.0);
        let under = td.growth_ratio(n, 0.95 * p.critical_depth_mm).unwrap();
        let over = td.growth_ratio(n, 1.05 * p.critical_depth_mm).unwrap();
        assert!(
            under < 1.0 && over > 1.0,
            "{n} rpm, a = {} mm: {under} / {over}",
            p.critical_depth_mm
        );
    }
}

/// With N = 4 in slotting the teeth in cut sum to a constant directional matrix, so the
/// zero-order solution is exact and SDM must agree up to its discretisation error: within
/// 1 % in depth and frequency at every speed from 3000 to 8000 rpm (all Hopf) with m = 80
/// (observed worst 0.6 %; m = 40 gives 2.2 % at 3000 rpm, m = 160 0.2 %). With N = 2 the periodic
/// terms do not cancel and the methods differ (≈ 10 % at the lobe bottoms, up to 2× at flip lobes).
#[test]
fn sdm_and_zoa_agree_in_slotting() {
    let tool = Tool::new(4, 20.0, 6e8, 2e8);
    let modes = TipModes::symmetric(benchmark_mode());
    let sdm = MillingSdm::new(
        &tool,
        &modes,
        1.0,
        Milling::Down,
        SdmOptions {
            steps_per_period: 80,
        },
    )
    .unwrap();
    let zoa = Zoa::new(&tool, &modes, 1.0, Milling::Down).unwrap();
    let mut worst: f64 = 0.0;
    for i in 0..11 {
        let n = 3000.0 + 500.0 * f64::from(i);
        let s = sdm
            .at_speed(n)
            .unwrap()
            .critical_depth(None, 1.0, 1e-6)
            .unwrap()
            .unwrap();
        let z = zoa.critical_depth(n).unwrap().unwrap();
        assert_eq!(s.kind, BoundaryKind::Hopf, "{n}");
        worst = worst.max((s.critical_depth_mm / z.critical_depth_mm - 1.0).abs());
        assert!(
            (s.chatter_frequency_hz / z.chatter_frequency_hz - 1.0).abs() < 0.01,
            "{n}: {s:?} {z:?}"
        );
    }
    println!("SDM–ZOA worst relative difference: {worst}");
    assert!(worst < 0.01, "worst relative difference {worst}");
}

/// At a_e/D = 0.05 (down milling) SDM finds a period-doubling (flip) lobe at 10 000 rpm; ZOA,
/// which averages the force, reports only Hopf and a depth about twice as large there.
#[test]
fn flip_lobe_at_low_immersion() {
    let (tool, modes) = (benchmark_tool(), benchmark_modes());
    let sdm = MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
    let s = sdm
        .at_speed(10_000.0)
        .unwrap()
        .critical_depth(None, 20.0, 1e-4)
        .unwrap()
        .unwrap();
    assert_eq!(s.kind, BoundaryKind::Flip);
    // Period doubling: chatter at half the tooth-passing frequency plus its harmonics.
    let tooth_hz = 10_000.0 * 2.0 / 60.0;
    let k = s.chatter_frequency_hz / tooth_hz - 0.5;
    assert!((k - k.round()).abs() < 1e-6, "{}", s.chatter_frequency_hz);
    let z = Zoa::new(&tool, &modes, 0.05, Milling::Down)
        .unwrap()
        .critical_depth(10_000.0)
        .unwrap()
        .unwrap();
    assert_eq!(z.kind, BoundaryKind::Hopf);
    assert!(z.critical_depth_mm > 1.5 * s.critical_depth_mm);
}

/// The boundary tracer needs ≥ 10× fewer stability evaluations than the 201 × 100 grid and
/// stays within 1 % of the depth range (one grid cell) of the grid's boundary: of the first
/// stable→unstable switch of each speed's depth column where that column is monotone, and of
/// one of its switches where a thin unstable island (flip lobe) lies under a stable band.
#[test]
fn tracer_matches_grid_with_ten_times_fewer_evaluations() {
    let (tool, modes) = (benchmark_tool(), benchmark_modes());
    // 5000–13000 rpm: the boundary stays under 15 mm (the Hopf lobe peak near 13 700 rpm does not).
    let speeds: Vec<f64> = (0..201).map(|i| 5000.0 + 40.0 * f64::from(i)).collect();
    let max_mm = 15.0;
    let depths: Vec<f64> = (1..=100).map(|j| max_mm * f64::from(j) / 100.0).collect();
    let grid_sdm =
        MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
    let radii = grid_sdm.grid(&speeds, &depths).unwrap();
    let tracer_sdm =
        MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
    let traced = tracer_sdm.trace(&speeds, max_mm, 0.03).unwrap();
    assert_eq!(grid_sdm.evaluations(), 201 * 100);
    assert!(
        tracer_sdm.evaluations() * 10 <= grid_sdm.evaluations(),
        "tracer {} vs grid {}",
        tracer_sdm.evaluations(),
        grid_sdm.evaluations()
    );
    let missing: Vec<f64> = speeds
        .iter()
        .filter(|n| !traced.iter().any(|p| p.spindle_rpm == **n))
        .cloned()
        .collect();
    assert!(missing.is_empty(), "no boundary at {missing:?}");
    let mut islands = 0;
    for (column, p) in radii.iter().zip(&traced) {
        // Depths (cell midpoints) where the column switches from stable to unstable.
        let mut switches = Vec::new();
        let mut prev_stable = true;
        for (j, rho) in column.iter().enumerate() {
            let stable = *rho < 1.0;
            if prev_stable && !stable {
                switches.push(max_mm * (j as f64 + 0.5) / 100.0);
            }
            prev_stable = stable;
        }
        let near = |a: f64| (p.critical_depth_mm - a).abs() <= 0.01 * max_mm;
        if switches.len() > 1 && !near(switches[0]) {
            islands += 1;
            assert!(
                switches.iter().any(|a| near(*a)),
                "{} rpm: {p:?} vs {switches:?}",
                p.spindle_rpm
            );
        } else {
            assert!(
                near(switches[0]),
                "{} rpm: {p:?} vs {switches:?}",
                p.spindle_rpm
            );
        }
    }
    println!(
        "tracer {} / grid {} evaluations; {islands} of 201 speeds follow a higher switch over an island",
        tracer_sdm.evaluations(),
        grid_sdm.evaluations()
    );
    assert!(islands <= 5);
}

/// The lobes API returns points for every method, and repeated calls are bit-identical; SDM
/// (converged resolution) and the time domain (64 RK4 steps per tooth) agree to 3 % at
/// a_e/D = 0.5 up milling.
#[test]
fn lobes_api_and_determinism() {
    let (tool, modes) = (benchmark_tool(), benchmark_modes());
    let speeds = [9000.0, 12000.0, 15000.0];
    for method in [Method::Sdm, Method::Zoa, Method::Time] {
        let a = lobes(method, &tool, &modes, 0.5, Milling::Up, &speeds).unwrap();
        let b = lobes(method, &tool, &modes, 0.5, Milling::Up, &speeds).unwrap();
        assert_eq!(a.len(), 3, "{method:?}");
        assert_eq!(a, b, "{method:?}");
        assert!(a
            .iter()
            .all(|p| p.critical_depth_mm > 0.0 && p.critical_depth_mm.is_finite()));
    }
    let sdm = lobes(Method::Sdm, &tool, &modes, 0.5, Milling::Up, &speeds).unwrap();
    let time = lobes(Method::Time, &tool, &modes, 0.5, Milling::Up, &speeds).unwrap();
    for (s, t) in sdm.iter().zip(&time) {
        assert!(
            (s.critical_depth_mm / t.critical_depth_mm - 1.0).abs() < 0.03,
            "{s:?} {t:?}"
        );
    }
}

/// Process damping (force against the normal penetration rate, ∝ 1/v_c) raises the limit,
/// most at low speed.
#[test]
fn process_damping_stabilises() {
    let mut tool = benchmark_tool();
    let modes = benchmark_modes();
    let base = MillingSdm::new(&tool, &modes, 0.5, Milling::Down, SdmOptions::default()).unwrap();
    tool.process_damping_n_per_m = 1e5;
    let damped = MillingSdm::new(&tool, &modes, 0.5, Milling::Down, SdmOptions::default()).unwrap();
    let a0 = limit_at(&base, 3000.0);
    let a1 = limit_at(&damped, 3000.0);
    assert!(
        a1.critical_depth_mm > 1.05 * a0.critical_depth_mm,
        "{a0:?} {a1:?}"
    );
}

/// The process model (feed, loss of contact) stays bounded under the limit and settles to the
/// forced tooth-periodic response: once-per-tooth displacement samples converge.
#[test]
fn process_simulation_settles_when_stable() {
    let (mut tool, modes) = (benchmark_tool(), benchmark_modes());
    tool.kte_n_per_m = 2e4;
    tool.kne_n_per_m = 1e4;
    let td = TimeDomain::new(&tool, &modes, 0.5, Milling::Down, TimeOptions::default()).unwrap();
    let sdm = MillingSdm::new(&tool, &modes, 0.5, Milling::Down, SdmOptions::default()).unwrap();
    let limit = limit_at(&sdm, 9000.0);
    let sim = td
        .simulate(
            9000.0,
            0.5 * limit.critical_depth_mm,
            0.1,
            ForceModel::Process,
        )
        .unwrap();
    let d = &sim.displacement_m;
    let last = d[d.len() - 1];
    let prev = d[d.len() - 2];
    assert!(last[0].abs() > 1e-7 && last[0].abs() < 1e-3, "{last:?}");
    assert!(
        (last[0] - prev[0]).abs() < 1e-3 * last[0].abs(),
        "{limit:?} {last:?} {prev:?}"
    );
    assert_eq!(sim.steps, 400 * 64);
}

/// Convergence in m on the milling benchmark (a_e/D = 0.5 up milling, 6000 rpm, 0.2 mm):
/// |ρ_m − ρ_320| = 3.9e-2, 1.0e-2, 2.4e-3 for m = 20, 40, 80: orders 1.94 and 2.05.
#[test]
fn milling_sdm_converges_second_order() {
    let (tool, modes) = (benchmark_tool(), benchmark_modes());
    let rho = |m: usize| {
        let sdm = MillingSdm::new(
            &tool,
            &modes,
            0.5,
            Milling::Up,
            SdmOptions {
                steps_per_period: m,
            },
        )
        .unwrap();
        sdm.stability(6000.0, 0.2).unwrap().spectral_radius
    };
    let reference = rho(320);
    let errs: Vec<f64> = [20, 40, 80]
        .iter()
        .map(|&m| (rho(m) - reference).abs())
        .collect();
    let orders: Vec<f64> = errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    println!("milling |ρ_m − ρ_320| for m = 20, 40, 80: {errs:?}, orders {orders:?}");
    assert!(
        orders.iter().all(|o| (1.7..2.4).contains(o)),
        "{errs:?} {orders:?}"
    );
}

/// Several modes per direction (the first two modes of a steel cantilever, L = 100 mm,
/// D = 12 mm, ζ = 2 %, in x and y), N = 3, a_e/D = 0.3 up milling: 5 % under the SDM boundary
/// the time-domain vibration decays, 5 % over it grows.
#[test]
fn multi_mode_cantilever_sdm_and_time_domain_agree() {
    let beam = vmc_dynamics::beam::Cantilever {
        youngs_modulus_pa: 210e9,
        density_kg_per_m3: 7850.0,
        length_mm: 100.0,
        outer_diameter_mm: 12.0,
        inner_diameter_mm: 0.0,
    };
    let m = beam.modes(2, 0.02).unwrap();
    let modes = TipModes { x: m.clone(), y: m };
    let tool = Tool::new(3, 12.0, 6e8, 2e8);
    let sdm = MillingSdm::new(
        &tool,
        &modes,
        0.3,
        Milling::Up,
        SdmOptions {
            steps_per_period: 60,
        },
    )
    .unwrap();
    let opts = TimeOptions {
        steps_per_tooth: 128,
        ..TimeOptions::default()
    };
    let td = TimeDomain::new(&tool, &modes, 0.3, Milling::Up, opts).unwrap();
    for n in [9000.0, 14000.0] {
        let p = limit_below(&sdm, n, 50.0);
        let under = td.growth_ratio(n, 0.95 * p.critical_depth_mm).unwrap();
        let over = td.growth_ratio(n, 1.05 * p.critical_depth_mm).unwrap();
        assert!(
            under < 1.0 && over > 1.0,
            "{n} rpm, {p:?}: {under} / {over}"
        );
    }
}

/// Repeated computations are bit-identical: SDM monodromy and radii, time-domain samples.
#[test]
fn determinism() {
    let (tool, modes) = (benchmark_tool(), benchmark_modes());
    let sdm = MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
    let s = sdm.at_speed(9000.0).unwrap();
    assert_eq!(s.monodromy(2.0), s.monodromy(2.0));
    let speeds = [6000.0, 9000.0];
    let depths = [1.0, 2.0, 4.0];
    assert_eq!(
        sdm.grid(&speeds, &depths).unwrap(),
        sdm.grid(&speeds, &depths).unwrap()
    );
    let td = TimeDomain::new(&tool, &modes, 0.05, Milling::Down, TimeOptions::default()).unwrap();
    let a = td.simulate(9000.0, 2.0, 0.1, ForceModel::Process).unwrap();
    let b = td.simulate(9000.0, 2.0, 0.1, ForceModel::Process).unwrap();
    assert_eq!(a, b);
}

/// The time-domain boundary also yields the chatter frequency (spectral peak) and the kind:
/// at 9000 rpm (Hopf) and 10 000 rpm (flip) on the a_e/D = 0.05 benchmark they match SDM,
/// frequencies within 1 %.
#[test]
fn time_domain_frequency_and_kind_match_sdm() {
    let (tool, modes) = (benchmark_tool(), benchmark_modes());
    let sdm = MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
    let td = TimeDomain::new(&tool, &modes, 0.05, Milling::Down, TimeOptions::default()).unwrap();
    for (n, kind) in [(9000.0, BoundaryKind::Hopf), (10_000.0, BoundaryKind::Flip)] {
        let s = sdm
            .at_speed(n)
            .unwrap()
            .critical_depth(None, 20.0, 1e-3)
            .unwrap()
            .unwrap();
        let t = td.critical_depth(n, 20.0, 1e-2).unwrap().unwrap();
        assert_eq!((s.kind, t.kind), (kind, kind), "{n}: {s:?} {t:?}");
        assert!(
            (t.chatter_frequency_hz / s.chatter_frequency_hz - 1.0).abs() < 0.01,
            "{n}: {s:?} {t:?}"
        );
        assert!(
            (t.critical_depth_mm / s.critical_depth_mm - 1.0).abs() < 0.05,
            "{n}: {s:?} {t:?}"
        );
    }
}

/// The critical depth by ITP (the tracer's refinement) lies within the tolerance of the one
/// plain bisection of the same bracket finds, at Hopf and flip speeds, in fewer stability
/// evaluations over the whole set (bisection needs ⌈log₂(20 mm / 1e-4 mm)⌉ = 18 per speed).
#[test]
fn itp_refinement_matches_bisection_in_fewer_evaluations() {
    let (tool, modes) = (benchmark_tool(), benchmark_modes());
    let sdm = MillingSdm::new(&tool, &modes, 0.05, Milling::Down, SdmOptions::default()).unwrap();
    let (max_mm, tol) = (20.0, 1e-4);
    let (mut bisection_evaluations, mut itp_evaluations) = (0, 0);
    for n in [6000.0, 9000.0, 10000.0, 12000.0, 14500.0] {
        let s = sdm.at_speed(n).unwrap();
        let (mut lo, mut hi) = (0.0, max_mm);
        assert!(!s.stability(hi).unwrap().is_stable());
        while hi - lo > tol {
            let mid = 0.5 * (lo + hi);
            bisection_evaluations += 1;
            if s.stability(mid).unwrap().is_stable() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let before = sdm.evaluations();
        let p = s.critical_depth(None, max_mm, tol).unwrap().unwrap();
        let itp = sdm.evaluations() - before;
        assert!(
            (p.critical_depth_mm - 0.5 * (lo + hi)).abs() <= tol,
            "{n} rpm: ITP {} vs bisection {}",
            p.critical_depth_mm,
            0.5 * (lo + hi)
        );
        // Its worst case: the first evaluation at the maximum, bisection's count plus one.
        assert!(itp <= 1 + 18 + 1, "{n} rpm: {itp} evaluations");
        itp_evaluations += itp;
    }
    println!("evaluations for 5 speeds: ITP {itp_evaluations}, bisection {bisection_evaluations}");
    assert!(
        itp_evaluations < bisection_evaluations,
        "ITP {itp_evaluations} vs bisection {bisection_evaluations}"
    );
}
