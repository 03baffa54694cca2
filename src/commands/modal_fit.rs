//! `vmc-twin modal-fit`: the tool-tip modes of a measured receptance FRF (an impact test), as
//! the tool file that `lobes`, `cut` and `chatter` take.
//!
//! The fit is [`crate::dynamics::modal_fit`] (LSCF poles, a stabilisation diagram for the
//! number of modes, real-mode constants with residual terms). The tool file holds the modes
//! only (no residual terms) and the cutter (`[tool]`) of a template tool file, since an FRF
//! says nothing of teeth or cutting coefficients. The report gives each mode's frequency,
//! damping ratio, stiffness, modal mass and the orders its pole stayed through, and per
//! direction the RMS misfit of the fit and of the modes alone (what the tool file gives the
//! stability methods).

use std::fmt::Write as _;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use nalgebra::Complex;

use crate::dynamics::modal::ModalModel;
use crate::dynamics::modal_fit::{fit, DirectionFit, FitOptions, Frf, ModalFit};
use crate::dynamics::TipModes;
use crate::files;
use crate::record::modal_fit::{record_frf, FrfCurve};
use vmc_machine::milling::{tool_file_toml, ToolDynamics};

/// What to fit, validated.
pub struct ModalFitConfig {
    /// The measured FRF.
    pub frf: Frf,
    /// Where it came from (for the report and the tool file's comment).
    pub frf_source: String,
    /// The tool whose cutter the written tool file takes.
    pub template: ToolDynamics,
    /// Where the template came from.
    pub template_source: String,
    /// Name of the written tool (default: the template's name with the FRF file's).
    pub name: Option<String>,
    /// Options of the fit.
    pub options: FitOptions,
    /// The tool file to write.
    pub out: Option<PathBuf>,
    /// A Rerun recording of the measured and fitted receptance.
    pub rrd: Option<PathBuf>,
    /// Overwrite existing outputs.
    pub force: bool,
}

/// Fits the modes, prints them, writes the tool file and the recording.
///
/// # Errors
/// Outputs that may not be written (checked before the fit), no stable mode, fitted modes the
/// dynamics refuses.
pub fn modal_fit(cfg: &ModalFitConfig, out: &mut dyn Write) -> Result<()> {
    if let Some(path) = &cfg.out {
        files::check_writable(path, cfg.force)?;
    }
    if let Some(path) = &cfg.rrd {
        crate::record::check_rrd_path(path, cfg.force)?;
    }
    let fitted = fit(&cfg.frf, &cfg.options).with_context(|| cfg.frf_source.clone())?;
    let modes = fitted.tip_modes();
    let model =
        ModalModel::new(&modes).with_context(|| format!("{}: the fitted modes", cfg.frf_source))?;
    let curves = curves(&cfg.frf, &model);
    let text = report(cfg, &fitted, &curves)?;
    out.write_all(text.as_bytes())?;
    if let Some(path) = &cfg.out {
        let toml = tool_file(cfg, &fitted, &modes, path)?;
        files::write_atomic(path, toml.as_bytes(), cfg.force)?;
        writeln!(out, "wrote {}", path.display())?;
    }
    if let Some(path) = &cfg.rrd {
        let title = format!("vmc-twin modal-fit {}", cfg.frf_source);
        let md = format!(
            "# vmc-twin modal-fit\n\nMeasured receptance against the receptance of the fitted \
             modes alone (what the tool file holds), per direction: magnitude in µm/N and \
             phase in degrees (frequencies rounded to whole Hz on the `frequency_hz` \
             timeline).\n\n```text\n{text}```\n"
        );
        let bytes = record_frf(path, cfg.force, &title, &curves, &md)?;
        super::wrote_recording(out, path, bytes, "")?;
    }
    Ok(())
}

/// The measured receptance of each direction in the file with that of the fitted modes.
fn curves<'a>(frf: &'a Frf, model: &ModalModel) -> Vec<FrfCurve<'a>> {
    let mut v = Vec::new();
    for (direction, data, k) in [('x', &frf.x_m_per_n, 0), ('y', &frf.y_m_per_n, 1)] {
        let Some(data) = data else { continue };
        let measured_m_per_n = data.iter().map(|&(re, im)| Complex::new(re, im)).collect();
        let fitted_m_per_n = frf
            .frequency_hz
            .iter()
            .map(|f| model.frf(2.0 * std::f64::consts::PI * f)[(k, k)])
            .collect();
        v.push(FrfCurve {
            direction,
            frequency_hz: &frf.frequency_hz,
            measured_m_per_n,
            fitted_m_per_n,
        });
    }
    v
}

/// RMS of |measured − fitted| over the rows, m/N.
fn rms_misfit_m_per_n(c: &FrfCurve<'_>) -> f64 {
    let sq: f64 = c
        .measured_m_per_n
        .iter()
        .zip(&c.fitted_m_per_n)
        .map(|(m, f)| (m - f).norm_sqr())
        .sum();
    (sq / c.measured_m_per_n.len().max(1) as f64).sqrt()
}

/// The printed report.
fn report(cfg: &ModalFitConfig, fitted: &ModalFit, curves: &[FrfCurve<'_>]) -> Result<String> {
    let (f, o) = (&cfg.frf.frequency_hz, &cfg.options);
    let mut s = String::new();
    let dirs: Vec<String> = curves.iter().map(|c| c.direction.to_string()).collect();
    writeln!(
        s,
        "vmc-twin modal-fit: {}, {} frequencies from {} to {} Hz, direction(s) {}",
        cfg.frf_source,
        f.len(),
        f.first().copied().unwrap_or(0.0),
        f.last().copied().unwrap_or(0.0),
        dirs.join(" and ")
    )?;
    writeln!(
        s,
        "method: LSCF at denominator orders 2 to {}; a mode's pole stays within {} % in frequency and {} % in damping through at least {} orders; real modes with upper and lower residual terms",
        o.max_order,
        100.0 * o.frequency_tol,
        100.0 * o.damping_tol,
        o.stable_orders
    )?;
    for (direction, d) in [('x', &fitted.x), ('y', &fitted.y)] {
        match (d, curves.iter().find(|c| c.direction == direction)) {
            (Some(d), Some(c)) => direction_report(&mut s, direction, d, c)?,
            _ => writeln!(s, "direction {direction}: rigid (no columns in the file)")?,
        }
    }
    let t = &cfg.template.tool;
    writeln!(
        s,
        "cutter of the tool file from {}: {} teeth, diameter {} mm, K_t {:e} N/m², K_n {:e} N/m² (an FRF does not give the cutter: --tool FILE for yours)",
        cfg.template_source, t.teeth, t.diameter_mm, t.kt_n_per_m2, t.kn_n_per_m2
    )?;
    Ok(s)
}

/// One direction's lines: its misfit and its modes.
fn direction_report(
    s: &mut String,
    direction: char,
    d: &DirectionFit,
    c: &FrfCurve<'_>,
) -> std::fmt::Result {
    let modes_alone = rms_misfit_m_per_n(c);
    writeln!(
        s,
        "direction {direction}: {} mode(s); peak |H| {:.4e} m/N; residual RMS {:.3e} m/N ({:.2} % of the peak) with the residual terms (upper {:.3e}, lower {:.3e} m/N), {:.3e} m/N ({:.2} %) for the modes alone (what the tool file holds)",
        d.modes.len(),
        d.peak_m_per_n,
        d.rms_residual_m_per_n,
        100.0 * d.rms_residual_m_per_n / d.peak_m_per_n,
        d.upper_residual_m_per_n,
        d.lower_residual_m_per_n,
        modes_alone,
        100.0 * modes_alone / d.peak_m_per_n
    )?;
    writeln!(
        s,
        "  {:>4} {:>12} {:>13} {:>17} {:>13} {:>13}",
        "mode",
        "frequency_hz",
        "damping_ratio",
        "stiffness_n_per_m",
        "modal_mass_kg",
        "stable_orders"
    )?;
    for (i, m) in d.modes.iter().enumerate() {
        writeln!(
            s,
            "  {:>4} {:>12.2} {:>13.5} {:>17.4e} {:>13.5} {:>13}",
            i + 1,
            m.mode.frequency_hz,
            m.mode.damping_ratio,
            m.mode.stiffness_n_per_m,
            m.modal_mass_kg,
            m.stable_orders
        )?;
    }
    Ok(())
}

/// The tool file's text, checked by reading it back.
fn tool_file(
    cfg: &ModalFitConfig,
    fitted: &ModalFit,
    modes: &TipModes,
    path: &Path,
) -> Result<String> {
    let name = cfg
        .name
        .clone()
        .unwrap_or_else(|| format!("{} with the modes of {}", cfg.template.name, cfg.frf_source));
    let mut comment = format!(
        "Written by vmc-twin modal-fit from the FRF {}.\n\
         Modes: LSCF with a stabilisation diagram (orders 2 to {}, stable through >= {}); the \
         fit's residual terms are not kept.\n",
        cfg.frf_source, cfg.options.max_order, cfg.options.stable_orders
    );
    for (direction, d) in [('x', &fitted.x), ('y', &fitted.y)] {
        match d {
            Some(d) => writeln!(
                comment,
                "{direction}: {} mode(s), residual RMS {:.3e} m/N of a {:.3e} m/N peak.",
                d.modes.len(),
                d.rms_residual_m_per_n,
                d.peak_m_per_n
            )?,
            None => writeln!(comment, "{direction}: rigid (not in the FRF file).")?,
        }
    }
    write!(
        comment,
        "[tool]: the cutter of {} (an FRF does not give it).",
        cfg.template_source
    )?;
    let text = tool_file_toml(&name, &comment, &cfg.template.tool, modes);
    // What is written must read back as a valid tool file.
    ToolDynamics::from_toml_str(&text, &path.display().to_string())?;
    Ok(text)
}
