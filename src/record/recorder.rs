//! The [`Recorder`]: a [`vmc_machine::sim::Observer`] that logs a run into a Rerun stream (entities
//! and timelines in the [module docs](super)).

use std::path::PathBuf;

use rerun::RecordingStream;

use super::scene::{mm_to_scene, screw_counts, temp_rgba, Body, Scene};
use super::series::{BoundedPath, PointRow, Series};
use super::{Diagonal, RecordError, RecordSettings, RrdFile, NODE_TEMP_RANGE_DEGC};
use vmc_machine::sensors::SensorReadings;
use vmc_machine::sim::{EventLevel, Observer, PointRecord, RunStart, SimEvent};

/// Colours.
const GREY: [u8; 4] = [235, 235, 235, 255];
const RED: [u8; 4] = [235, 70, 55, 255];
const GREEN: [u8; 4] = [60, 210, 100, 255];
const MAGENTA: [u8; 4] = [255, 40, 220, 255];

/// Records one or more runs into a Rerun stream (see the module docs for the entities).
pub struct Recorder {
    rec: RecordingStream,
    path: PathBuf,
    settings: RecordSettings,
    scene: Scene,
    nodes: Vec<Option<(Body, [f64; 3])>>,
    node_names: Vec<String>,
    diagonal: Option<Diagonal>,
    measured: bool,
    run_duration_s: f64,
    last_q_mm: [f64; 3],
    last_history_motion_s: f64,
    last_history_sensor_s: f64,
    last_history_nodes_s: f64,
    sensor_names: Vec<String>,
    /// Poses, readings and points, sent in chunks as the run goes.
    pub(super) series: Series,
    next_sample: i64,
    path_commanded: BoundedPath,
    pub(super) path_before: BoundedPath,
    pub(super) path_after: BoundedPath,
    arrows_origin: BoundedPath,
    pub(super) arrows_before: BoundedPath,
    arrows_after: BoundedPath,
    last_path_log_s: f64,
    event_points: Vec<([f64; 3], String)>,
    /// Rows logged one by one (node temperatures, events, paths) since the last flush.
    logs_since_flush: usize,
    error: Option<RecordError>,
}

/// Rows logged one by one between two waits for the file: 1024 rows of node temperatures are a
/// few hundred kB.
const FLUSH_EVERY_LOGS: usize = 1024;

impl Recorder {
    /// A recorder on `file`'s stream for machine `spec`. Logs the static scene at once.
    pub fn new(
        file: &RrdFile,
        spec: &vmc_machine::machine::MachineSpec,
        settings: RecordSettings,
        diagonal: Option<Diagonal>,
    ) -> Result<Self, RecordError> {
        settings.validate()?;
        let scene = Scene::new(spec);
        let node_names: Vec<String> = spec.thermal.nodes.iter().map(|n| n.name.clone()).collect();
        let screws = screw_counts(&node_names);
        let nodes = node_names
            .iter()
            .map(|n| scene.node_place(n, screws))
            .collect();
        let r = Recorder {
            rec: file.stream().clone(),
            path: file.path().to_path_buf(),
            settings,
            scene,
            nodes,
            node_names,
            diagonal,
            measured: true,
            run_duration_s: 0.0,
            last_q_mm: spec.axes.home_mm,
            last_history_motion_s: f64::NEG_INFINITY,
            last_history_sensor_s: f64::NEG_INFINITY,
            last_history_nodes_s: f64::NEG_INFINITY,
            sensor_names: spec.sensors.iter().map(|s| s.name.clone()).collect(),
            series: Series::default(),
            next_sample: 0,
            path_commanded: BoundedPath::new(settings.max_path_vertices),
            path_before: BoundedPath::new(settings.max_path_vertices),
            path_after: BoundedPath::new(settings.max_path_vertices),
            arrows_origin: BoundedPath::new(settings.max_path_vertices),
            arrows_before: BoundedPath::new(settings.max_path_vertices),
            arrows_after: BoundedPath::new(settings.max_path_vertices),
            last_path_log_s: f64::NEG_INFINITY,
            event_points: Vec::new(),
            logs_since_flush: 0,
            error: None,
        };
        r.log_static_scene()?;
        Ok(r)
    }

    fn err(&self, e: impl std::fmt::Display) -> RecordError {
        RecordError::Rerun {
            path: self.path.clone(),
            msg: e.to_string(),
        }
    }

    /// Keeps the first logging error (observer callbacks cannot return one).
    fn keep(&mut self, r: Result<(), RecordError>) {
        if let Err(e) = r {
            self.error.get_or_insert(e);
        }
    }

    fn log_static_scene(&self) -> Result<(), RecordError> {
        let rec = &self.rec;
        let e = |e: rerun::RecordingStreamError| self.err(e);
        rec.log_static("/", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP())
            .map_err(e)?;
        for body in [
            Body::Bed,
            Body::Column,
            Body::Saddle,
            Body::Table,
            Body::Head,
        ] {
            let boxes = self.scene.boxes(body);
            let arch = rerun::Boxes3D::from_centers_and_half_sizes(
                boxes.iter().map(|b| mm_to_scene(b.center_mm)),
                boxes.iter().map(|b| mm_to_scene(b.half_mm)),
            )
            .with_colors(boxes.iter().map(|b| {
                rerun::Color::from_unmultiplied_rgba(b.rgba[0], b.rgba[1], b.rgba[2], b.rgba[3])
            }))
            .with_labels(boxes.iter().map(|b| b.label))
            .with_show_labels(false)
            .with_fill_mode(if body == Body::Head {
                rerun::components::FillMode::MajorWireframe
            } else {
                rerun::components::FillMode::Solid
            });
            rec.log_static(body.entity(), &arch).map_err(e)?;
        }
        let lt = self.scene.tool_len_mm();
        rec.log_static(
            "machine/head/tool",
            &rerun::Cylinders3D::from_lengths_and_radii(
                [(lt * 1e-3) as f32],
                [(self.scene.tool_radius_mm() * 1e-3) as f32],
            )
            .with_centers([mm_to_scene([0.0, 0.0, 0.5 * lt])])
            .with_colors([rerun::Color::from_rgb(230, 200, 60)])
            .with_labels(["tool"])
            .with_show_labels(false),
        )
        .map_err(e)?;
        // Initial pose: home.
        self.rec.reset_time();
        self.log_pose(self.last_q_mm)?;
        let k = self.settings.magnify;
        for (entity, name) in [("errors/before", "before"), ("errors/after", "after")] {
            for (c, comp, rgb) in [
                ("ex", "Ex", [235, 90, 80]),
                ("ey", "Ey", [90, 200, 90]),
                ("ez", "Ez", [80, 140, 240]),
                ("norm", "|E|", [240, 240, 240]),
            ] {
                rec.log_static(
                    format!("{entity}/{c}"),
                    &rerun::SeriesLines::new()
                        .with_names([format!("{comp} {name} (µm)")])
                        .with_colors([rerun::Color::from_rgb(rgb[0], rgb[1], rgb[2])])
                        .with_widths([if c == "norm" { 2.5 } else { 1.5 }]),
                )
                .map_err(e)?;
                rec.log_static(
                    format!("{entity}/{c}"),
                    &rerun::SeriesPoints::new()
                        .with_names([format!("{comp} {name} (µm)")])
                        .with_colors([rerun::Color::from_rgb(rgb[0], rgb[1], rgb[2])])
                        .with_marker_sizes([2.5]),
                )
                .map_err(e)?;
            }
        }
        for name in &self.sensor_names {
            rec.log_static(
                format!("thermal/sensors/{name}"),
                &rerun::SeriesLines::new().with_names([format!("{name} (°C)")]),
            )
            .map_err(e)?;
        }
        rec.log_static(
            "legend",
            &rerun::TextDocument::from_markdown(format!(
                "**Errors magnified ×{k:.0}** in the 3-D view (a 20 µm error is drawn as {:.0} mm). \
                 Grey: commanded path; red: actual path without compensation; green: actual \
                 path with compensation; arrows: error vectors at the measurement points. Thermal \
                 nodes coloured {:.0} °C (blue) → {:.0} °C (red). Scene units: m.",
                20e-3 * k,
                NODE_TEMP_RANGE_DEGC.0,
                NODE_TEMP_RANGE_DEGC.1
            )),
        )
        .map_err(e)?;
        Ok(())
    }

    /// Logs the transforms of the moving bodies, the paths and the arrows for axis position q
    /// at the stream's current time.
    fn log_pose(&self, q_mm: [f64; 3]) -> Result<(), RecordError> {
        for body in Body::MOVING {
            let t = mm_to_scene(self.scene.body_translation_mm(body, q_mm));
            self.rec
                .log(body.entity(), &rerun::Transform3D::from_translation(t))
                .map_err(|e| self.err(e))?;
        }
        let t = mm_to_scene(self.scene.body_translation_mm(Body::Table, q_mm));
        for entity in ["paths", "errors/vectors"] {
            self.rec
                .log(entity, &rerun::Transform3D::from_translation(t))
                .map_err(|e| self.err(e))?;
        }
        Ok(())
    }

    fn set_point_time(&self, row: &PointRow) {
        self.rec.reset_time();
        self.rec.set_duration_secs("sim_time", row.time_s);
        self.rec.set_time_sequence("sample", row.sample);
        if let Some(d) = row.diagonal_mm {
            self.rec.set_time_sequence("diagonal_mm", d);
        }
    }

    fn set_sim_time(&self, time_s: f64) {
        self.rec.reset_time();
        self.rec.set_duration_secs("sim_time", time_s);
    }

    fn thinned(&self, v: &[[f64; 3]]) -> Vec<[f32; 3]> {
        let n = v.len();
        let max = self.settings.max_path_vertices.max(2);
        if n <= max {
            return v.iter().map(|p| mm_to_scene(*p)).collect();
        }
        let stride = n.div_ceil(max);
        let mut out: Vec<[f32; 3]> = v.iter().step_by(stride).map(|p| mm_to_scene(*p)).collect();
        if !(n - 1).is_multiple_of(stride) {
            out.push(mm_to_scene(v[n - 1]));
        }
        out
    }

    fn log_paths(&self) -> Result<(), RecordError> {
        let k = self.settings.magnify;
        let e = |e: rerun::RecordingStreamError| self.err(e);
        let strip = |v: &[[f64; 3]], color: [u8; 4], label: String| {
            rerun::LineStrips3D::new([self.thinned(v)])
                .with_colors([rerun::Color::from_unmultiplied_rgba(
                    color[0], color[1], color[2], color[3],
                )])
                .with_radii([rerun::Radius::new_ui_points(if color == GREY {
                    1.5
                } else {
                    2.5
                })])
                .with_labels([label])
        };
        self.rec
            .log(
                "paths/commanded",
                &strip(self.path_commanded.as_slice(), GREY, "commanded".into()),
            )
            .map_err(e)?;
        self.rec
            .log(
                "paths/actual_uncompensated",
                &strip(
                    self.path_before.as_slice(),
                    RED,
                    format!("actual, uncompensated (errors ×{k:.0})"),
                ),
            )
            .map_err(e)?;
        if !self.path_after.is_empty() {
            self.rec
                .log(
                    "paths/actual_compensated",
                    &strip(
                        self.path_after.as_slice(),
                        GREEN,
                        format!("actual, compensated (errors ×{k:.0})"),
                    ),
                )
                .map_err(e)?;
        }
        if !self.arrows_origin.is_empty() {
            let origins: Vec<[f32; 3]> = self
                .arrows_origin
                .as_slice()
                .iter()
                .map(|p| mm_to_scene(*p))
                .collect();
            self.rec
                .log(
                    "paths/measured",
                    &rerun::Points3D::new(origins.clone())
                        .with_colors([rerun::Color::from_rgb(255, 255, 255)])
                        .with_radii([rerun::Radius::new_ui_points(3.0)]),
                )
                .map_err(e)?;
            self.rec
                .log(
                    "errors/vectors/before",
                    &rerun::Arrows3D::from_vectors(
                        self.arrows_before
                            .as_slice()
                            .iter()
                            .map(|v| mm_to_scene(*v)),
                    )
                    .with_origins(origins.clone())
                    .with_colors([rerun::Color::from_rgb(RED[0], RED[1], RED[2])]),
                )
                .map_err(e)?;
            if !self.arrows_after.is_empty() {
                self.rec
                    .log(
                        "errors/vectors/after",
                        &rerun::Arrows3D::from_vectors(
                            self.arrows_after.as_slice().iter().map(|v| mm_to_scene(*v)),
                        )
                        .with_origins(origins)
                        .with_colors([rerun::Color::from_rgb(GREEN[0], GREEN[1], GREEN[2])]),
                    )
                    .map_err(e)?;
            }
        }
        Ok(())
    }

    fn record_point(
        &mut self,
        point: &PointRecord,
        readings: &SensorReadings,
    ) -> Result<(), RecordError> {
        let k = self.settings.magnify;
        let p = point.commanded_mm;
        let row = PointRow {
            time_s: point.time_s,
            sample: self.next_sample,
            diagonal_mm: self.diagonal.map(|d| d.position_mm(p).round() as i64),
            before_um: point.error_before_um,
            after_um: point.error_after_um,
            readings_degc: readings.values_degc.clone(),
        };
        self.next_sample += 1;
        let shift = |e_um: [f64; 3]| [0, 1, 2].map(|a| p[a] + k * e_um[a] * 1e-3);
        self.path_commanded.push(p);
        self.path_before.push(shift(point.error_before_um));
        if let Some(a) = point.error_after_um {
            self.path_after.push(shift(a));
        }
        if point.at_dwell {
            self.arrows_origin.push(p);
            self.arrows_before
                .push(point.error_before_um.map(|e| k * e * 1e-3));
            if let Some(a) = point.error_after_um {
                self.arrows_after.push(a.map(|e| k * e * 1e-3));
            }
        }
        // Paths are re-logged whole (latest-at shows the growing path): at every dwell point,
        // and during motion at most ~200 times per run.
        let every_s = (self.run_duration_s / 200.0).max(0.25);
        let due = point.at_dwell || point.time_s - self.last_path_log_s >= every_s;
        self.set_point_time(&row);
        if due {
            self.last_path_log_s = point.time_s;
            self.log_paths()?;
            // The pose at the point, on all three timelines.
            self.log_pose(p)?;
            self.count_log()?;
        }
        self.series.points.push(row);
        self.send_if_full()
    }

    fn record_nodes(&mut self, time_s: f64, temps: &[f64]) -> Result<(), RecordError> {
        let mut pos = Vec::new();
        let mut colors = Vec::new();
        let mut labels = Vec::new();
        for (i, place) in self.nodes.iter().enumerate() {
            let (Some((body, local)), Some(t)) = (place, temps.get(i)) else {
                continue;
            };
            let tr = self.scene.body_translation_mm(*body, self.last_q_mm);
            pos.push(mm_to_scene([0, 1, 2].map(|a| local[a] + tr[a])));
            let c = temp_rgba(*t, NODE_TEMP_RANGE_DEGC.0, NODE_TEMP_RANGE_DEGC.1);
            colors.push(rerun::Color::from_rgb(c[0], c[1], c[2]));
            labels.push(format!("{} {:.2} °C", self.node_names[i], t));
        }
        self.set_sim_time(time_s);
        self.rec
            .log(
                "thermal/nodes",
                &rerun::Points3D::new(pos)
                    .with_colors(colors)
                    .with_labels(labels)
                    .with_show_labels(false)
                    .with_radii([rerun::Radius::new_scene_units(0.018)]),
            )
            .map_err(|e| self.err(e))
    }

    fn record_event(&mut self, ev: &SimEvent) -> Result<(), RecordError> {
        let level = match ev.level {
            EventLevel::Info => rerun::TextLogLevel::INFO,
            EventLevel::Warning => rerun::TextLogLevel::WARN,
            EventLevel::Error => rerun::TextLogLevel::ERROR,
        };
        self.set_sim_time(ev.time_s);
        self.rec
            .log(
                "events",
                &rerun::TextLog::new(format!("{}: {}", ev.kind, ev.text)).with_level(level),
            )
            .map_err(|e| self.err(e))?;
        if let Some(p) = ev.position_mm {
            self.event_points
                .push((p, format!("{}: {}", ev.kind, ev.text)));
            let (pts, labels): (Vec<[f32; 3]>, Vec<String>) = self
                .event_points
                .iter()
                .map(|(p, l)| (mm_to_scene(*p), l.clone()))
                .unzip();
            self.rec
                .log(
                    "paths/events",
                    &rerun::Points3D::new(pts)
                        .with_labels(labels)
                        .with_colors([rerun::Color::from_rgb(MAGENTA[0], MAGENTA[1], MAGENTA[2])])
                        .with_radii([rerun::Radius::new_ui_points(8.0)]),
                )
                .map_err(|e| self.err(e))?;
        }
        Ok(())
    }

    /// Sends the buffered series once one of its buffers is full.
    fn send_if_full(&mut self) -> Result<(), RecordError> {
        if !self.series.full() {
            return Ok(());
        }
        self.series
            .send(&self.rec, &self.scene, &self.sensor_names)
            .map_err(|x| self.err(x))?;
        self.flush()
    }

    /// Waits until everything logged so far is in the file, so that what the stream holds in
    /// flight stays bounded however fast the simulation produces it.
    fn flush(&mut self) -> Result<(), RecordError> {
        self.logs_since_flush = 0;
        self.rec.flush_blocking().map_err(|x| self.err(x))
    }

    /// Counts one logged row; flushes every [`FLUSH_EVERY_LOGS`].
    fn count_log(&mut self) -> Result<(), RecordError> {
        self.logs_since_flush += 1;
        if self.logs_since_flush >= FLUSH_EVERY_LOGS {
            return self.flush();
        }
        Ok(())
    }

    /// Sends the buffered series (machine motion, errors, sensors), the report (markdown) and
    /// returns the first error met while logging, if any. Call before [`RrdFile::finish`].
    pub fn finish(mut self, report_markdown: Option<&str>) -> Result<(), RecordError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.series
            .send(&self.rec, &self.scene, &self.sensor_names)
            .map_err(|x| self.err(x))?;
        let rec = &self.rec;
        let e = |e: &dyn std::fmt::Display| self.err(e);
        if let Some(md) = report_markdown {
            rec.log_static("report", &rerun::TextDocument::from_markdown(md))
                .map_err(|x| e(&x))?;
        }
        Ok(())
    }
}

impl Observer for Recorder {
    fn on_run_start(&mut self, start: &RunStart) {
        self.measured = start.measured;
        self.run_duration_s = start.duration_s;
        self.last_path_log_s = f64::NEG_INFINITY;
        let ev = SimEvent {
            time_s: start.time_s,
            level: EventLevel::Info,
            kind: "start".into(),
            text: format!("{} ({:.0} s)", start.label, start.duration_s),
            position_mm: None,
        };
        let r = self.record_event(&ev);
        self.keep(r);
    }

    fn on_point(&mut self, point: &PointRecord, readings: &SensorReadings) {
        let r = self.record_point(point, readings);
        self.keep(r);
    }

    fn on_thermal_step(&mut self, time_s: f64, readings: &SensorReadings) {
        if !self.measured {
            if time_s - self.last_history_sensor_s < self.settings.history_sample_s - 1e-9 {
                return;
            }
            self.last_history_sensor_s = time_s;
        }
        self.series
            .push_readings(time_s, &readings.values_degc, self.sensor_names.len());
        let r = self.send_if_full();
        self.keep(r);
    }

    fn on_node_temps(&mut self, time_s: f64, node_temps_degc: &[f64]) {
        // Nodes: every second during measured runs, every history interval otherwise.
        let every = if self.measured {
            1.0
        } else {
            self.settings.history_sample_s
        };
        if time_s - self.last_history_nodes_s < every - 1e-9 {
            return;
        }
        self.last_history_nodes_s = time_s;
        let r = self
            .record_nodes(time_s, node_temps_degc)
            .and_then(|()| self.count_log());
        self.keep(r);
    }

    fn motion_sample_interval_s(&self) -> Option<f64> {
        Some(if self.measured {
            self.settings.motion_sample_s
        } else {
            self.settings.history_sample_s
        })
    }

    fn on_motion_sample(&mut self, time_s: f64, axis_mm: [f64; 3]) {
        self.last_q_mm = axis_mm;
        if !self.measured {
            if time_s - self.last_history_motion_s < self.settings.history_sample_s - 1e-9 {
                return;
            }
            self.last_history_motion_s = time_s;
        }
        // Unchanged poses (dwells) are skipped: the viewer holds the latest pose.
        if self.series.push_pose(time_s, axis_mm) {
            let r = self.send_if_full();
            self.keep(r);
        }
    }

    fn on_event(&mut self, event: &SimEvent) {
        let r = self.record_event(event).and_then(|()| self.count_log());
        self.keep(r);
    }
}
