//! Recordings of the milling-dynamics commands: the lobe diagram of `lobes --rrd` and the time
//! series and spectra of `cut --rrd`.
//!
//! | entity | archetype | content |
//! |---|---|---|
//! | `lobes/critical_depth_mm/{boundary,hopf,flip}` | `Scalars` | critical depth (mm) on the `spindle_rpm` timeline: the whole boundary as a line, Hopf points blue, flip points orange |
//! | `lobes/chatter_frequency_hz/{hopf,flip}` | `Scalars` | chatter frequency (Hz) per speed |
//! | `cut/vibration_um/{x,y}` | `Scalars` | tip displacement (µm) on `sim_time` |
//! | `cut/force_n/{fx,fy}` | `Scalars` | cutting force on the tool (N) on `sim_time` |
//! | `cut/change_per_tooth_um` | `Scalars` | change of the vibration over one tooth period (µm), once per tooth: the verdict's quantity |
//! | `spectrum/vibration_um`, `spectrum/disturbance_um` | `BarChart` | amplitude spectra (µm against Hz) of the vibration and of the vibration minus the steady cut, last half of the horizon |
//! | `diagram/…` | `LineStrips2D`, `Points2D` | `lobes`: the boundary drawn whole in a 2D view (see [`super::chatter`]) |
//! | `report` | `TextDocument` | the command's printed report |
//!
//! Speeds are whole rpm on the `spindle_rpm` timeline (a sequence), so a time-series view plots
//! depth against speed.

use std::path::Path;

use rerun::blueprint::{
    BarChartView, Blueprint, Horizontal, Spatial2DView, TextDocumentView, TimeSeriesView, Vertical,
};

use crate::dynamics::{BoundaryKind, CutSimulation, LobePoint};

use super::chatter::{log_diagram, LobeCurve};
use super::layout::{framed, framed_with};
use super::{RecordError, RrdFile};

const HOPF_RGB: [u8; 3] = [70, 140, 240];
const FLIP_RGB: [u8; 3] = [245, 150, 40];

fn rgb(c: [u8; 3]) -> rerun::Color {
    rerun::Color::from_rgb(c[0], c[1], c[2])
}

/// Layout of a lobes recording: the whole diagram, depth against speed by kind, chatter
/// frequency and report.
fn lobes_blueprint() -> Blueprint {
    let diagram = Spatial2DView::new("Stability lobes (critical a_p against spindle speed)")
        .with_origin("/diagram");
    let depth = TimeSeriesView::new("Critical axial depth (mm) against spindle speed (rpm)")
        .with_origin("/lobes/critical_depth_mm");
    let freq =
        TimeSeriesView::new("Chatter frequency (Hz)").with_origin("/lobes/chatter_frequency_hz");
    let report = TextDocumentView::new("Report").with_origin("/report");
    let below = Horizontal::new([depth.into(), freq.into(), report.into()]);
    framed_with(
        Horizontal::new([Vertical::new([diagram.into(), below.into()])
            .with_row_shares([2.0, 1.0])
            .into()]),
        "spindle_rpm",
        rerun::blueprint::components::PlayState::Paused,
    )
}

/// Layout of a cut recording: vibration and force over time, spectra and report.
fn cut_blueprint() -> Blueprint {
    let vib = TimeSeriesView::new("Tool-tip vibration (µm)").with_origin("/cut/vibration_um");
    let force = TimeSeriesView::new("Cutting force on the tool (N)").with_origin("/cut/force_n");
    let change = TimeSeriesView::new("Change of the vibration over one tooth period (µm)")
        .with_origin("/cut/change_per_tooth_um");
    let spec = BarChartView::new("Spectrum of the vibration (µm against Hz), last half")
        .with_origin("/spectrum/vibration_um");
    let dist = BarChartView::new("Spectrum of the vibration minus the steady cut (µm against Hz)")
        .with_origin("/spectrum/disturbance_um");
    let report = TextDocumentView::new("Report").with_origin("/report");
    let left = Vertical::new([vib.into(), force.into(), change.into()]);
    let right = Vertical::new([spec.into(), dist.into(), report.into()]);
    framed(Horizontal::new([left.into(), right.into()]), "sim_time")
}

/// Writes a lobe diagram; gives the file's size in bytes.
///
/// # Errors
/// The recording cannot be written.
pub fn record_lobes(
    path: &Path,
    force: bool,
    title: &str,
    points: &[LobePoint],
    report: &str,
) -> Result<u64, RecordError> {
    let file = RrdFile::create(path, force, title, lobes_blueprint())?;
    let rec = file.stream();
    let series = |entity: &str, name: &str, color: [u8; 3], line: bool| {
        if line {
            rec.log_static(
                entity,
                &rerun::SeriesLines::new()
                    .with_names([name])
                    .with_colors([rgb(color)])
                    .with_widths([1.0]),
            )
        } else {
            rec.log_static(
                entity,
                &rerun::SeriesPoints::new()
                    .with_names([name])
                    .with_colors([rgb(color)])
                    .with_markers([rerun::components::MarkerShape::Circle])
                    .with_marker_sizes([3.0]),
            )
        }
    };
    let send = |entity: &str, pts: &[&LobePoint], value: fn(&LobePoint) -> f64| {
        if pts.is_empty() {
            return Ok(());
        }
        let index = rerun::TimeColumn::new_sequence(
            "spindle_rpm",
            pts.iter().map(|p| p.spindle_rpm.round() as i64),
        );
        let cols = rerun::Scalars::new(pts.iter().map(|p| value(p))).columns_of_unit_batches()?;
        rec.send_columns(entity, [index], cols)
    };
    let all: Vec<&LobePoint> = points.iter().collect();
    let of_kind =
        |k: BoundaryKind| -> Vec<&LobePoint> { points.iter().filter(|p| p.kind == k).collect() };
    let depth = |p: &LobePoint| p.critical_depth_mm;
    let freq = |p: &LobePoint| p.chatter_frequency_hz;
    series(
        "lobes/critical_depth_mm/boundary",
        "boundary",
        [170, 170, 170],
        true,
    )
    .map_err(|x| file.err(x))?;
    send("lobes/critical_depth_mm/boundary", &all, depth).map_err(|x| file.err(x))?;
    for (kind, name, color) in [
        (BoundaryKind::Hopf, "hopf", HOPF_RGB),
        (BoundaryKind::Flip, "flip", FLIP_RGB),
    ] {
        let pts = of_kind(kind);
        for (quantity, value) in [
            ("critical_depth_mm", depth as fn(&LobePoint) -> f64),
            ("chatter_frequency_hz", freq),
        ] {
            let entity = format!("lobes/{quantity}/{name}");
            series(
                &entity,
                &format!("{name} ({})", unit(quantity)),
                color,
                false,
            )
            .map_err(|x| file.err(x))?;
            send(&entity, &pts, value).map_err(|x| file.err(x))?;
        }
    }
    let curve = LobeCurve {
        name: "critical depth".into(),
        points: points.to_vec(),
    };
    log_diagram(rec, &[curve], &[]).map_err(|x| file.err(x))?;
    rec.log_static("report", &rerun::TextDocument::from_markdown(report))
        .map_err(|x| file.err(x))?;
    file.finish()
}

fn unit(quantity: &str) -> &'static str {
    if quantity.ends_with("_mm") {
        "mm"
    } else {
        "Hz"
    }
}

/// Writes the time series and spectra of one cut; the spectra are drawn up to `max_hz`. Gives
/// the file's size in bytes.
///
/// # Errors
/// The recording cannot be written.
pub fn record_cut(
    path: &Path,
    force: bool,
    title: &str,
    sim: &CutSimulation,
    max_hz: f64,
    report: &str,
) -> Result<u64, RecordError> {
    let file = RrdFile::create(path, force, title, cut_blueprint())?;
    let rec = file.stream();
    let times = rerun::TimeColumn::new_duration_secs(
        "sim_time",
        (0..sim.displacement_m.len()).map(|i| sim.time_s(i)),
    );
    for (entity, name, color, values) in [
        (
            "cut/vibration_um/x",
            "x (µm)",
            [235, 90, 80],
            column(&sim.displacement_m, 0, 1e6),
        ),
        (
            "cut/vibration_um/y",
            "y (µm)",
            [90, 200, 90],
            column(&sim.displacement_m, 1, 1e6),
        ),
        (
            "cut/force_n/fx",
            "Fx (N)",
            [235, 90, 80],
            column(&sim.force_n, 0, 1.0),
        ),
        (
            "cut/force_n/fy",
            "Fy (N)",
            [90, 200, 90],
            column(&sim.force_n, 1, 1.0),
        ),
    ] {
        rec.log_static(
            entity,
            &rerun::SeriesLines::new()
                .with_names([name])
                .with_colors([rgb(color)])
                .with_widths([1.0]),
        )
        .map_err(|x| file.err(x))?;
        let cols = rerun::Scalars::new(values)
            .columns_of_unit_batches()
            .map_err(|x| file.err(x))?;
        rec.send_columns(entity, [times.clone()], cols)
            .map_err(|x| file.err(x))?;
    }
    // Tooth pass k (k = 1..=K) is at t = kτ.
    let passes = rerun::TimeColumn::new_duration_secs(
        "sim_time",
        (1..=sim.change_per_tooth_m.len()).map(|k| k as f64 * sim.period_s),
    );
    rec.log_static(
        "cut/change_per_tooth_um",
        &rerun::SeriesPoints::new()
            .with_names(["change over one tooth period (µm)"])
            .with_colors([rgb(HOPF_RGB)])
            .with_marker_sizes([2.0]),
    )
    .map_err(|x| file.err(x))?;
    let cols = rerun::Scalars::new(sim.change_per_tooth_m.iter().map(|d| d * 1e6))
        .columns_of_unit_batches()
        .map_err(|x| file.err(x))?;
    rec.send_columns("cut/change_per_tooth_um", [passes], cols)
        .map_err(|x| file.err(x))?;
    for (entity, spectrum, color) in [
        ("spectrum/vibration_um", &sim.spectrum, [200, 200, 200]),
        (
            "spectrum/disturbance_um",
            &sim.disturbance_spectrum,
            FLIP_RGB,
        ),
    ] {
        let bins: Vec<usize> = (0..spectrum.frequency_hz.len())
            .filter(|&j| spectrum.frequency_hz[j] <= max_hz)
            .collect();
        let f: Vec<f64> = bins.iter().map(|&j| spectrum.frequency_hz[j]).collect();
        let a: Vec<f64> = bins.iter().map(|&j| spectrum.amplitude[j] * 1e6).collect();
        let width = f.get(1).copied().unwrap_or(1.0) as f32;
        rec.log_static(
            entity,
            &rerun::BarChart::new(a)
                .with_abscissa(f)
                .with_widths(vec![width; bins.len()])
                .with_color(rgb(color)),
        )
        .map_err(|x| file.err(x))?;
    }
    rec.log_static("report", &rerun::TextDocument::from_markdown(report))
        .map_err(|x| file.err(x))?;
    file.finish()
}

fn column(v: &[[f64; 2]], axis: usize, scale: f64) -> Vec<f64> {
    v.iter().map(|p| p[axis] * scale).collect()
}
