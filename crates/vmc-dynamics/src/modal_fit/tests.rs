//! Fits of receptances synthesised from known modes with seeded noise.

use super::*;

/// SplitMix64: a small seeded generator for the test noise.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Standard normal (Box–Muller).
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

fn receptance(modes: &[Mode], f_hz: f64) -> Complex<f64> {
    modes
        .iter()
        .map(|m| {
            let r = f_hz / m.frequency_hz;
            Complex::new(1.0, 0.0)
                / (Complex::new(1.0 - r * r, 2.0 * m.damping_ratio * r) * m.stiffness_n_per_m)
        })
        .sum()
}

/// A receptance at every `step_hz` over [lo, hi] with complex noise of `relative` × |H| per
/// component plus a floor of `floor` × the peak.
fn synthesise(
    modes: &[Mode],
    (lo, hi, step_hz): (f64, f64, f64),
    (relative, floor): (f64, f64),
    seed: u64,
) -> (Vec<f64>, Vec<Complex<f64>>) {
    let mut rng = Rng(seed);
    let n = ((hi - lo) / step_hz).round() as usize + 1;
    let f: Vec<f64> = (0..n).map(|i| lo + step_hz * i as f64).collect();
    let clean: Vec<Complex<f64>> = f.iter().map(|&x| receptance(modes, x)).collect();
    let peak = clean.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let h = clean
        .iter()
        .map(|v| {
            let s = relative * v.norm() + floor * peak;
            v + Complex::new(s * rng.normal(), s * rng.normal())
        })
        .collect();
    (f, h)
}

fn check(fitted: &DirectionFit, truth: &[Mode], what: &str) {
    assert_eq!(
        fitted.modes.len(),
        truth.len(),
        "{what}: {:#?}",
        fitted.modes
    );
    for (got, want) in fitted.modes.iter().zip(truth) {
        let g = got.mode;
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        println!(
            "{what}: f {:.2} Hz ({:+.3} %), ζ {:.5} ({:+.2} %), k {:.4e} N/m ({:+.2} %), stable over {} orders",
            g.frequency_hz,
            100.0 * (g.frequency_hz / want.frequency_hz - 1.0),
            g.damping_ratio,
            100.0 * (g.damping_ratio / want.damping_ratio - 1.0),
            g.stiffness_n_per_m,
            100.0 * (g.stiffness_n_per_m / want.stiffness_n_per_m - 1.0),
            got.stable_orders
        );
        assert!(
            rel(g.frequency_hz, want.frequency_hz) < 0.005,
            "{what}: {g:?} vs {want:?}"
        );
        assert!(
            rel(g.damping_ratio, want.damping_ratio) < 0.10,
            "{what}: {g:?} vs {want:?}"
        );
        assert!(
            rel(g.stiffness_n_per_m, want.stiffness_n_per_m) < 0.05,
            "{what}: {g:?} vs {want:?}"
        );
        assert!((got.modal_mass_kg - g.modal_mass_kg()).abs() < 1e-12 * got.modal_mass_kg);
    }
}

fn three_modes() -> Vec<Mode> {
    vec![
        Mode {
            frequency_hz: 640.0,
            damping_ratio: 0.03,
            stiffness_n_per_m: 1.0e7,
        },
        Mode {
            frequency_hz: 1150.0,
            damping_ratio: 0.015,
            stiffness_n_per_m: 2.0e7,
        },
        Mode {
            frequency_hz: 2600.0,
            damping_ratio: 0.02,
            stiffness_n_per_m: 6.0e7,
        },
    ]
}

fn two_modes() -> Vec<Mode> {
    vec![
        Mode {
            frequency_hz: 700.0,
            damping_ratio: 0.025,
            stiffness_n_per_m: 1.5e7,
        },
        Mode {
            frequency_hz: 1900.0,
            damping_ratio: 0.012,
            stiffness_n_per_m: 4.0e7,
        },
    ]
}

#[test]
fn three_and_two_mode_receptances_with_noise_give_back_their_modes() {
    for seed in [1, 2, 3] {
        let grid = (100.0, 4000.0, 2.0);
        let (f, h) = synthesise(&three_modes(), grid, (0.01, 0.002), seed);
        let fitted = fit_direction(&f, &h, &FitOptions::default(), 'x').unwrap();
        check(&fitted, &three_modes(), &format!("3 modes, seed {seed}"));
        let (f, h) = synthesise(&two_modes(), grid, (0.01, 0.002), 100 + seed);
        let fitted = fit_direction(&f, &h, &FitOptions::default(), 'y').unwrap();
        check(&fitted, &two_modes(), &format!("2 modes, seed {seed}"));
    }
}

#[test]
fn a_fit_from_a_file_gives_the_tip_modes_of_a_tool_file() {
    let grid = (100.0, 4000.0, 2.0);
    let (f, hx) = synthesise(&three_modes(), grid, (0.01, 0.002), 7);
    let (_, hy) = synthesise(&two_modes(), grid, (0.01, 0.002), 8);
    let mut text =
        String::from("frequency_hz,x_re_m_per_n,x_im_m_per_n,y_re_m_per_n,y_im_m_per_n\n");
    for ((fk, x), y) in f.iter().zip(&hx).zip(&hy) {
        text.push_str(&format!(
            "{fk},{:e},{:e},{:e},{:e}\n",
            x.re, x.im, y.re, y.im
        ));
    }
    let frf = Frf::parse(&text).unwrap();
    let fitted = fit(&frf, &FitOptions::default()).unwrap();
    check(fitted.x.as_ref().unwrap(), &three_modes(), "file x");
    check(fitted.y.as_ref().unwrap(), &two_modes(), "file y");
    let tip = fitted.tip_modes();
    assert_eq!((tip.x.len(), tip.y.len()), (3, 2));
    assert!(tip.validate().is_ok());
}

#[test]
fn bad_options_and_degenerate_data_are_refused() {
    let (f, h) = synthesise(&two_modes(), (100.0, 4000.0, 2.0), (0.0, 0.0), 1);
    let odd = FitOptions {
        max_order: 41,
        ..FitOptions::default()
    };
    assert_eq!(
        fit_direction(&f, &h, &odd, 'x').unwrap_err().to_string(),
        "max_order must be even and >= 4, got 41"
    );
    let tol = FitOptions {
        damping_tol: 0.0,
        ..FitOptions::default()
    };
    assert!(fit_direction(&f, &h, &tol, 'x').is_err());
    let zero = vec![Complex::new(0.0, 0.0); f.len()];
    assert_eq!(
        fit_direction(&f, &zero, &FitOptions::default(), 'y').unwrap_err(),
        FitError::ZeroReceptance { direction: 'y' }
    );
    assert_eq!(
        fit_direction(&f[..30], &h[..30], &FitOptions::default(), 'x')
            .unwrap_err()
            .to_string(),
        "direction x: 30 rows are too few for model order 40 (need at least 41)"
    );
}

/// The 1-DOF benchmark's mode (922 Hz, ζ = 0.011, 0.03993 kg) measured in x only, 200–2000 Hz
/// every 1 Hz with 1 % noise: one mode in x, y rigid, modal mass within 5 %.
#[test]
fn the_benchmark_mode_measured_in_x_only_gives_a_rigid_y() {
    let truth = [Mode::from_mass(922.0, 0.011, 0.03993)];
    let (f, h) = synthesise(&truth, (200.0, 2000.0, 1.0), (0.01, 0.002), 11);
    let mut text = String::from("# x only\nfrequency_hz,x_re_m_per_n,x_im_m_per_n\n");
    for (fk, v) in f.iter().zip(&h) {
        text.push_str(&format!("{fk},{:e},{:e}\n", v.re, v.im));
    }
    let fitted = fit(&Frf::parse(&text).unwrap(), &FitOptions::default()).unwrap();
    assert!(fitted.y.is_none());
    let x = fitted.x.as_ref().unwrap();
    check(x, &truth, "benchmark");
    assert!((x.modes[0].modal_mass_kg / 0.03993 - 1.0).abs() < 0.05);
    let tip = fitted.tip_modes();
    assert!(tip.y.is_empty() && tip.x.len() == 1);
}
