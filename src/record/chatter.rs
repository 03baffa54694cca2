//! Lobe diagrams: the recording of `chatter --rrd` (the stability lobes at the program's
//! engagements with its cuts as points on them) and of `lobes --controller --rrd` (the lobes
//! without and with the controller, no cuts).
//!
//! | entity | archetype | content |
//! |---|---|---|
//! | `chatter/depth_mm/lobes/<engagement>` | `Scalars` (line) | critical depth (mm) against speed on the `spindle_rpm` timeline, one curve per engagement the program has (a_e/D bin and milling direction) |
//! | `chatter/depth_mm/cuts/{stable,marginal,unstable}` | `Scalars` (points) | each cutting move at (its speed, its axial depth a_p): green, yellow, red |
//! | `diagram/{frame,ticks,lobes/<engagement>,cuts}` | `LineStrips2D`, `Points2D` | the same diagram drawn whole in a 2D view (speed to the right, depth up; curves clipped at the top), with tick labels |
//! | `report` | `TextDocument` | the command's printed report |
//!
//! A cut sits under the curve of its engagement when it is stable, above it when it chatters.

use std::path::Path;

use rerun::blueprint::{
    Blueprint, Horizontal, Spatial2DView, TextDocumentView, TimeSeriesView, Vertical,
};

use crate::dynamics::LobePoint;

use super::{layout::framed_with, RecordError, RrdFile};

/// One lobe curve of the program: a name (e.g. `a_e/D 0.150 down`) and its points.
#[derive(Debug, Clone)]
pub struct LobeCurve {
    /// Engagement label.
    pub name: String,
    /// The boundary, by speed.
    pub points: Vec<LobePoint>,
}

/// One cut as a point of the diagram.
#[derive(Debug, Clone, Copy)]
pub struct CutPoint {
    /// Spindle speed, rpm.
    pub spindle_rpm: f64,
    /// Axial depth a_p, mm.
    pub axial_depth_mm: f64,
    /// 0 stable, 1 marginal, 2 unstable.
    pub class: usize,
    /// Index of its engagement's curve.
    pub curve: usize,
}

/// Curve colours, in turn.
const CURVES_RGB: [[u8; 3]; 6] = [
    [70, 140, 240],
    [245, 150, 40],
    [170, 110, 220],
    [60, 190, 190],
    [200, 200, 90],
    [150, 150, 150],
];
/// Stable, marginal, unstable.
const CLASSES: [(&str, [u8; 3]); 3] = [
    ("stable", [60, 200, 90]),
    ("marginal", [240, 210, 60]),
    ("unstable", [235, 60, 60]),
];

fn rgb(c: [u8; 3]) -> rerun::Color {
    rerun::Color::from_rgb(c[0], c[1], c[2])
}

fn blueprint(with_cuts: bool) -> Blueprint {
    let cuts = if with_cuts {
        " and the program's cuts"
    } else {
        ""
    };
    let depth = TimeSeriesView::new(format!(
        "Critical axial depth (mm) against spindle speed (rpm){cuts}"
    ))
    .with_origin("/chatter/depth_mm");
    let diagram = Spatial2DView::new(format!(
        "Stability lobes (critical a_p against spindle speed){cuts}"
    ))
    .with_origin("/diagram");
    let report = TextDocumentView::new("Report").with_origin("/report");
    let left = Vertical::new([diagram.into(), depth.into()]).with_row_shares([3.0, 1.0]);
    framed_with(
        Horizontal::new([left.into(), report.into()]).with_column_shares([3.0, 1.2]),
        "spindle_rpm",
        rerun::blueprint::components::PlayState::Paused,
    )
}

/// Entity-path-safe form of a label.
fn slug(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// Writes the diagram of `curves` and `cuts` (none for a plain lobe comparison); gives the
/// file's size in bytes.
///
/// # Errors
/// The recording cannot be written.
pub fn record_lobe_diagram(
    path: &Path,
    force: bool,
    title: &str,
    curves: &[LobeCurve],
    cuts: &[CutPoint],
    report: &str,
) -> Result<u64, RecordError> {
    let file = RrdFile::create(path, force, title, blueprint(!cuts.is_empty()))?;
    let rec = file.stream();
    let speed_index = |rpm: &mut dyn Iterator<Item = f64>| {
        rerun::TimeColumn::new_sequence("spindle_rpm", rpm.map(|n| n.round() as i64))
    };
    for (i, c) in curves.iter().enumerate() {
        if c.points.is_empty() {
            continue;
        }
        let entity = format!("chatter/depth_mm/lobes/{}", slug(&c.name));
        rec.log_static(
            entity.as_str(),
            &rerun::SeriesLines::new()
                .with_names([c.name.as_str()])
                .with_colors([rgb(CURVES_RGB[i % CURVES_RGB.len()])])
                .with_widths([1.5]),
        )
        .map_err(|x| file.err(x))?;
        let index = speed_index(&mut c.points.iter().map(|p| p.spindle_rpm));
        let cols = rerun::Scalars::new(c.points.iter().map(|p| p.critical_depth_mm))
            .columns_of_unit_batches()
            .map_err(|x| file.err(x))?;
        rec.send_columns(entity.as_str(), [index], cols)
            .map_err(|x| file.err(x))?;
    }
    for (class, (name, color)) in CLASSES.iter().enumerate() {
        let pts: Vec<&CutPoint> = cuts.iter().filter(|c| c.class == class).collect();
        if pts.is_empty() {
            continue;
        }
        let entity = format!("chatter/depth_mm/cuts/{name}");
        rec.log_static(
            entity.as_str(),
            &rerun::SeriesPoints::new()
                .with_names([format!("{name} cuts")])
                .with_colors([rgb(*color)])
                .with_markers([rerun::components::MarkerShape::Diamond])
                .with_marker_sizes([5.0]),
        )
        .map_err(|x| file.err(x))?;
        let index = speed_index(&mut pts.iter().map(|p| p.spindle_rpm));
        let cols = rerun::Scalars::new(pts.iter().map(|p| p.axial_depth_mm))
            .columns_of_unit_batches()
            .map_err(|x| file.err(x))?;
        rec.send_columns(entity.as_str(), [index], cols)
            .map_err(|x| file.err(x))?;
    }
    log_diagram(rec, curves, cuts).map_err(|x| file.err(x))?;
    rec.log_static("report", &rerun::TextDocument::from_markdown(report))
        .map_err(|x| file.err(x))?;
    file.finish()
}

/// Width and height of the 2D diagram, in its own units (y grows downward in a 2D view).
const DIAGRAM_WH: [f32; 2] = [1000.0, 500.0];

/// A round step near `span / 5`: 1, 2 or 5 × 10^k.
fn tick_step(span: f64) -> f64 {
    let raw = span / 5.0;
    let pow = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * pow)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * pow)
}

/// The whole diagram as 2D primitives under `diagram/`: frame, ticks with labels, curves, cuts,
/// legend.
pub(super) fn log_diagram(
    rec: &rerun::RecordingStream,
    curves: &[LobeCurve],
    cuts: &[CutPoint],
) -> rerun::RecordingStreamResult<()> {
    let speeds = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.spindle_rpm))
        .chain(cuts.iter().map(|c| c.spindle_rpm));
    let (lo, hi) = speeds.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), n| {
        (lo.min(n), hi.max(n))
    });
    if !(lo.is_finite() && hi > lo) {
        return Ok(());
    }
    // Depth range: the cuts well inside, the lobes' minima visible; peaks are clipped.
    let deepest_cut = cuts.iter().map(|c| c.axial_depth_mm).fold(0.0, f64::max);
    let lowest_lobe = curves
        .iter()
        .flat_map(|c| c.points.iter().map(|p| p.critical_depth_mm))
        .fold(f64::INFINITY, f64::min);
    // Every curve's own minimum stays in view too (a controlled loop's lobes lie far above the
    // open loop's).
    let highest_minimum = curves
        .iter()
        .filter_map(|c| {
            c.points
                .iter()
                .map(|p| p.critical_depth_mm)
                .min_by(f64::total_cmp)
        })
        .fold(0.0, f64::max);
    let top = (2.0 * deepest_cut)
        .max(3.0 * lowest_lobe.min(1e9))
        .max(1.5 * highest_minimum.min(1e9))
        .max(1e-3);
    let [w, h] = DIAGRAM_WH;
    let xy = |rpm: f64, depth: f64| -> [f32; 2] {
        let x = ((rpm - lo) / (hi - lo)) as f32 * w;
        let y = h - (depth / top).clamp(0.0, 1.0) as f32 * h;
        [x, y]
    };
    let grey = rgb([150, 150, 150]);
    rec.log_static(
        "diagram/frame",
        &rerun::LineStrips2D::new([[[0.0, 0.0], [w, 0.0], [w, h], [0.0, h], [0.0, 0.0]]])
            .with_colors([grey])
            .with_radii([1.0]),
    )?;
    let (mut tick_lines, mut tick_pos, mut tick_labels) = (Vec::new(), Vec::new(), Vec::new());
    let step_rpm = tick_step(hi - lo);
    let mut n = (lo / step_rpm).ceil() * step_rpm;
    while n <= hi + 1e-9 {
        let [x, _] = xy(n, 0.0);
        tick_lines.push(vec![[x, h], [x, h + 8.0]]);
        tick_pos.push([x, h + 22.0]);
        tick_labels.push(format!("{n:.0} rpm"));
        n += step_rpm;
    }
    let step_mm = tick_step(top);
    let mut d = 0.0;
    while d <= top + 1e-12 {
        let [_, y] = xy(lo, d);
        tick_lines.push(vec![[-8.0, y], [0.0, y]]);
        tick_pos.push([-45.0, y]);
        tick_labels.push(format!("{d:.2} mm"));
        d += step_mm;
    }
    rec.log_static(
        "diagram/ticks",
        &rerun::LineStrips2D::new(tick_lines)
            .with_colors([grey])
            .with_radii([1.0]),
    )?;
    rec.log_static(
        "diagram/tick_labels",
        &rerun::Points2D::new(tick_pos)
            .with_radii([0.5])
            .with_colors([grey])
            .with_labels(tick_labels)
            .with_show_labels(true),
    )?;
    // A legend under the diagram: the curves, then the cuts.
    let mut legend: Vec<(String, rerun::Color)> = Vec::new();
    for (i, c) in curves.iter().enumerate() {
        if c.points.is_empty() {
            continue;
        }
        let color = rgb(CURVES_RGB[i % CURVES_RGB.len()]);
        let strip: Vec<[f32; 2]> = c
            .points
            .iter()
            .map(|p| xy(p.spindle_rpm, p.critical_depth_mm))
            .collect();
        rec.log_static(
            format!("diagram/lobes/{}", slug(&c.name)).as_str(),
            &rerun::LineStrips2D::new([strip])
                .with_colors([color])
                .with_radii([1.5]),
        )?;
        legend.push((format!("lobes, {}", c.name), color));
    }
    // Cuts at the same speed and depth (a whole pocket at one setting) are one marker per
    // engagement and verdict, side by side, counted in the legend.
    let mut clusters: Vec<(usize, usize, [f32; 2], usize)> = Vec::new();
    for c in cuts {
        let at = xy(c.spindle_rpm, c.axial_depth_mm);
        match clusters
            .iter_mut()
            .find(|k| k.0 == c.curve && k.1 == c.class && k.2 == at)
        {
            Some(k) => k.3 += 1,
            None => clusters.push((c.curve, c.class, at, 1)),
        }
    }
    let spread = curves.len().max(1) as f32;
    rec.log_static(
        "diagram/cuts",
        &rerun::Points2D::new(
            clusters.iter().map(|&(curve, _, [x, y], _)| {
                [x + 12.0 * (curve as f32 - 0.5 * (spread - 1.0)), y]
            }),
        )
        .with_radii([8.0])
        .with_colors(clusters.iter().map(|k| rgb(CLASSES[k.1.min(2)].1))),
    )?;
    for &(curve, class, _, n) in &clusters {
        let name = curves.get(curve).map_or("", |c| c.name.as_str());
        let (verdict, color) = CLASSES[class.min(2)];
        legend.push((format!("{n} cut(s), {name}: {verdict}"), rgb(color)));
    }
    rec.log_static(
        "diagram/legend",
        &rerun::Points2D::new((0..legend.len()).map(|k| [0.5 * w, h + 60.0 + 26.0 * k as f32]))
            .with_radii([0.5])
            .with_colors(legend.iter().map(|l| l.1))
            .with_labels(legend.iter().map(|l| l.0.clone()))
            .with_show_labels(true),
    )?;
    Ok(())
}
