//! `modal-fit` on the real binary: an FRF synthesised here from known modes with seeded noise
//! gives back the modes (frequency within 0.5 %, damping ratio within 10 %, stiffness within
//! 5 %) in a tool file that `lobes` takes; the cutter comes from the template; an existing
//! file is kept without `--force`; bad FRF files are refused in one line naming the file and
//! the line.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::{ok, refused, repo_file, vmc, TempDir};

/// (frequency_hz, damping_ratio, stiffness_n_per_m) of the synthesised tip.
type Mode = (f64, f64, f64);

/// Three modes in x, two in y: a spindle-holder mode, a holder mode and a tool-bending mode.
const X: [Mode; 3] = [
    (560.0, 0.028, 1.2e7),
    (1320.0, 0.017, 2.6e7),
    (2900.0, 0.013, 5.5e7),
];
const Y: [Mode; 2] = [(590.0, 0.032, 1.4e7), (2750.0, 0.018, 4.0e7)];

/// SplitMix64: a small seeded generator, so the noise is the same on every machine.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1].
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 1.0) / (1u64 << 53) as f64
    }

    /// Standard normal (Box–Muller).
    fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
}

/// Receptance (re, im) in m/N of `modes` at `f_hz` (mode shape 1 at the tip).
fn receptance(modes: &[Mode], f_hz: f64) -> (f64, f64) {
    modes
        .iter()
        .fold((0.0, 0.0), |(re, im), &(fn_hz, zeta, k)| {
            let r = f_hz / fn_hz;
            let (a, b) = (k * (1.0 - r * r), k * 2.0 * zeta * r);
            let d = a * a + b * b;
            (re + a / d, im - b / d)
        })
}

/// The FRF file of `X` and `Y` from 100 to 4000 Hz every 2 Hz, with complex Gaussian noise of
/// 1 % of |H| per component plus 0.2 % of the direction's peak, drawn from `seed`.
fn synthetic_frf(seed: u64) -> String {
    let freqs: Vec<f64> = (0..1951).map(|i| 100.0 + 2.0 * i as f64).collect();
    let peak = |modes: &[Mode]| {
        freqs
            .iter()
            .map(|&f| {
                let (re, im) = receptance(modes, f);
                re.hypot(im)
            })
            .fold(0.0, f64::max)
    };
    let (px, py) = (peak(&X), peak(&Y));
    let mut rng = SplitMix64(seed);
    let mut s = String::from(
        "# synthetic\nfrequency_hz,x_re_m_per_n,x_im_m_per_n,y_re_m_per_n,y_im_m_per_n\n",
    );
    for &f in &freqs {
        s.push_str(&format!("{f}"));
        for (modes, p) in [(&X[..], px), (&Y[..], py)] {
            let (re, im) = receptance(modes, f);
            let sigma = 0.01 * re.hypot(im) + 0.002 * p;
            let (nr, ni) = (sigma * rng.normal(), sigma * rng.normal());
            s.push_str(&format!(",{:e},{:e}", re + nr, im + ni));
        }
        s.push('\n');
    }
    s
}

/// The modes of one direction in a tool file, as (f, ζ, k), in the file's order.
fn modes_of(toml_text: &str, direction: &str) -> Vec<Mode> {
    let value: toml::Value = toml::from_str(toml_text).expect("the tool file is TOML");
    value["modes"][direction]
        .as_array()
        .map(|list| {
            list.iter()
                .map(|m| {
                    let get = |k: &str| m[k].as_float().unwrap_or_else(|| panic!("{k} in {m}"));
                    (
                        get("frequency_hz"),
                        get("damping_ratio"),
                        get("stiffness_n_per_m"),
                    )
                })
                .collect()
        })
        .unwrap_or_default()
}

fn assert_modes(got: &[Mode], want: &[Mode], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: {got:?}");
    for (g, w) in got.iter().zip(want) {
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        assert!(rel(g.0, w.0) < 0.005, "{what}: frequency {g:?} vs {w:?}");
        assert!(rel(g.1, w.1) < 0.10, "{what}: damping ratio {g:?} vs {w:?}");
        assert!(rel(g.2, w.2) < 0.05, "{what}: stiffness {g:?} vs {w:?}");
    }
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

#[test]
fn the_fit_of_a_synthetic_frf_gives_back_its_modes_in_a_tool_file_that_lobes_takes() {
    let tmp = TempDir::new("modalfit");
    let dir = tmp.path();
    for seed in [11, 12] {
        let frf = format!("frf{seed}.csv");
        write(dir, &frf, &synthetic_frf(seed));
        let toml_name = format!("fit{seed}.toml");
        let out = ok(
            &vmc(dir, &["modal-fit", &frf, "-o", &toml_name]),
            "modal-fit",
        );
        assert!(out.contains("direction x: 3 mode(s)"), "{out}");
        assert!(out.contains("direction y: 2 mode(s)"), "{out}");
        assert!(out.contains("stable_orders"), "{out}");
        assert!(out.ends_with(&format!("wrote {toml_name}\n")), "{out}");
        let text = std::fs::read_to_string(dir.join(&toml_name)).unwrap();
        assert_modes(&modes_of(&text, "x"), &X, &format!("seed {seed}, x"));
        assert_modes(&modes_of(&text, "y"), &Y, &format!("seed {seed}, y"));
    }
    // The cutter is the template's: by default the benchmark's 2 teeth; with --tool the file's.
    let text = std::fs::read_to_string(dir.join("fit11.toml")).unwrap();
    let value: toml::Value = toml::from_str(&text).unwrap();
    assert_eq!(value["tool"]["teeth"].as_integer(), Some(2), "{text}");
    let helical = repo_file("machines/benchmarks/helical-4flute-30deg.toml");
    let args = [
        "modal-fit",
        "frf11.csv",
        "--tool",
        helical.to_str().unwrap(),
        "--name",
        "my cutter",
        "-o",
        "helical.toml",
    ];
    ok(&vmc(dir, &args), "modal-fit --tool");
    let value: toml::Value =
        toml::from_str(&std::fs::read_to_string(dir.join("helical.toml")).unwrap()).unwrap();
    assert_eq!(value["tool"]["teeth"].as_integer(), Some(4));
    assert_eq!(value["tool"]["helix_deg"].as_float(), Some(30.0));
    assert_eq!(value["name"].as_str(), Some("my cutter"));
    // `lobes` reads the written file and traces its lobes (converged resolution).
    let lobes = [
        "lobes",
        "--tool",
        "fit11.toml",
        "--immersion",
        "0.1",
        "--rpm",
        "8000,16000",
        "--out",
        "l.csv",
    ];
    let out = ok(&vmc(dir, &lobes), "lobes --tool fit11.toml");
    assert!(out.contains("minimum critical depth"), "{out}");
    assert!(out.contains("resolution: converged"), "{out}");
    let csv = std::fs::read_to_string(dir.join("l.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
}

#[test]
fn an_existing_tool_file_is_kept_without_force() {
    let tmp = TempDir::new("modalfit-force");
    let dir = tmp.path();
    write(dir, "frf.csv", &synthetic_frf(3));
    write(dir, "fit.toml", "keep me");
    let e = refused(
        &vmc(dir, &["modal-fit", "frf.csv", "-o", "fit.toml"]),
        "no --force",
    );
    assert!(e.contains("fit.toml: already exists (pass --force"), "{e}");
    assert_eq!(
        std::fs::read_to_string(dir.join("fit.toml")).unwrap(),
        "keep me"
    );
    let args = ["modal-fit", "frf.csv", "-o", "fit.toml", "--force"];
    ok(&vmc(dir, &args), "--force");
    assert!(std::fs::read_to_string(dir.join("fit.toml"))
        .unwrap()
        .contains("[[modes.x]]"));
}

#[test]
fn bad_frf_files_are_refused_in_one_line_with_the_file_and_the_line() {
    let tmp = TempDir::new("modalfit-bad");
    let dir = tmp.path();
    let good = synthetic_frf(5);
    let lines: Vec<&str> = good.lines().collect();
    // Line 1 is the comment, line 2 the header, line 3 the first row.
    let with_line = |n: usize, text: &str| {
        let mut l = lines.clone();
        l[n - 1] = text;
        l.join("\n")
    };
    let cases = [
        (
            "back.csv",
            with_line(10, lines[8]),
            "back.csv: line 10: frequency 112 Hz is not above the 112 Hz of line 9",
        ),
        (
            "nan.csv",
            with_line(7, "110,NaN,-1e-7,1e-8,-1e-8"),
            "nan.csv: line 7: `x_re_m_per_n` is not finite (NaN)",
        ),
        (
            "half.csv",
            good.replacen(",y_im_m_per_n", ",y_imag", 1),
            "half.csv: line 2: unknown column `y_imag`",
        ),
        (
            "half2.csv",
            lines
                .iter()
                .map(|l| l.rsplit_once(',').map_or(*l, |(a, _)| a))
                .collect::<Vec<_>>()
                .join("\n"),
            "half2.csv: line 2: direction y has `y_re_m_per_n` but no `y_im_m_per_n` column",
        ),
    ];
    for (name, text, want) in &cases {
        write(dir, name, text);
        let e = refused(&vmc(dir, &["modal-fit", name, "-o", "x.toml"]), name);
        assert!(e.starts_with(&format!("vmc-twin: error: {want}")), "{e}");
        assert!(!dir.join("x.toml").exists());
    }
    let e = refused(&vmc(dir, &["modal-fit", "missing.csv"]), "missing");
    assert!(e.contains("missing.csv"), "{e}");
}
