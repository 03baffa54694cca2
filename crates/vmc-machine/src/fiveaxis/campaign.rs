//! The probing campaign: which configurations, probing each, and the probing file (CSV).
//!
//! Configurations are spread deterministically: C by the golden-ratio sequence over its travel,
//! A evenly over its travel less 10° at each end; a configuration whose approaches would leave
//! the linear travels is skipped for the next one of the sequence.
//!
//! Configuration `i` probes sphere `i mod n` of the artefact (n spheres).
//!
//! The file holds one row per configuration: the sphere probed (`sphere`, 0 = the datum), the
//! rotary angles (`C_deg`, `A_deg`, named by the
//! machine's rotary axes), the nominal and the measured sphere centre in linear-axis coordinates
//! (`X_nominal_mm` …, `X_measured_mm` …), the centre's covariance from the fit (`cov_xx_mm2` …)
//! and the fit's RMS residual. Header comments name the machine and the realisation.

use nalgebra::{Matrix3, Vector3};
use rand::rngs::StdRng;
use rand::SeedableRng;

use super::probe::{probe_sphere, ProbeError, ProbedSphere, VirtualProbe};
use super::spec::FiveAxisSpec;
use super::truth::TrueMachine;
use vmc_identify::identify::Observation;
use vmc_identify::inverse::nominal_linear_axes;

/// The `i`-th configuration of the spread sequence, degrees.
#[must_use]
pub fn spread_configuration(spec: &FiveAxisSpec, i: usize, n: usize) -> [f64; 2] {
    let lim = spec.rotary_limits_deg();
    let mut rot = [0.0; 2];
    for (r, &(lo, hi)) in lim.iter().enumerate().take(2) {
        let is_turntable = hi - lo >= 359.0;
        rot[r] = if is_turntable {
            lo + (hi - lo) * (i as f64 * 0.618_033_988_75).fract()
        } else {
            let (a, b) = (
                lo + 10.0_f64.min((hi - lo) / 4.0),
                hi - 10.0_f64.min((hi - lo) / 4.0),
            );
            a + (b - a) * ((i % n) as f64 + 0.5) / n as f64
        };
    }
    rot
}

/// Whether every approach of the probe to the sphere at `target_w_mm` at `rotary_deg` stays
/// within the linear travels.
#[must_use]
pub fn reachable(
    spec: &FiveAxisSpec,
    probe: &VirtualProbe,
    target_w_mm: [f64; 3],
    rotary_deg: [f64; 2],
) -> bool {
    let q = nominal_linear_axes(&spec.geometry(), rotary_deg, Vector3::from(target_w_mm));
    let reach = probe.contact_radius_mm + probe.clearance_mm;
    spec.within_travel(q, reach)
}

/// One configuration to probe: which sphere (index, nominal centre in the workpiece frame) at
/// which rotary angles (degrees).
pub type Configuration = ((usize, [f64; 3]), [f64; 2]);

/// `n` reachable configurations of the spread sequence, configuration `i` on sphere `i mod`
/// the number of spheres.
#[must_use]
pub fn spread_configurations(
    spec: &FiveAxisSpec,
    probe: &VirtualProbe,
    n: usize,
) -> Vec<Configuration> {
    let targets = spec.sphere_targets_w_mm();
    let mut out = Vec::with_capacity(n);
    let mut i = 0;
    while out.len() < n && i < 100 * n + 100 {
        let rot = spread_configuration(spec, i, n);
        let k = out.len() % targets.len();
        if reachable(spec, probe, targets[k], rot) {
            out.push(((k, targets[k]), rot));
        }
        i += 1;
    }
    out
}

/// Probes every configuration; the trigger noise is drawn from `noise_seed`.
///
/// # Errors
/// [`ProbeError`] from the first configuration that cannot be probed.
pub fn run(
    machine: &TrueMachine,
    probe: &VirtualProbe,
    configs: &[Configuration],
    noise_seed: u64,
) -> Result<Vec<ProbedSphere>, ProbeError> {
    let mut rng = StdRng::seed_from_u64(noise_seed ^ 0x9b0b_e5ee_d000_0001);
    configs
        .iter()
        .map(|&(sphere, rot)| probe_sphere(machine, probe, sphere, rot, &mut rng))
        .collect()
}

/// The probing file's text.
#[must_use]
pub fn to_csv(
    spec: &FiveAxisSpec,
    seed: u64,
    probe: &VirtualProbe,
    rows: &[ProbedSphere],
) -> String {
    let letters: Vec<char> = spec
        .geometry()
        .rotary
        .iter()
        .map(|r| r.axis.letter())
        .collect();
    let mut s = format!(
        "# machine: {}\n# seed: {seed}\n# trigger_noise_2sigma_um: {}\n# points_per_sphere: {}\n",
        spec.machine.name,
        probe.noise_sigma_mm * 2e3,
        probe.points
    );
    s.push_str("config,sphere");
    for l in &letters {
        s.push_str(&format!(",{l}_deg"));
    }
    s.push_str(",X_nominal_mm,Y_nominal_mm,Z_nominal_mm,X_measured_mm,Y_measured_mm,Z_measured_mm");
    s.push_str(",cov_xx_mm2,cov_yy_mm2,cov_zz_mm2,cov_xy_mm2,cov_xz_mm2,cov_yz_mm2,fit_rms_um\n");
    let var = probe.noise_sigma_mm.powi(2);
    for (i, r) in rows.iter().enumerate() {
        s.push_str(&format!("{i},{}", r.sphere));
        for v in r.rotary_deg.iter().take(letters.len()) {
            s.push_str(&format!(",{v}"));
        }
        let c = r.fit.cov_per_var * var;
        for v in r.nominal_mm.iter().chain(r.fit.centre_mm.iter()).chain(
            [
                c[(0, 0)],
                c[(1, 1)],
                c[(2, 2)],
                c[(0, 1)],
                c[(0, 2)],
                c[(1, 2)],
            ]
            .iter(),
        ) {
            s.push_str(&format!(",{v}"));
        }
        s.push_str(&format!(",{}\n", r.fit.rms_residual_mm * 1e3));
    }
    s
}

/// A probing file, read back.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbingFile {
    /// `# machine:` header value.
    pub machine: Option<String>,
    /// `# seed:` header value.
    pub seed: Option<u64>,
    /// `# trigger_noise_2sigma_um:` header value.
    pub trigger_noise_2sigma_um: Option<f64>,
    /// One observation per row.
    pub observations: Vec<Observation>,
}

/// Largest magnitude of any number in a probing file (mm, °, mm²).
pub const MAX_PROBING_VALUE: f64 = 1e5;

/// Largest distance between a measured and a nominal sphere centre, mm (geometric errors of a
/// machine tool are micrometres to tenths of a millimetre).
pub const MAX_CENTRE_ERROR_MM: f64 = 5.0;

/// Largest variance of a probed centre coordinate, mm² (a standard deviation of 1 mm).
pub const MAX_CENTRE_VARIANCE_MM2: f64 = 1.0;

/// What is wrong with a probing file.
#[derive(Debug, thiserror::Error)]
pub enum ProbingFileError {
    /// A structural problem.
    #[error("{0}")]
    Format(String),
    /// A row that does not parse.
    #[error("line {line}: {msg}")]
    Row {
        /// 1-based line.
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// The file was made on another machine.
    #[error("{0}")]
    Mismatch(String),
}

/// Parses a probing file and checks it against the machine: same rotary axes, angles within
/// their limits, nominal centres where this machine puts the sphere (1 µm).
///
/// # Errors
/// [`ProbingFileError`] naming the first problem.
pub fn parse_csv(text: &str, spec: &FiveAxisSpec) -> Result<ProbingFile, ProbingFileError> {
    let geom = spec.geometry();
    let letters: Vec<char> = geom.rotary.iter().map(|r| r.axis.letter()).collect();
    let mut file = ProbingFile {
        machine: None,
        seed: None,
        trigger_noise_2sigma_um: None,
        observations: Vec::new(),
    };
    let mut header: Option<Vec<String>> = None;
    for (n, line) in text.lines().enumerate() {
        let line_no = n + 1;
        let row_err = |msg: String| ProbingFileError::Row { line: line_no, msg };
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        if let Some(c) = line.strip_prefix('#') {
            if let Some((k, v)) = c.split_once(':') {
                let v = v.trim();
                match k.trim() {
                    "machine" => file.machine = Some(v.to_string()),
                    "seed" => file.seed = v.parse().ok(),
                    "trigger_noise_2sigma_um" => file.trigger_noise_2sigma_um = v.parse().ok(),
                    _ => {}
                }
            }
            continue;
        }
        let Some(cols) = &header else {
            let cols: Vec<String> = line.split(',').map(|c| c.trim().to_string()).collect();
            let rot_cols: Vec<String> = cols
                .iter()
                .filter(|c| c.ends_with("_deg"))
                .cloned()
                .collect();
            let want: Vec<String> = letters.iter().map(|l| format!("{l}_deg")).collect();
            if rot_cols != want {
                return Err(ProbingFileError::Mismatch(format!(
                    "the probing file has rotary columns {rot_cols:?} but machine {} has rotary axes {want:?}: its configurations do not match this machine",
                    spec.machine.name
                )));
            }
            header = Some(cols);
            continue;
        };
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != cols.len() {
            return Err(row_err(format!(
                "{} fields, the header has {}",
                fields.len(),
                cols.len()
            )));
        }
        let get = |name: &str| -> Result<f64, ProbingFileError> {
            let i = cols.iter().position(|c| c == name).ok_or_else(|| {
                ProbingFileError::Format(format!("the probing file has no column {name}"))
            })?;
            let v = fields[i]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| row_err(format!("{name} is not a number: '{}'", fields[i])))?;
            // Coordinates, angles, counts and covariances of a machine tool are all far below
            // this; a larger number is a broken cell, not a measurement.
            if v.abs() > MAX_PROBING_VALUE {
                return Err(row_err(format!(
                    "{name} = {v:e} is beyond any probing value (|v| ≤ {MAX_PROBING_VALUE:e})"
                )));
            }
            Ok(v)
        };
        let mut rot = [0.0; 2];
        for (r, l) in letters.iter().enumerate() {
            rot[r] = get(&format!("{l}_deg"))?;
            let (lo, hi) = spec.rotary_limits_deg()[r];
            if rot[r] < lo - 1e-9 || rot[r] > hi + 1e-9 {
                return Err(row_err(format!(
                    "{l} = {}° is outside the travel {lo}…{hi}° of machine {}: the configurations do not match this machine",
                    rot[r], spec.machine.name
                )));
            }
        }
        let xyz = |suffix: &str| -> Result<[f64; 3], ProbingFileError> {
            Ok([
                get(&format!("X_{suffix}"))?,
                get(&format!("Y_{suffix}"))?,
                get(&format!("Z_{suffix}"))?,
            ])
        };
        let targets = spec.sphere_targets_w_mm();
        let k = get("sphere")?;
        if k.fract() != 0.0 || k < 0.0 || k as usize >= targets.len() {
            return Err(row_err(format!(
                "sphere {k} does not exist on machine {} ({} sphere(s)): the configurations do not match this machine",
                spec.machine.name,
                targets.len()
            )));
        }
        let target = targets[k as usize];
        let nominal = xyz("nominal_mm")?;
        let measured = xyz("measured_mm")?;
        let want = nominal_linear_axes(&geom, rot, Vector3::from(target));
        let off = (Vector3::from(want) - Vector3::from(nominal)).norm();
        if off > 1e-3 {
            return Err(row_err(format!(
                "the nominal centre ({:.3}, {:.3}, {:.3}) mm is {:.3} mm from where machine {} puts the sphere at these angles ({:.3}, {:.3}, {:.3}): the configurations do not match this machine",
                nominal[0], nominal[1], nominal[2], off, spec.machine.name, want[0], want[1], want[2]
            )));
        }
        let miss_mm = (Vector3::from(measured) - Vector3::from(nominal)).norm();
        if miss_mm > MAX_CENTRE_ERROR_MM {
            return Err(row_err(format!(
                "the measured centre is {miss_mm:.3} mm from the nominal one: a machine's \
                 errors move it by less than {MAX_CENTRE_ERROR_MM} mm"
            )));
        }
        let (xx, yy, zz) = (get("cov_xx_mm2")?, get("cov_yy_mm2")?, get("cov_zz_mm2")?);
        let (xy, xz, yz) = (get("cov_xy_mm2")?, get("cov_xz_mm2")?, get("cov_yz_mm2")?);
        for (name, v) in [("cov_xx_mm2", xx), ("cov_yy_mm2", yy), ("cov_zz_mm2", zz)] {
            if !(v > 0.0 && v <= MAX_CENTRE_VARIANCE_MM2) {
                return Err(row_err(format!(
                    "{name} = {v:e} mm²: a variance of a probed centre must lie in \
                     (0, {MAX_CENTRE_VARIANCE_MM2}] mm²"
                )));
            }
        }
        let cov = Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz);
        file.observations.push(Observation {
            rotary_deg: rot,
            target_w_mm: target,
            nominal_mm: nominal,
            measured_mm: measured,
            cov_mm2: cov,
        });
    }
    if header.is_none() {
        return Err(ProbingFileError::Format(
            "the probing file has no header row".into(),
        ));
    }
    Ok(file)
}
