//! The fleet in a recording: a histogram across machines (one per seed) of each fleet quantity
//! of the hybrid predictor ([`crate::studies::campaign::fleet::QUANTITIES`]) as a bar chart under
//! `fleet/<quantity>`, and, in a recording of its own (`merge --rrd`), the printed summary as
//! `report`.

use std::path::Path;

use rerun::blueprint::{BarChartView, Blueprint, Horizontal, TextDocumentView, Vertical};

use crate::studies::campaign::fleet::FleetSummary;

use super::layout::framed_with;
use super::{RecordError, RrdFile};

/// The entity of a quantity's histogram.
fn entity(name: &str) -> String {
    let slug: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    format!("fleet/{}", slug.trim_matches('_'))
}

/// Logs the fleet's histograms to `file` (nothing for fewer than two machines).
///
/// # Errors
/// The recording cannot be written.
pub fn log_fleet(file: &RrdFile, fleet: &FleetSummary) -> Result<(), RecordError> {
    if fleet.machines < 2 {
        return Ok(());
    }
    for q in &fleet.quantities {
        let (name, Some(h)) = (q.name, &q.histogram) else {
            continue;
        };
        let counts: Vec<f64> = h.counts.iter().map(|&c| c as f64).collect();
        file.stream()
            .log_static(
                entity(name).as_str(),
                &rerun::BarChart::new(counts)
                    .with_abscissa(h.centres())
                    .with_widths(vec![h.width as f32; h.counts.len()]),
            )
            .map_err(|x| file.err(x))?;
    }
    Ok(())
}

/// Writes a recording of the fleet alone: the four histograms and the printed `summary`;
/// gives its size in bytes.
///
/// # Errors
/// The recording cannot be written.
pub fn record_fleet(
    path: &Path,
    force: bool,
    title: &str,
    fleet: &FleetSummary,
    summary: &str,
) -> Result<u64, RecordError> {
    let views: Vec<_> = fleet
        .quantities
        .iter()
        .map(|q| {
            BarChartView::new(format!("Machines against {}", q.name))
                .with_origin(entity(q.name))
                .into()
        })
        .collect();
    let charts = Vertical::new(views);
    let report = TextDocumentView::new("Summary").with_origin("/report");
    let blueprint: Blueprint = framed_with(
        Horizontal::new([charts.into(), report.into()]).with_column_shares([2.0, 1.5]),
        "seed",
        rerun::blueprint::components::PlayState::Paused,
    );
    let file = RrdFile::create(path, force, title, blueprint)?;
    log_fleet(&file, fleet)?;
    file.stream()
        .log_static(
            "report",
            &rerun::TextDocument::from_markdown(format!("```\n{summary}```\n")),
        )
        .map_err(|x| file.err(x))?;
    file.finish()
}
