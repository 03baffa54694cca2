//! The recording of `modal-fit --rrd`: the measured receptance of each direction against the
//! receptance of the fitted modes.
//!
//! | entity | archetype | content |
//! |---|---|---|
//! | `frf/<x or y>/magnitude_um_per_n/{measured,fitted}` | `Scalars` | \|H\| in µm/N on the `frequency_hz` timeline: measured points grey, the fitted modes' curve coloured |
//! | `frf/<x or y>/phase_deg/{measured,fitted}` | `Scalars` | phase of H in degrees (0 to −180 through a mode) |
//! | `report` | `TextDocument` | the command's printed report |
//!
//! Frequencies are whole Hz on the `frequency_hz` timeline (a sequence), so a time-series view
//! plots the receptance against frequency; a file finer than 1 Hz gives several points per
//! whole Hz.

use std::path::Path;

use nalgebra::Complex;
use rerun::blueprint::{Blueprint, Horizontal, TextDocumentView, TimeSeriesView, Vertical};

use super::layout::framed_with;
use super::{RecordError, RrdFile};

/// One direction's measured and fitted receptance at the file's frequencies.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfCurve<'a> {
    /// `x` or `y`.
    pub direction: char,
    /// The file's frequencies, Hz.
    pub frequency_hz: &'a [f64],
    /// The measured receptance, m/N, one per frequency.
    pub measured_m_per_n: Vec<Complex<f64>>,
    /// The receptance of the fitted modes, m/N, one per frequency.
    pub fitted_m_per_n: Vec<Complex<f64>>,
}

const MEASURED_RGB: [u8; 3] = [170, 170, 170];
const FITTED_RGB: [u8; 3] = [235, 90, 80];

/// Layout: per direction magnitude above phase, the report beside them.
fn blueprint(directions: &[char]) -> Blueprint {
    let columns = directions.iter().map(|d| {
        let magnitude = TimeSeriesView::new(format!("{d}: |H| (µm/N) against frequency (Hz)"))
            .with_origin(format!("/frf/{d}/magnitude_um_per_n"));
        let phase = TimeSeriesView::new(format!("{d}: phase of H (deg)"))
            .with_origin(format!("/frf/{d}/phase_deg"));
        Vertical::new([magnitude.into(), phase.into()]).into()
    });
    let report = TextDocumentView::new("Report").with_origin("/report");
    let all: Vec<_> = columns.chain([report.into()]).collect();
    framed_with(
        Horizontal::new(all),
        "frequency_hz",
        rerun::blueprint::components::PlayState::Paused,
    )
}

/// Writes the measured and fitted receptances and the report; gives the file's size in bytes.
///
/// # Errors
/// The recording cannot be written.
pub fn record_frf(
    path: &Path,
    force: bool,
    title: &str,
    curves: &[FrfCurve<'_>],
    report: &str,
) -> Result<u64, RecordError> {
    let directions: Vec<char> = curves.iter().map(|c| c.direction).collect();
    let file = RrdFile::create(path, force, title, blueprint(&directions))?;
    let rec = file.stream();
    for c in curves {
        let index = || {
            rerun::TimeColumn::new_sequence(
                "frequency_hz",
                c.frequency_hz.iter().map(|f| f.round() as i64),
            )
        };
        for (quantity, value) in [
            (
                "magnitude_um_per_n",
                magnitude_um_per_n as fn(&Complex<f64>) -> f64,
            ),
            ("phase_deg", phase_deg),
        ] {
            for (name, values, color, line) in [
                ("measured", &c.measured_m_per_n, MEASURED_RGB, false),
                ("fitted", &c.fitted_m_per_n, FITTED_RGB, true),
            ] {
                let entity = format!("frf/{}/{quantity}/{name}", c.direction);
                let color = rerun::Color::from_rgb(color[0], color[1], color[2]);
                let style = if line {
                    rec.log_static(
                        entity.as_str(),
                        &rerun::SeriesLines::new()
                            .with_names([format!("{name} ({})", c.direction)])
                            .with_colors([color])
                            .with_widths([1.5]),
                    )
                } else {
                    rec.log_static(
                        entity.as_str(),
                        &rerun::SeriesPoints::new()
                            .with_names([format!("{name} ({})", c.direction)])
                            .with_colors([color])
                            .with_markers([rerun::components::MarkerShape::Circle])
                            .with_marker_sizes([1.5]),
                    )
                };
                style.map_err(|x| file.err(x))?;
                let cols = rerun::Scalars::new(values.iter().map(value))
                    .columns_of_unit_batches()
                    .map_err(|x| file.err(x))?;
                rec.send_columns(entity.as_str(), [index()], cols)
                    .map_err(|x| file.err(x))?;
            }
        }
    }
    rec.log_static("report", &rerun::TextDocument::from_markdown(report))
        .map_err(|x| file.err(x))?;
    file.finish()
}

fn magnitude_um_per_n(h: &Complex<f64>) -> f64 {
    h.norm() * 1e6
}

fn phase_deg(h: &Complex<f64>) -> f64 {
    h.arg().to_degrees()
}
