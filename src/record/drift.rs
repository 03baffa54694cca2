//! Recording of measured and predicted thermal drifts over a measurement file (one time-series
//! view per drift channel: `drift/<channel>/measured`, `drift/<channel>/pred<i>`, and
//! `drift/<channel>/black_box`).

use std::path::Path;

use rerun::blueprint::{Horizontal, TimeSeriesView, Vertical};

use super::layout::framed_with;
use super::{RecordError, RrdFile};

const MEASURED_RGB: [u8; 3] = [220, 220, 220];
const PRED_RGB: [[u8; 3]; 3] = [[235, 90, 80], [240, 170, 60], [90, 200, 90]];
const BLACK_BOX_RGB: [u8; 3] = [90, 150, 235];

/// Writes measured drifts (`drifts`, one column per channel named in `names`) and the named
/// predictions over `time_s` (NaN rows are left out); gives the file's size in bytes.
///
/// # Errors
/// The recording cannot be written.
#[allow(clippy::too_many_arguments)]
pub fn record_drift(
    path: &Path,
    force: bool,
    title: &str,
    time_s: &[f64],
    names: &[String],
    drifts: &[Vec<f64>],
    preds: &[(&str, &Vec<Vec<f64>>)],
    black_box: Option<(&str, &Vec<Vec<f64>>)>,
) -> Result<u64, RecordError> {
    let views: Vec<_> = names
        .iter()
        .map(|n| {
            TimeSeriesView::new(format!("{n}: measured and predicted drift"))
                .with_origin(format!("/drift/{n}"))
                .into()
        })
        .collect();
    let blueprint = framed_with(
        Horizontal::new([Vertical::new(views).into()]),
        "test_time",
        rerun::blueprint::components::PlayState::Paused,
    );
    let file = RrdFile::create(path, force, title, blueprint)?;
    let rec = file.stream();
    for (k, name) in names.iter().enumerate() {
        let mut series: Vec<(String, &str, [u8; 3], &[f64])> = vec![(
            format!("drift/{name}/measured"),
            "measured",
            MEASURED_RGB,
            &drifts[k],
        )];
        for (i, (label, p)) in preds.iter().enumerate() {
            series.push((
                format!("drift/{name}/pred{i}"),
                label,
                PRED_RGB[i % PRED_RGB.len()],
                &p[k],
            ));
        }
        if let Some((label, p)) = black_box {
            series.push((
                format!("drift/{name}/black_box"),
                label,
                BLACK_BOX_RGB,
                &p[k],
            ));
        }
        for (entity, label, c, values) in series {
            rec.log_static(
                entity.as_str(),
                &rerun::SeriesLines::new()
                    .with_names([label])
                    .with_colors([rerun::Color::from_rgb(c[0], c[1], c[2])])
                    .with_widths([1.0]),
            )
            .map_err(|x| file.err(x))?;
            let rows: Vec<usize> = (0..values.len().min(time_s.len()))
                .filter(|&r| values[r].is_finite())
                .collect();
            let times =
                rerun::TimeColumn::new_duration_secs("test_time", rows.iter().map(|&r| time_s[r]));
            let cols = rerun::Scalars::new(rows.iter().map(|&r| values[r]))
                .columns_of_unit_batches()
                .map_err(|x| file.err(x))?;
            rec.send_columns(entity.as_str(), [times], cols)
                .map_err(|x| file.err(x))?;
        }
    }
    file.finish()
}
