//! Default viewer layouts (Rerun blueprints), sent inside the recording so `rerun FILE.rrd`
//! opens ready to read.
//!
//! Run layout (`vmc-twin run … --rrd`), timeline `sim_time`:
//! ```text
//! ┌──────────────────────────────┬───────────────────────────┐
//! │ 3-D: machine, paths (×K),    │ errors before (µm)        │
//! │ error arrows, thermal nodes  ├───────────────────────────┤
//! │                              │ errors after (µm)         │
//! ├──────────────┬───────────────┼───────────────────────────┤
//! │ report (md)  │ events        │ sensor temperatures (°C)  │
//! └──────────────┴───────────────┴───────────────────────────┘
//! ```
//! Campaign layout (`vmc-twin campaign --rrd`), timeline `diagonal_mm`: the same for the
//! representative run, with a first time-series panel of |E| before (red) and after (green) of
//! every held-out hybrid run, all on one axis of position along the diagonal.

use rerun::blueprint::components::{PanelState, PlayState};
use rerun::blueprint::{
    Blueprint, BlueprintPanel, ContainerLike, Horizontal, SelectionPanel, Spatial3DView, Tabs,
    TextDocumentView, TextLogView, TimePanel, TimeSeriesView, Vertical,
};

/// Room for the views (blueprint and selection panels collapsed), the time cursor at the end of
/// `timeline` (every path fully drawn).
pub(crate) fn framed(root: Horizontal, timeline: &str) -> Blueprint {
    framed_with(root, timeline, PlayState::Following)
}

/// [`framed`] with the time cursor paused: for diagrams drawn on a timeline that is not time
/// (e.g. spindle speed), whose plots then show the whole range.
pub(crate) fn framed_with(root: Horizontal, timeline: &str, play: PlayState) -> Blueprint {
    Blueprint::new(root)
        .with_blueprint_panel(BlueprintPanel::from_state(PanelState::Collapsed))
        .with_selection_panel(SelectionPanel::from_state(PanelState::Collapsed))
        .with_time_panel(
            TimePanel::new()
                .with_timeline(timeline)
                .with_play_state(play),
        )
}

fn scene_view(magnify: f64) -> Spatial3DView {
    Spatial3DView::new(format!("Machine and tool paths (errors ×{magnify:.0})"))
        .with_origin("/")
        .with_contents([
            "+ /machine/**",
            "+ /paths/**",
            "+ /errors/vectors/**",
            "+ /thermal/nodes",
        ])
}

fn text_panels() -> ContainerLike {
    Tabs::new([
        TextDocumentView::new("Report")
            .with_origin("/report")
            .into(),
        TextDocumentView::new("Legend")
            .with_origin("/legend")
            .into(),
        TextLogView::new("Events").with_origin("/events").into(),
    ])
    .into()
}

fn error_views(prefix: &str) -> [ContainerLike; 2] {
    [
        TimeSeriesView::new(format!(
            "{prefix}errors before compensation Ex, Ey, Ez, |E| (µm)"
        ))
        .with_origin("/errors/before")
        .into(),
        TimeSeriesView::new(format!("{prefix}errors after compensation (µm)"))
            .with_origin("/errors/after")
            .into(),
    ]
}

fn sensors_view() -> ContainerLike {
    TimeSeriesView::new("Sensor temperatures (°C)")
        .with_origin("/thermal/sensors")
        .into()
}

/// Layout of a single run's recording.
pub fn run_blueprint(magnify: f64) -> Blueprint {
    let [before, after] = error_views("");
    let left =
        Vertical::new([scene_view(magnify).into(), text_panels()]).with_row_shares([3.0, 1.2]);
    let right = Vertical::new([before, after, sensors_view()]);
    framed(
        Horizontal::new([left.into(), right.into()]).with_column_shares([1.3, 1.0]),
        "sim_time",
    )
}

/// Layout of a campaign recording (see the module docs).
pub fn campaign_blueprint(magnify: f64, representative: &str) -> Blueprint {
    let [before, after] = error_views(&format!("{representative}: "));
    let all_runs: ContainerLike = TimeSeriesView::new(
        "Every held-out hybrid run: |E| before (red) and after compensation (green), µm, along the diagonal",
    )
    .with_origin("/runs")
    .into();
    let left =
        Vertical::new([scene_view(magnify).into(), text_panels()]).with_row_shares([3.0, 1.2]);
    let right = Vertical::new([all_runs, before, after, sensors_view()])
        .with_row_shares([1.4, 1.0, 1.0, 1.0]);
    framed(
        Horizontal::new([left.into(), right.into()]).with_column_shares([1.2, 1.0]),
        "diagonal_mm",
    )
}
