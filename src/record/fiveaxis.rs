//! Recordings of the five-axis machine: `run`, `probe-campaign` and `identify` with `--rrd`.
//!
//! # Scene
//! The bed frame, Z up, metres ([`super::scene::mm_to_scene`]). Each element of the chain is an
//! entity whose transform is its nominal pose relative to its parent,
//! [`vmc_identify::htm::parent_from_element`] with zero errors, nested from the bed outwards:
//! `machine/X/Y/A/C/workpiece` for the trunnion `w C A Y X b Z t` (the slides move by `−q`, the
//! table turns by `−θ`, see [`vmc_identify::chain`]), `machine/Z/tip` on the tool side. Every
//! element frame coincides with the bed frame at machine zero, so each body is drawn in bed
//! coordinates at zero: illustrative boxes sized from the rotary axes' lines (slides, the A
//! cradle, a Ø 400 mm C table), the reference spheres on the table, the spindle and the tool.
//!
//! What is drawn in the workpiece frame rides on the table:
//!
//! | recording | entity (under `…/workpiece/`) | content |
//! |---|---|---|
//! | run | `paths/commanded` | commanded tool-tip path (grey) |
//! | run | `paths/actual_uncompensated`, `paths/actual_compensated` | through `p + K·E` at the points (red, green) |
//! | run | `errors/before`, `errors/after` | error vectors ×K at the points (red, green) |
//! | probe-campaign | `probed/points` | the triggers of each configuration |
//! | probe-campaign | `probed/centre_error` | fitted − nominal centre ×K (orange) |
//! | identify | `heldout/before`, `heldout/after` | the held-out error field ×K (red, green) |
//!
//! Time series: `errors/{before,after}/{ex,ey,ez,norm}` (µm) and `axes/<letter>_deg`.
//! Timelines: `sim_time` (run), `configuration` (probe-campaign), `pose` (identify).

use std::path::Path;

use nalgebra::{Isometry3, Vector3};
use rerun::blueprint::{
    Blueprint, Horizontal, Spatial3DView, TextDocumentView, TimeSeriesView, Vertical,
};

use super::layout::framed;
use super::scene::mm_to_scene;
use super::{RecordError, RrdFile};
use vmc_identify::chain::{Axis, Geometry, Pose};
use vmc_identify::errors::ErrorState;
use vmc_identify::htm::{parent_from_element, tip_in_workpiece_mm};
use vmc_machine::fiveaxis::heldout::JudgedPose;
use vmc_machine::fiveaxis::plan::FivePlan;
use vmc_machine::fiveaxis::probe::ProbedSphere;
use vmc_machine::fiveaxis::run::{pose_of, FivePoint};
use vmc_machine::fiveaxis::FiveAxisSpec;

const GREY: [u8; 3] = [170, 170, 170];
const RED: [u8; 3] = [230, 60, 50];
const GREEN: [u8; 3] = [60, 200, 90];
const ORANGE: [u8; 3] = [250, 160, 30];
/// Most machine poses drawn along a run (longer runs are sampled more coarsely).
const MAX_POSES: f64 = 4000.0;

fn color(c: [u8; 3]) -> rerun::Color {
    rerun::Color::from_rgb(c[0], c[1], c[2])
}

fn scene_vec(v_mm: Vector3<f64>) -> [f32; 3] {
    mm_to_scene([v_mm[0], v_mm[1], v_mm[2]])
}

/// The chain's entities and the stream.
struct Scene<'a> {
    rrd: &'a RrdFile,
    geom: Geometry,
    /// Entity path of each chain element, by element index.
    entity: Vec<String>,
    /// The workpiece frame's entity.
    workpiece: String,
}

impl<'a> Scene<'a> {
    fn new(rrd: &'a RrdFile, spec: &FiveAxisSpec) -> Result<Self, RecordError> {
        let geom = spec.geometry();
        let n = geom.chain.elements().len();
        let nw = geom.chain.n_workpiece_side();
        let mut entity = vec![String::new(); n];
        let mut path = String::from("machine");
        for i in (0..nw).rev() {
            path = format!("{path}/{}", geom.chain.elements()[i].letter());
            entity[i] = path.clone();
        }
        let workpiece = format!("{path}/workpiece");
        let mut path = String::from("machine");
        for (i, e) in entity.iter_mut().enumerate().skip(nw) {
            path = format!("{path}/{}", geom.chain.elements()[i].letter());
            *e = path.clone();
        }
        let scene = Scene {
            rrd,
            geom,
            entity,
            workpiece,
        };
        scene.log_static(spec)?;
        Ok(scene)
    }

    fn log_static(&self, spec: &FiveAxisSpec) -> Result<(), RecordError> {
        let rec = self.rrd.stream();
        let e = |e: rerun::RecordingStreamError| self.rrd.err(e);
        rec.log_static("/", &rerun::ViewCoordinates::RIGHT_HAND_Z_UP())
            .map_err(e)?;
        let z = |axis: char| {
            spec.rotary
                .iter()
                .find(|r| r.axis.starts_with(axis))
                .map(|r| r.point_mm[2])
        };
        let z_table = z('C').or(z('B')).unwrap_or(-450.0);
        let z_low = z('A').unwrap_or(z_table - 50.0).min(z_table - 50.0);
        let boxes = |entity: &str, items: &[([f64; 3], [f64; 3], [u8; 3])]| {
            rec.log_static(
                entity,
                &rerun::Boxes3D::from_centers_and_half_sizes(
                    items.iter().map(|b| mm_to_scene(b.0)),
                    items.iter().map(|b| mm_to_scene(b.1)),
                )
                .with_colors(items.iter().map(|b| color(b.2)))
                .with_fill_mode(rerun::components::FillMode::Solid),
            )
            .map_err(e)
        };
        boxes(
            "machine",
            &[(
                [0.0, 0.0, z_low - 260.0],
                [420.0, 380.0, 40.0],
                [90, 90, 100],
            )],
        )?;
        let nw = self.geom.chain.n_workpiece_side();
        for (i, el) in self.geom.chain.elements().iter().enumerate() {
            let entity = &self.entity[i];
            match el {
                Axis::Linear(_) if i < nw => {
                    let level = if i + 1 == nw { 200.0 } else { 170.0 };
                    boxes(
                        entity,
                        &[(
                            [0.0, 0.0, z_low - level],
                            [300.0, 260.0, 15.0],
                            [120, 125, 140],
                        )],
                    )?;
                }
                Axis::Linear(_) => boxes(
                    entity,
                    &[([0.0, 0.0, 110.0], [70.0, 70.0, 100.0], [120, 125, 140])],
                )?,
                Axis::Rotary(r) if r.letter() == 'C' => {
                    rec.log_static(
                        entity.as_str(),
                        &rerun::Cylinders3D::from_lengths_and_radii([0.02], [0.2])
                            .with_centers([mm_to_scene([0.0, 0.0, z_table - 10.0])])
                            .with_colors([color([160, 165, 175])]),
                    )
                    .map_err(e)?;
                }
                Axis::Rotary(_) => boxes(
                    entity,
                    &[
                        (
                            [0.0, 0.0, z_table - 35.0],
                            [230.0, 160.0, 15.0],
                            [140, 150, 170],
                        ),
                        ([-245.0, 0.0, z_low], [15.0, 60.0, 50.0], [140, 150, 170]),
                        ([245.0, 0.0, z_low], [15.0, 60.0, 50.0], [140, 150, 170]),
                    ],
                )?,
            }
        }
        let datum = Vector3::from(self.geom.datum_mm);
        rec.log_static(
            self.workpiece.as_str(),
            &rerun::Transform3D::from_translation(scene_vec(datum)),
        )
        .map_err(e)?;
        let r = (spec.sphere.radius_mm * 1e-3) as f32;
        let targets = spec.sphere_targets_w_mm();
        rec.log_static(
            format!("{}/spheres", self.workpiece),
            &rerun::Ellipsoids3D::from_centers_and_radii(
                targets.iter().map(|c| mm_to_scene(*c)),
                targets.iter().map(|_| r),
            )
            .with_colors([color([220, 220, 230])])
            .with_fill_mode(rerun::components::FillMode::Solid),
        )
        .map_err(e)?;
        let tool = Vector3::from(self.geom.tool_offset_mm);
        if let Some(last) = self.entity.last() {
            rec.log_static(
                format!("{last}/tip"),
                &rerun::Transform3D::from_translation(scene_vec(tool)),
            )
            .map_err(e)?;
            rec.log_static(
                format!("{last}/tool"),
                &rerun::Arrows3D::from_vectors([scene_vec(tool)])
                    .with_colors([color([230, 200, 60])])
                    .with_radii([0.004]),
            )
            .map_err(e)?;
        }
        Ok(())
    }

    /// Logs every element's nominal transform at `pose` at the stream's current time.
    fn log_pose(&self, pose: &Pose) -> Result<(), RecordError> {
        let zero = ErrorState::default();
        for (i, entity) in self.entity.iter().enumerate() {
            let m: Isometry3<f64> = parent_from_element(&self.geom, i, pose, &zero);
            let q = m.rotation.coords;
            self.rrd
                .stream()
                .log(
                    entity.as_str(),
                    &rerun::Transform3D::from_translation_rotation(
                        scene_vec(m.translation.vector),
                        rerun::datatypes::Quaternion::from_xyzw(
                            [q[0], q[1], q[2], q[3]].map(|v| v as f32),
                        ),
                    ),
                )
                .map_err(|e| self.rrd.err(e))?;
        }
        for (k, r) in self.geom.rotary.iter().enumerate() {
            self.rrd
                .stream()
                .log(
                    format!("axes/{}_deg", r.axis.letter().to_ascii_lowercase()),
                    &rerun::Scalars::single(pose.rotary_deg[k]),
                )
                .map_err(|e| self.rrd.err(e))?;
        }
        Ok(())
    }

    fn log_in_workpiece(
        &self,
        what: &str,
        arch: &impl rerun::AsComponents,
        at_static: bool,
    ) -> Result<(), RecordError> {
        let entity = format!("{}/{what}", self.workpiece);
        let rec = self.rrd.stream();
        if at_static {
            rec.log_static(entity, arch)
        } else {
            rec.log(entity, arch)
        }
        .map_err(|e| self.rrd.err(e))
    }

    fn log_errors(&self, entity: &str, e_um: [f64; 3]) -> Result<(), RecordError> {
        let n = crate::report::norm(e_um);
        for (c, v) in ["ex", "ey", "ez", "norm"]
            .iter()
            .zip([e_um[0], e_um[1], e_um[2], n])
        {
            self.rrd
                .stream()
                .log(format!("errors/{entity}/{c}"), &rerun::Scalars::single(v))
                .map_err(|e| self.rrd.err(e))?;
        }
        Ok(())
    }

    fn document(&self, entity: &str, markdown: String) -> Result<(), RecordError> {
        self.rrd
            .stream()
            .log_static(entity, &rerun::TextDocument::from_markdown(markdown))
            .map_err(|e| self.rrd.err(e))
    }
}

fn arrows(
    origins_mm: &[[f64; 3]],
    vectors_um: &[[f64; 3]],
    magnify: f64,
    c: [u8; 3],
) -> rerun::Arrows3D {
    rerun::Arrows3D::from_vectors(
        vectors_um
            .iter()
            .map(|v| mm_to_scene(v.map(|x| x * 1e-3 * magnify))),
    )
    .with_origins(origins_mm.iter().map(|p| mm_to_scene(*p)))
    .with_colors([color(c)])
}

fn strip(points_mm: impl Iterator<Item = [f64; 3]>, c: [u8; 3]) -> rerun::LineStrips3D {
    let v: Vec<[f32; 3]> = points_mm.map(mm_to_scene).collect();
    rerun::LineStrips3D::new([v])
        .with_colors([color(c)])
        .with_radii([rerun::Radius::new_ui_points(1.5)])
}

/// The layout: the 3-D scene beside the time series and the report.
fn blueprint(title: &str, magnify: f64, timeline: &str, series: &[(&str, &str)]) -> Blueprint {
    let scene = Spatial3DView::new(format!("{title} (errors ×{magnify:.0})")).with_origin("/");
    let mut right: Vec<rerun::blueprint::ContainerLike> = series
        .iter()
        .map(|(name, origin)| TimeSeriesView::new(*name).with_origin(*origin).into())
        .collect();
    right.push(
        TextDocumentView::new("Report")
            .with_origin("/report")
            .into(),
    );
    framed(
        Horizontal::new([scene.into(), Vertical::new(right).into()]).with_column_shares([1.4, 1.0]),
        timeline,
    )
}

fn legend(magnify: f64, colours: &str) -> String {
    format!(
        "**Errors magnified ×{magnify:.0}** (a 20 µm error is drawn as {:.0} mm). {colours} \
         The machine is drawn in its nominal geometry (illustrative boxes); scene units: m.",
        20e-3 * magnify
    )
}

/// The recording of a five-axis `run`: the machine moving through the plan, the commanded and
/// actual tool paths and the error vectors in the workpiece frame; gives the file's size.
///
/// # Errors
/// The recording cannot be written.
#[allow(clippy::too_many_arguments)]
pub fn record_run(
    path: &Path,
    force: bool,
    id: &str,
    magnify: f64,
    spec: &FiveAxisSpec,
    plan: &FivePlan,
    points: &[FivePoint],
    report: &str,
) -> Result<u64, RecordError> {
    let series = [
        (
            "Errors before compensation Ex, Ey, Ez, |E| (µm)",
            "/errors/before",
        ),
        ("Errors after compensation (µm)", "/errors/after"),
        ("Rotary axes (degrees)", "/axes"),
    ];
    let rrd = RrdFile::create(
        path,
        force,
        id,
        blueprint("Five-axis run", magnify, "sim_time", &series),
    )?;
    let scene = Scene::new(&rrd, spec)?;
    let geom = &scene.geom;
    let rec = rrd.stream();
    let zero = ErrorState::default();
    let duration_s = plan.duration_s();
    let dt_s = (duration_s / MAX_POSES).max(0.05);
    let n = (duration_s / dt_s).ceil() as usize;
    let mut commanded = Vec::with_capacity(n + 1);
    for k in 0..=n {
        let t_s = (k as f64 * dt_s).min(duration_s);
        let (q_mm, abc_deg) = plan.joints_at(t_s);
        let pose = pose_of(geom, q_mm, abc_deg);
        rec.set_duration_secs("sim_time", t_s);
        scene.log_pose(&pose)?;
        let tip = tip_in_workpiece_mm(geom, &pose, &zero);
        commanded.push([tip[0], tip[1], tip[2]]);
    }
    scene.log_in_workpiece("paths/commanded", &strip(commanded.into_iter(), GREY), true)?;
    let at = |p: &FivePoint, e: [f64; 3]| [0, 1, 2].map(|i| p.tip_w_mm[i] + magnify * 1e-3 * e[i]);
    scene.log_in_workpiece(
        "paths/actual_uncompensated",
        &strip(points.iter().map(|p| at(p, p.error_before_um)), RED),
        true,
    )?;
    let after: Vec<&FivePoint> = points
        .iter()
        .filter(|p| p.error_after_um.is_some())
        .collect();
    if !after.is_empty() {
        scene.log_in_workpiece(
            "paths/actual_compensated",
            &strip(
                after
                    .iter()
                    .map(|p| at(p, p.error_after_um.unwrap_or_default())),
                GREEN,
            ),
            true,
        )?;
    }
    let mut origins = Vec::new();
    let (mut before_v, mut after_v) = (Vec::new(), Vec::new());
    for p in points {
        rec.set_duration_secs("sim_time", p.commanded.time_s);
        origins.push(p.tip_w_mm);
        before_v.push(p.error_before_um);
        scene.log_errors("before", p.error_before_um)?;
        scene.log_in_workpiece(
            "errors/before",
            &arrows(&origins, &before_v, magnify, RED),
            false,
        )?;
        if let Some(a) = p.error_after_um {
            after_v.push(a);
            scene.log_errors("after", a)?;
            scene.log_in_workpiece(
                "errors/after",
                &arrows(&origins, &after_v, magnify, GREEN),
                false,
            )?;
        }
    }
    scene.document(
        "report",
        format!(
            "# vmc-twin run (five-axis)\n\n{}\n\n```text\n{report}```\n",
            legend(
                magnify,
                "Grey: commanded tool-tip path; red: actual without compensation; green: with the identified model; arrows: error vectors at the points, in the workpiece frame (they ride on the table)."
            )
        ),
    )?;
    drop(scene);
    rrd.finish()
}

/// The recording of a `probe-campaign`: at each configuration the machine's pose, the sphere's
/// triggers and the fitted centre's error (×K) in the workpiece frame; gives the file's size.
///
/// # Errors
/// The recording cannot be written.
#[allow(clippy::too_many_arguments)]
pub fn record_probing(
    path: &Path,
    force: bool,
    id: &str,
    magnify: f64,
    spec: &FiveAxisSpec,
    rows: &[ProbedSphere],
    report: &str,
) -> Result<u64, RecordError> {
    let series = [
        (
            "Fitted − nominal sphere centre, workpiece frame (µm)",
            "/errors/before",
        ),
        ("Rotary axes (degrees)", "/axes"),
    ];
    let rrd = RrdFile::create(
        path,
        force,
        id,
        blueprint("Probing campaign", magnify, "configuration", &series),
    )?;
    let scene = Scene::new(&rrd, spec)?;
    let geom = &scene.geom;
    let rec = rrd.stream();
    let zero = ErrorState::default();
    let (mut centres, mut offsets) = (Vec::new(), Vec::new());
    for (k, row) in rows.iter().enumerate() {
        rec.set_time_sequence("configuration", k as i64);
        let at = |q: [f64; 3]| {
            let pose = Pose {
                linear_mm: q,
                rotary_deg: row.rotary_deg,
            };
            tip_in_workpiece_mm(geom, &pose, &zero)
        };
        scene.log_pose(&Pose {
            linear_mm: row.nominal_mm,
            rotary_deg: row.rotary_deg,
        })?;
        let triggers: Vec<[f32; 3]> = row
            .points_mm
            .iter()
            .map(|q| scene_vec(at([q[0], q[1], q[2]])))
            .collect();
        scene.log_in_workpiece(
            "probed/points",
            &rerun::Points3D::new(triggers)
                .with_colors([color(ORANGE)])
                .with_radii([rerun::Radius::new_ui_points(4.0)]),
            false,
        )?;
        let c = row.fit.centre_mm;
        let offset_um = (at([c[0], c[1], c[2]]) - Vector3::from(row.target_w_mm)) * 1e3;
        centres.push(row.target_w_mm);
        offsets.push([offset_um[0], offset_um[1], offset_um[2]]);
        scene.log_errors("before", offsets[offsets.len() - 1])?;
        scene.log_in_workpiece(
            "probed/centre_error",
            &arrows(&centres, &offsets, magnify, ORANGE),
            false,
        )?;
    }
    scene.document(
        "report",
        format!(
            "# vmc-twin probe-campaign\n\n{}\n\n```text\n{report}```\n",
            legend(
                magnify,
                "Orange points: the probe's triggers at this configuration (on the contact sphere); orange arrows: fitted minus nominal centre of each probed sphere, in the workpiece frame."
            )
        ),
    )?;
    drop(scene);
    rrd.finish()
}

/// The recording of `identify`: the held-out error field before (red) and after (green)
/// compensation with the identified model, as arrows ×K at the target points in the workpiece
/// frame, the machine posed at each held-out pose; gives the file's size.
///
/// # Errors
/// The recording cannot be written.
#[allow(clippy::too_many_arguments)]
pub fn record_heldout(
    path: &Path,
    force: bool,
    id: &str,
    magnify: f64,
    spec: &FiveAxisSpec,
    poses: &[JudgedPose],
    report: &str,
) -> Result<u64, RecordError> {
    let series = [
        ("Held-out error before compensation (µm)", "/errors/before"),
        ("Held-out error after compensation (µm)", "/errors/after"),
        ("Rotary axes (degrees)", "/axes"),
    ];
    let rrd = RrdFile::create(
        path,
        force,
        id,
        blueprint("Held-out error field", magnify, "pose", &series),
    )?;
    let scene = Scene::new(&rrd, spec)?;
    let geom = &scene.geom;
    let rec = rrd.stream();
    let origins: Vec<[f64; 3]> = poses.iter().map(|p| p.target_w_mm).collect();
    let before: Vec<[f64; 3]> = poses.iter().map(|p| p.before_um).collect();
    let after: Vec<[f64; 3]> = poses.iter().map(|p| p.after_um).collect();
    scene.log_in_workpiece(
        "heldout/before",
        &arrows(&origins, &before, magnify, RED),
        true,
    )?;
    scene.log_in_workpiece(
        "heldout/after",
        &arrows(&origins, &after, magnify, GREEN),
        true,
    )?;
    for (k, p) in poses.iter().enumerate() {
        rec.set_time_sequence("pose", k as i64);
        let q = vmc_identify::inverse::nominal_linear_axes(
            geom,
            p.rotary_deg,
            Vector3::from(p.target_w_mm),
        );
        scene.log_pose(&Pose {
            linear_mm: q,
            rotary_deg: p.rotary_deg,
        })?;
        scene.log_errors("before", p.before_um)?;
        scene.log_errors("after", p.after_um)?;
    }
    scene.document(
        "report",
        format!(
            "# vmc-twin identify\n\n{}\n\n```text\n{report}```\n",
            legend(
                magnify,
                "Red arrows: the volumetric error at each held-out target point without compensation; green: with the identified model (workpiece frame, every pose at once)."
            )
        ),
    )?;
    drop(scene);
    rrd.finish()
}
