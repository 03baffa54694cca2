//! The recording of `chatter --rrd`: the stability lobes at the program's engagements with its
//! cuts as points on them.
//!
//! | entity | archetype | content |
//! |---|---|---|
//! | `chatter/depth_mm/lobes/<engagement>` | `Scalars` (line) | critical depth (mm) against speed on the `spindle_rpm` timeline, one curve per engagement the program has (a_e/D bin and milling direction) |
//! | `chatter/depth_mm/cuts/{stable,marginal,unstable}` | `Scalars` (points) | each cutting move at (its speed, its axial depth a_p): green, yellow, red |
//! | `report` | `TextDocument` | the command's printed report |
//!
//! A cut sits under the curve of its engagement when it is stable, above it when it chatters.

use std::path::Path;

use rerun::blueprint::{Blueprint, Horizontal, TextDocumentView, TimeSeriesView};

use crate::dynamics::LobePoint;

use super::{layout::framed, RecordError, RrdFile};

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

fn blueprint() -> Blueprint {
    let depth = TimeSeriesView::new(
        "Critical axial depth (mm) against spindle speed (rpm), with the program's cuts",
    )
    .with_origin("/chatter/depth_mm");
    let report = TextDocumentView::new("Report").with_origin("/report");
    framed(
        Horizontal::new([depth.into(), report.into()]).with_column_shares([3.0, 2.0]),
        "spindle_rpm",
    )
}

/// Entity-path-safe form of a label.
fn slug(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

/// Writes the diagram; gives the file's size in bytes.
///
/// # Errors
/// The recording cannot be written.
pub fn record_chatter(
    path: &Path,
    force: bool,
    title: &str,
    curves: &[LobeCurve],
    cuts: &[CutPoint],
    report: &str,
) -> Result<u64, RecordError> {
    let file = RrdFile::create(path, force, title, blueprint())?;
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
    rec.log_static("report", &rerun::TextDocument::from_markdown(report))
        .map_err(|x| file.err(x))?;
    file.finish()
}
