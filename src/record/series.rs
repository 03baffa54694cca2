//! The recorder's time series in bounded buffers: machine poses, sensor readings every thermal
//! step and the errors and readings at the measurement points are gathered in columns of at
//! most [`CHUNK_ROWS`] rows and sent to the stream (`send_columns`) whenever a buffer is full and
//! at the end, so a recording's memory does not grow with the machine time it covers.
//!
//! The chunks of one entity are successive, non-overlapping time ranges; the viewer and
//! `rerun rrd verify` read them as one series. Units: s (times), mm (poses), µm (errors), °C.

use rerun::RecordingStream;

use super::scene::{mm_to_scene, Body, Scene};
use crate::report::norm;

/// Rows gathered per series before they are sent: 4096 rows are a few hundred kB at most, and
/// large enough that the per-chunk cost of the stream and the file's index stays small.
pub const CHUNK_ROWS: usize = 4096;

/// One measurement point as buffered for the error and sensor series.
#[derive(Debug, Clone)]
pub(super) struct PointRow {
    pub(super) time_s: f64,
    pub(super) sample: i64,
    pub(super) diagonal_mm: Option<i64>,
    pub(super) before_um: [f64; 3],
    pub(super) after_um: Option<[f64; 3]>,
    pub(super) readings_degc: Vec<f64>,
}

/// The buffered series of a recorder.
#[derive(Debug, Default)]
pub(super) struct Series {
    /// Machine poses: time and axis position.
    pub(super) motion_t_s: Vec<f64>,
    motion_q_mm: Vec<[f64; 3]>,
    /// The last pose buffered or sent (unchanged poses are skipped).
    last_q_mm: Option<[f64; 3]>,
    /// Sensor readings every thermal step: time, and the values row by row.
    sensor_t_s: Vec<f64>,
    sensor_degc: Vec<f64>,
    /// Measurement points.
    pub(super) points: Vec<PointRow>,
    /// Rows sent so far (poses, readings, points), for the tests of the buffers' bound.
    pub(super) sent_rows: [usize; 3],
}

/// A failure of the stream, as text (the recorder names the file).
pub(super) type SendError = String;

impl Series {
    /// Buffers a pose unless it is the last one again (a dwell).
    pub(super) fn push_pose(&mut self, time_s: f64, q_mm: [f64; 3]) -> bool {
        if self.last_q_mm == Some(q_mm) {
            return false;
        }
        self.last_q_mm = Some(q_mm);
        self.motion_t_s.push(time_s);
        self.motion_q_mm.push(q_mm);
        true
    }

    /// Buffers one set of readings.
    pub(super) fn push_readings(&mut self, time_s: f64, values_degc: &[f64], n_sensors: usize) {
        self.sensor_t_s.push(time_s);
        self.sensor_degc
            .extend((0..n_sensors).map(|i| values_degc.get(i).copied().unwrap_or(f64::NAN)));
    }

    /// Whether any buffer is full.
    pub(super) fn full(&self) -> bool {
        self.motion_t_s.len() >= CHUNK_ROWS
            || self.sensor_t_s.len() >= CHUNK_ROWS
            || self.points.len() >= CHUNK_ROWS
    }

    /// Sends every buffered row and empties the buffers.
    pub(super) fn send(
        &mut self,
        rec: &RecordingStream,
        scene: &Scene,
        sensor_names: &[String],
    ) -> Result<(), SendError> {
        rec.reset_time();
        self.send_poses(rec, scene)?;
        self.send_readings(rec, sensor_names)?;
        self.send_points(rec, sensor_names)
    }

    /// Machine poses (sim_time only): the moving bodies, and the paths and arrows riding the
    /// table.
    fn send_poses(&mut self, rec: &RecordingStream, scene: &Scene) -> Result<(), SendError> {
        if self.motion_t_s.is_empty() {
            return Ok(());
        }
        let e = |x: &dyn std::fmt::Display| x.to_string();
        let times =
            rerun::TimeColumn::new_duration_secs("sim_time", self.motion_t_s.iter().copied());
        for (entity, body) in Body::MOVING
            .iter()
            .map(|b| (b.entity(), *b))
            .chain([("paths", Body::Table), ("errors/vectors", Body::Table)])
        {
            let tr: Vec<[f32; 3]> = self
                .motion_q_mm
                .iter()
                .map(|q| mm_to_scene(scene.body_translation_mm(body, *q)))
                .collect();
            let cols = rerun::Transform3D::update_fields()
                .with_many_translation(tr)
                .columns_of_unit_batches()
                .map_err(|x| e(&x))?;
            rec.send_columns(entity, [times.clone()], cols)
                .map_err(|x| e(&x))?;
        }
        self.sent_rows[0] += self.motion_t_s.len();
        self.motion_t_s.clear();
        self.motion_q_mm.clear();
        Ok(())
    }

    /// Sensor readings every thermal step (sim_time only).
    fn send_readings(
        &mut self,
        rec: &RecordingStream,
        sensor_names: &[String],
    ) -> Result<(), SendError> {
        if self.sensor_t_s.is_empty() || sensor_names.is_empty() {
            self.sensor_t_s.clear();
            self.sensor_degc.clear();
            return Ok(());
        }
        let e = |x: &dyn std::fmt::Display| x.to_string();
        let n = sensor_names.len();
        let times =
            rerun::TimeColumn::new_duration_secs("sim_time", self.sensor_t_s.iter().copied());
        for (i, name) in sensor_names.iter().enumerate() {
            let vals: Vec<f64> = self.sensor_degc.chunks(n).map(|row| row[i]).collect();
            rec.send_columns(
                format!("thermal/sensors/{name}"),
                [times.clone()],
                rerun::Scalars::new(vals)
                    .columns_of_unit_batches()
                    .map_err(|x| e(&x))?,
            )
            .map_err(|x| e(&x))?;
        }
        self.sent_rows[1] += self.sensor_t_s.len();
        self.sensor_t_s.clear();
        self.sensor_degc.clear();
        Ok(())
    }

    /// Errors and sensors at the measurement points, on every timeline.
    fn send_points(
        &mut self,
        rec: &RecordingStream,
        sensor_names: &[String],
    ) -> Result<(), SendError> {
        if self.points.is_empty() {
            return Ok(());
        }
        let e = |x: &dyn std::fmt::Display| x.to_string();
        let points = &self.points;
        let mut index = vec![
            rerun::TimeColumn::new_duration_secs("sim_time", points.iter().map(|r| r.time_s)),
            rerun::TimeColumn::new_sequence("sample", points.iter().map(|r| r.sample)),
        ];
        if points.iter().all(|r| r.diagonal_mm.is_some()) {
            index.push(rerun::TimeColumn::new_sequence(
                "diagonal_mm",
                points.iter().map(|r| r.diagonal_mm.unwrap_or(0)),
            ));
        }
        let value = |e: [f64; 3], c: usize| if c < 3 { e[c] } else { norm(e) };
        for (c, comp) in ["ex", "ey", "ez", "norm"].iter().enumerate() {
            let before: Vec<f64> = points.iter().map(|r| value(r.before_um, c)).collect();
            rec.send_columns(
                format!("errors/before/{comp}"),
                index.clone(),
                rerun::Scalars::new(before)
                    .columns_of_unit_batches()
                    .map_err(|x| e(&x))?,
            )
            .map_err(|x| e(&x))?;
            if points.iter().all(|r| r.after_um.is_some()) {
                let after: Vec<f64> = points
                    .iter()
                    .map(|r| value(r.after_um.unwrap_or([f64::NAN; 3]), c))
                    .collect();
                rec.send_columns(
                    format!("errors/after/{comp}"),
                    index.clone(),
                    rerun::Scalars::new(after)
                        .columns_of_unit_batches()
                        .map_err(|x| e(&x))?,
                )
                .map_err(|x| e(&x))?;
            }
        }
        for (i, name) in sensor_names.iter().enumerate() {
            let vals: Vec<f64> = points
                .iter()
                .map(|r| r.readings_degc.get(i).copied().unwrap_or(f64::NAN))
                .collect();
            rec.send_columns(
                format!("thermal/sensors/{name}"),
                index.clone(),
                rerun::Scalars::new(vals)
                    .columns_of_unit_batches()
                    .map_err(|x| e(&x))?,
            )
            .map_err(|x| e(&x))?;
        }
        self.sent_rows[2] += self.points.len();
        self.points.clear();
        Ok(())
    }
}

/// A path kept to a bounded number of vertices: every `stride`-th vertex offered is kept, and
/// when the path reaches twice its bound every other kept vertex is dropped and the stride
/// doubles, so the kept vertices stay evenly spread over the whole path.
#[derive(Debug, Clone)]
pub(super) struct BoundedPath {
    pub(super) vertices: Vec<[f64; 3]>,
    max: usize,
    stride: usize,
    offered: usize,
}

impl BoundedPath {
    /// An empty path of at most `2 · max` vertices (`max` ≥ 1).
    pub(super) fn new(max: usize) -> Self {
        BoundedPath {
            vertices: Vec::new(),
            max: max.max(1),
            stride: 1,
            offered: 0,
        }
    }

    /// Whether the next vertex offered will be kept (paths offered together stay aligned).
    pub(super) fn keeps_next(&self) -> bool {
        self.offered.is_multiple_of(self.stride)
    }

    /// Offers the next vertex.
    pub(super) fn push(&mut self, v: [f64; 3]) {
        if self.keeps_next() {
            self.vertices.push(v);
            if self.vertices.len() >= 2 * self.max {
                let mut i = 0;
                self.vertices.retain(|_| {
                    i += 1;
                    (i - 1) % 2 == 0
                });
                self.stride *= 2;
            }
        }
        self.offered += 1;
    }

    /// Whether no vertex was kept.
    pub(super) fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// The kept vertices.
    pub(super) fn as_slice(&self) -> &[[f64; 3]] {
        &self.vertices
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bounded_path_keeps_evenly_spread_vertices_under_twice_its_bound() {
        let mut p = BoundedPath::new(100);
        for i in 0..100_000 {
            p.push([f64::from(i), 0.0, 0.0]);
            assert!(p.vertices.len() < 200);
        }
        let xs: Vec<f64> = p.as_slice().iter().map(|v| v[0]).collect();
        assert_eq!(xs[0], 0.0);
        let gaps: Vec<f64> = xs.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps.iter().all(|g| *g == gaps[0]), "{gaps:?}");
        assert!(*xs.last().unwrap() > 99_000.0 - gaps[0], "{xs:?}");
    }

    #[test]
    fn a_short_path_is_kept_whole() {
        let mut p = BoundedPath::new(100);
        for i in 0..150 {
            p.push([f64::from(i), 1.0, 2.0]);
        }
        assert_eq!(p.as_slice().len(), 150);
    }

    #[test]
    fn full_buffers_are_reported_at_the_chunk_size() {
        let mut s = Series::default();
        for i in 0..CHUNK_ROWS {
            assert!(!s.full());
            s.push_pose(i as f64, [i as f64, 0.0, 0.0]);
        }
        assert!(s.full());
        // A repeated pose is not buffered.
        let mut s = Series::default();
        assert!(s.push_pose(0.0, [1.0; 3]));
        assert!(!s.push_pose(1.0, [1.0; 3]));
        assert_eq!(s.motion_t_s.len(), 1);
    }
}
