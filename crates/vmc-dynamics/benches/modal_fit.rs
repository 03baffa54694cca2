//! Modal fit of a two-direction receptance: 1951 frequencies (100–4000 Hz every 2 Hz), three
//! modes in x (640, 1150, 2600 Hz) and two in y (700, 1900 Hz), with a deterministic ripple of
//! 1 % standing in for noise; stabilisation diagram up to order 40 (20 LSCF fits per
//! direction), then the real-mode constants.
//!
//! Figures (`nice cargo bench -p vmc-dynamics --bench modal_fit`, the 2-core machine shared
//! with other builds, load average ≈ 5): `fit_two_directions` 0.53 s.

use criterion::{criterion_group, criterion_main, Criterion};
use vmc_dynamics::modal_fit::{fit, FitOptions, Frf};
use vmc_dynamics::Mode;

fn receptance(modes: &[Mode], f_hz: f64) -> (f64, f64) {
    let (mut re, mut im) = (0.0, 0.0);
    for m in modes {
        let r = f_hz / m.frequency_hz;
        let (a, b) = (1.0 - r * r, 2.0 * m.damping_ratio * r);
        let d = (a * a + b * b) * m.stiffness_n_per_m;
        re += a / d;
        im -= b / d;
    }
    (re, im)
}

fn bench(c: &mut Criterion) {
    let mode = |f, z, k| Mode {
        frequency_hz: f,
        damping_ratio: z,
        stiffness_n_per_m: k,
    };
    let x = [
        mode(640.0, 0.03, 1.0e7),
        mode(1150.0, 0.015, 2.0e7),
        mode(2600.0, 0.02, 6.0e7),
    ];
    let y = [mode(700.0, 0.025, 1.5e7), mode(1900.0, 0.012, 4.0e7)];
    let mut text =
        String::from("frequency_hz,x_re_m_per_n,x_im_m_per_n,y_re_m_per_n,y_im_m_per_n\n");
    for i in 0..1951 {
        let f = 100.0 + 2.0 * f64::from(i);
        let ripple = 1.0 + 0.01 * (0.37 * f64::from(i)).sin();
        let (xr, xi) = receptance(&x, f);
        let (yr, yi) = receptance(&y, f);
        text.push_str(&format!(
            "{f},{:e},{:e},{:e},{:e}\n",
            xr * ripple,
            xi * ripple,
            yr * ripple,
            yi * ripple
        ));
    }
    let frf = Frf::parse(&text).expect("valid FRF");
    let mut g = c.benchmark_group("modal_fit");
    g.sample_size(10);
    g.bench_function("fit_two_directions", |b| {
        b.iter(|| fit(&frf, &FitOptions::default()).expect("fit"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
