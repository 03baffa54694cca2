//! The [`Recorder`]: a [`vmc_machine::sim::Observer`] that logs a run into a Rerun stream (entities
//! and timelines in the [module docs](super)).

use std::path::PathBuf;

use rerun::RecordingStream;

use super::scene::{mm_to_scene, screw_counts, temp_rgba, Body, Scene};
use super::{Diagonal, RecordError, RecordSettings, RrdFile, NODE_TEMP_RANGE_DEGC};
use crate::report::norm;
use vmc_machine::sensors::SensorReadings;
use vmc_machine::sim::{EventLevel, Observer, PointRecord, RunStart, SimEvent};

/// One measurement point as buffered for the error and sensor series.
#[derive(Debug, Clone)]
pub(super) struct PointRow {
    time_s: f64,
    sample: i64,
    pub(super) diagonal_mm: Option<i64>,
    before_um: [f64; 3],
    after_um: Option<[f64; 3]>,
    readings_degc: Vec<f64>,
}

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
    pub(super) motion_t_s: Vec<f64>,
    motion_q_mm: Vec<[f64; 3]>,
    last_history_motion_s: f64,
    last_history_sensor_s: f64,
    last_history_nodes_s: f64,
    sensor_names: Vec<String>,
    sensor_t_s: Vec<f64>,
    sensor_degc: Vec<Vec<f64>>,
    pub(super) points: Vec<PointRow>,
    next_sample: i64,
    path_commanded: Vec<[f64; 3]>,
    pub(super) path_before: Vec<[f64; 3]>,
    pub(super) path_after: Vec<[f64; 3]>,
    arrows_origin: Vec<[f64; 3]>,
    pub(super) arrows_before: Vec<[f64; 3]>,
    arrows_after: Vec<[f64; 3]>,
    last_path_log_s: f64,
    event_points: Vec<([f64; 3], String)>,
    error: Option<RecordError>,
}

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
            motion_t_s: Vec::new(),
            motion_q_mm: Vec::new(),
            last_history_motion_s: f64::NEG_INFINITY,
            last_history_sensor_s: f64::NEG_INFINITY,
            last_history_nodes_s: f64::NEG_INFINITY,
            sensor_names: spec.sensors.iter().map(|s| s.name.clone()).collect(),
            sensor_t_s: Vec::new(),
            sensor_degc: Vec::new(),
            points: Vec::new(),
            next_sample: 0,
            path_commanded: Vec::new(),
            path_before: Vec::new(),
            path_after: Vec::new(),
            arrows_origin: Vec::new(),
            arrows_before: Vec::new(),
            arrows_after: Vec::new(),
            last_path_log_s: f64::NEG_INFINITY,
            event_points: Vec::new(),
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
                &strip(&self.path_commanded, GREY, "commanded".into()),
            )
            .map_err(e)?;
        self.rec
            .log(
                "paths/actual_uncompensated",
                &strip(
                    &self.path_before,
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
                        &self.path_after,
                        GREEN,
                        format!("actual, compensated (errors ×{k:.0})"),
                    ),
                )
                .map_err(e)?;
        }
        if !self.arrows_origin.is_empty() {
            let origins: Vec<[f32; 3]> =
                self.arrows_origin.iter().map(|p| mm_to_scene(*p)).collect();
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
                        self.arrows_before.iter().map(|v| mm_to_scene(*v)),
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
                            self.arrows_after.iter().map(|v| mm_to_scene(*v)),
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
        }
        self.points.push(row);
        Ok(())
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

    /// Sends the buffered series (machine motion, errors, sensors), the report (markdown) and
    /// returns the first error met while logging, if any. Call before [`RrdFile::finish`].
    pub fn finish(mut self, report_markdown: Option<&str>) -> Result<(), RecordError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        let rec = &self.rec;
        let e = |e: &dyn std::fmt::Display| self.err(e);
        rec.reset_time();
        // Machine motion (sim_time only).
        if !self.motion_t_s.is_empty() {
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
                    .map(|q| mm_to_scene(self.scene.body_translation_mm(body, *q)))
                    .collect();
                let cols = rerun::Transform3D::update_fields()
                    .with_many_translation(tr)
                    .columns_of_unit_batches()
                    .map_err(|x| e(&x))?;
                rec.send_columns(entity, [times.clone()], cols)
                    .map_err(|x| e(&x))?;
            }
        }
        // Sensor readings every thermal step (sim_time only) …
        if !self.sensor_t_s.is_empty() {
            let times =
                rerun::TimeColumn::new_duration_secs("sim_time", self.sensor_t_s.iter().copied());
            for (i, name) in self.sensor_names.iter().enumerate() {
                let vals: Vec<f64> = self
                    .sensor_degc
                    .iter()
                    .map(|v| v.get(i).copied().unwrap_or(f64::NAN))
                    .collect();
                rec.send_columns(
                    format!("thermal/sensors/{name}"),
                    [times.clone()],
                    rerun::Scalars::new(vals)
                        .columns_of_unit_batches()
                        .map_err(|x| e(&x))?,
                )
                .map_err(|x| e(&x))?;
            }
        }
        // … and errors and sensors at the measurement points, on every timeline.
        if !self.points.is_empty() {
            let mut index = vec![
                rerun::TimeColumn::new_duration_secs(
                    "sim_time",
                    self.points.iter().map(|r| r.time_s),
                ),
                rerun::TimeColumn::new_sequence("sample", self.points.iter().map(|r| r.sample)),
            ];
            if self.points.iter().all(|r| r.diagonal_mm.is_some()) {
                index.push(rerun::TimeColumn::new_sequence(
                    "diagonal_mm",
                    self.points.iter().map(|r| r.diagonal_mm.unwrap_or(0)),
                ));
            }
            let comps = ["ex", "ey", "ez", "norm"];
            let value = |e: [f64; 3], c: usize| if c < 3 { e[c] } else { norm(e) };
            for (c, comp) in comps.iter().enumerate() {
                let before: Vec<f64> = self.points.iter().map(|r| value(r.before_um, c)).collect();
                rec.send_columns(
                    format!("errors/before/{comp}"),
                    index.clone(),
                    rerun::Scalars::new(before)
                        .columns_of_unit_batches()
                        .map_err(|x| e(&x))?,
                )
                .map_err(|x| e(&x))?;
                if self.points.iter().all(|r| r.after_um.is_some()) {
                    let after: Vec<f64> = self
                        .points
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
            for (i, name) in self.sensor_names.iter().enumerate() {
                let vals: Vec<f64> = self
                    .points
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
        }
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
        self.sensor_t_s.push(time_s);
        self.sensor_degc.push(readings.values_degc.clone());
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
        let r = self.record_nodes(time_s, node_temps_degc);
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
        // Skip unchanged poses (dwells): the viewer holds the latest pose.
        if self.motion_q_mm.last() == Some(&axis_mm) {
            return;
        }
        self.motion_t_s.push(time_s);
        self.motion_q_mm.push(axis_mm);
    }

    fn on_event(&mut self, event: &SimEvent) {
        let r = self.record_event(event);
        self.keep(r);
    }
}
