//! The probing campaign: which configurations, probing each, and the probing file (CSV).
//!
//! Configurations are spread deterministically: C by the golden-ratio sequence over its travel,
//! A evenly over its travel less 10° at each end; a configuration whose approaches would leave
//! the linear travels is skipped for the next one of the sequence.
//!
//! The targets are the artefact's n spheres and, after them, the placements of a relocated
//! sphere (the machine file's `placements_mm`, or by default spread over the working volume:
//! [`volume_placements_w_mm`]); configuration `i` probes target `i mod` their number. A single
//! artefact probed from its one spot sees the rotary axes' motion errors only where its spheres
//! are: their tilts, over a large table, are then extrapolated with a long lever. Placements over
//! the volume measure them there; each placement's offset from where it was put is fitted.
//!
//! The file holds one row per configuration: the sphere probed (`sphere`, 0 = the datum), the
//! placement (`placement`, 0 = the artefact), the nominal sphere centre in the workpiece frame
//! (`target_x_mm` …), the rotary angles (`C_deg`, `A_deg`, named by the
//! machine's rotary axes), the nominal and the measured sphere centre in linear-axis coordinates
//! (`X_nominal_mm` …, `X_measured_mm` …), the centre's covariance from the fit (`cov_xx_mm2` …)
//! and the fit's RMS residual. Header comments name the machine and the realisation.

use nalgebra::{Matrix3, Vector3};
use rand::rngs::StdRng;
use rand::SeedableRng;

use super::heldout::HeldOutPlan;
use super::probe::{probe_sphere, ProbeError, ProbeTarget, ProbedSphere, VirtualProbe};
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

/// One configuration to probe: which sphere at which rotary angles (degrees).
pub type Configuration = (ProbeTarget, [f64; 2]);

/// The most placements [`volume_placements_w_mm`] lays out.
pub const MAX_VOLUME_PLACEMENTS: usize = 8;

/// Where the default placements go, as (share of the judged radius, angle about the table axis
/// in degrees, share of the judged height): the first four spread over the edge at three
/// heights and the top near the centre; the next four fill between.
const VOLUME_LAYOUT: [(f64, f64, f64); MAX_VOLUME_PLACEMENTS] = [
    (0.75, 0.0, 0.75),
    (0.75, 120.0, 0.25),
    (0.75, 240.0, 0.5),
    (0.3, 60.0, 0.9),
    (0.5, 300.0, 0.6),
    (0.9, 180.0, 0.1),
    (0.5, 30.0, 0.4),
    (0.9, 90.0, 0.9),
];

/// `n` (at most [`MAX_VOLUME_PLACEMENTS`]) placements of a relocated sphere spread over the
/// machine's working volume — the cylinder the held-out judge draws from by default (radius
/// the larger half stroke of X and Y about the table's axis, height half the Z stroke) — as
/// nominal centres in the workpiece frame, mm.
#[must_use]
pub fn volume_placements_w_mm(spec: &FiveAxisSpec, n: usize) -> Vec<[f64; 3]> {
    let geom = spec.geometry();
    let table = geom
        .rotary
        .iter()
        .find(|r| r.axis.letter() == 'C')
        .map_or([0.0; 3], |r| r.point_mm);
    let (radius_mm, height_mm) = HeldOutPlan::default().region_mm(spec);
    VOLUME_LAYOUT
        .iter()
        .take(n)
        .map(|&(fr, angle_deg, fh)| {
            let a = angle_deg.to_radians();
            [
                table[0] + fr * radius_mm * a.cos() - geom.datum_mm[0],
                table[1] + fr * radius_mm * a.sin() - geom.datum_mm[1],
                table[2] + fh * height_mm - geom.datum_mm[2],
            ]
        })
        .collect()
}

/// The placements a campaign probes, nominal centres in the workpiece frame, mm: the first
/// `n` of the machine file's `placements_mm`, or of [`volume_placements_w_mm`] when the file
/// has none; `n = None`: all of the file's, or 4 over the volume.
///
/// # Errors
/// A message when `n` exceeds what the file or the layout holds.
pub fn placements_w_mm(spec: &FiveAxisSpec, n: Option<usize>) -> Result<Vec<[f64; 3]>, String> {
    let own = &spec.sphere.placements_mm;
    if own.is_empty() {
        let n = n.unwrap_or(4);
        if n > MAX_VOLUME_PLACEMENTS {
            return Err(format!(
                "at most {MAX_VOLUME_PLACEMENTS} placements are laid out over the volume, {n} asked (give your own as [sphere] placements_mm in the machine file)"
            ));
        }
        return Ok(volume_placements_w_mm(spec, n));
    }
    let n = n.unwrap_or(own.len());
    if n > own.len() {
        return Err(format!(
            "machine {} lists {} placements ([sphere] placements_mm), {n} asked",
            spec.machine.name,
            own.len()
        ));
    }
    let c = spec.sphere.centre_mm;
    Ok(own
        .iter()
        .take(n)
        .map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]])
        .collect())
}

/// `n` reachable configurations of the spread sequence, configuration `i` on target `i mod`
/// the number of targets: the artefact's spheres, then the placements `placements_w_mm`
/// (nominal centres in the workpiece frame, mm; placement k ≥ 1 is `placements_w_mm[k − 1]`).
#[must_use]
pub fn spread_configurations(
    spec: &FiveAxisSpec,
    probe: &VirtualProbe,
    n: usize,
    placements_w_mm: &[[f64; 3]],
) -> Vec<Configuration> {
    let targets: Vec<ProbeTarget> = spec
        .sphere_targets_w_mm()
        .into_iter()
        .enumerate()
        .map(|(k, t)| ProbeTarget::artefact(k, t))
        .chain(
            placements_w_mm
                .iter()
                .enumerate()
                .map(|(k, &t)| ProbeTarget {
                    sphere: 0,
                    placement: k + 1,
                    target_w_mm: t,
                }),
        )
        .collect();
    let mut out = Vec::with_capacity(n);
    let mut i = 0;
    while out.len() < n && i < 100 * n + 100 {
        let rot = spread_configuration(spec, i, n);
        let t = targets[out.len() % targets.len()];
        if reachable(spec, probe, t.target_w_mm, rot) {
            out.push((t, rot));
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
        .map(|&(target, rot)| probe_sphere(machine, probe, target, rot, &mut rng))
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
    s.push_str("config,sphere,placement,target_x_mm,target_y_mm,target_z_mm");
    for l in &letters {
        s.push_str(&format!(",{l}_deg"));
    }
    s.push_str(",X_nominal_mm,Y_nominal_mm,Z_nominal_mm,X_measured_mm,Y_measured_mm,Z_measured_mm");
    s.push_str(",cov_xx_mm2,cov_yy_mm2,cov_zz_mm2,cov_xy_mm2,cov_xz_mm2,cov_yz_mm2,fit_rms_um\n");
    let var = probe.noise_sigma_mm.powi(2);
    for (i, r) in rows.iter().enumerate() {
        let t = r.target_w_mm;
        s.push_str(&format!(
            "{i},{},{},{},{},{}",
            r.sphere, r.placement, t[0], t[1], t[2]
        ));
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
    let mut placed = Placed::default();
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
        let target = row_target(spec, cols, &get, &mut placed).map_err(row_err)?;
        let placement = placed.last_row_placement;
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
            placement,
        });
    }
    if header.is_none() {
        return Err(ProbingFileError::Format(
            "the probing file has no header row".into(),
        ));
    }
    if let Some(k) = (1..=placed.targets.len()).find(|k| !placed.targets.contains_key(k)) {
        return Err(ProbingFileError::Format(format!(
            "the probing file uses placements up to {} but none numbered {k}: placements are numbered 1, 2, … without gaps",
            placed.targets.keys().max().copied().unwrap_or(0)
        )));
    }
    Ok(file)
}

/// The placements met so far in a probing file: each one's nominal centre.
#[derive(Default)]
struct Placed {
    targets: std::collections::BTreeMap<usize, [f64; 3]>,
    last_row_placement: usize,
}

/// A row's sphere target in the workpiece frame: an artefact sphere where the machine puts it
/// (the row's `target_*` columns, if any, must agree), or a placement's own nominal centre (the
/// same on every row of that placement). Files without the `placement` column are artefact-only.
fn row_target(
    spec: &FiveAxisSpec,
    cols: &[String],
    get: &dyn Fn(&str) -> Result<f64, ProbingFileError>,
    placed: &mut Placed,
) -> Result<[f64; 3], String> {
    let msg = |e: ProbingFileError| match e {
        ProbingFileError::Row { msg, .. } => msg,
        other => other.to_string(),
    };
    let has = |c: &str| cols.iter().any(|h| h == c);
    let own = if has("target_x_mm") {
        Some([
            get("target_x_mm").map_err(msg)?,
            get("target_y_mm").map_err(msg)?,
            get("target_z_mm").map_err(msg)?,
        ])
    } else {
        None
    };
    let placement = if has("placement") {
        let p = get("placement").map_err(msg)?;
        if p.fract() != 0.0 || !(0.0..=1e6).contains(&p) {
            return Err(format!("placement {p} is not a whole number ≥ 0"));
        }
        p as usize
    } else {
        0
    };
    placed.last_row_placement = placement;
    let close = |a: [f64; 3], b: [f64; 3]| (Vector3::from(a) - Vector3::from(b)).norm() <= 1e-6;
    if placement > 0 {
        let t = own.ok_or_else(|| {
            format!("placement {placement} needs the columns target_x_mm, target_y_mm, target_z_mm")
        })?;
        let first = *placed.targets.entry(placement).or_insert(t);
        if !close(first, t) {
            return Err(format!(
                "placement {placement} is at ({:.3}, {:.3}, {:.3}) mm here but at ({:.3}, {:.3}, {:.3}) mm on an earlier row: one placement is one nominal position",
                t[0], t[1], t[2], first[0], first[1], first[2]
            ));
        }
        return Ok(t);
    }
    let targets = spec.sphere_targets_w_mm();
    let k = get("sphere").map_err(msg)?;
    if k.fract() != 0.0 || k < 0.0 || k as usize >= targets.len() {
        return Err(format!(
            "sphere {k} does not exist on machine {} ({} sphere(s)): the configurations do not match this machine",
            spec.machine.name,
            targets.len()
        ));
    }
    let t = targets[k as usize];
    if let Some(o) = own {
        if !close(o, t) {
            return Err(format!(
                "sphere {k} of the artefact is at ({:.3}, {:.3}, {:.3}) mm on machine {}, not ({:.3}, {:.3}, {:.3}) mm: the configurations do not match this machine",
                t[0], t[1], t[2], spec.machine.name, o[0], o[1], o[2]
            ));
        }
    }
    Ok(t)
}
