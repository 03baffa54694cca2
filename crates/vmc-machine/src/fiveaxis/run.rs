//! A G-code program on the five-axis machine: plan, sample, and the volumetric error at each
//! sample, before and after compensation with an identified model.
//!
//! # Model
//! - **Program and planning**: see [`super::plan`]. Without G43.4 `X Y Z` are the linear axes'
//!   positions (machine coordinates, work offsets G54…G59 from the machine file), as a
//!   post-processor for this machine's kinematics writes them; under G43.4 the tool tip in the
//!   part frame, turned into axis positions by the nominal inverse kinematics. `A`, `B`, `C`
//!   are the rotary axes' angles in degrees.
//! - **Sampling** as the three-axis `run`: the middle of every dwell (G4), and with
//!   [`Sampling::EveryCycle`] every interpolation cycle during motion.
//! - **Error.** At commanded axes `(q, θ)` the commanded tool tip is the nominal chain's
//!   `p = tip_w(q, θ; 0)` and the error `E = tip_w(q, θ; e(q, θ)) − p`, both in the workpiece
//!   frame (exact homogeneous transforms, [`vmc_identify::htm`]), `e` the machine's errors at
//!   the pose. The tool-axis error is the angle between the actual tool axis
//!   `a(q, θ; e)` and the commanded one `a* = a(q, θ; 0)`, relative to the workpiece.
//! - **Compensation** (with a model `ê`, [`Controller`]): with the linear axes only, the
//!   controller keeps `θ` and commands the `q'` that solve `tip_w(q', θ; ê(q', θ)) = p`
//!   (Newton, [`vmc_identify::inverse::linear_axes_for`]); with the rotary axes too, it also
//!   turns them to `θ'` so that the model's tool axis lies along `a*`, and solves `q'` at
//!   `θ'` ([`vmc_identify::inverse_pose::axes_for_tool_pose`]). The errors after are the
//!   machine's at the commanded `(q', θ')`. The controller sees `ê` only.
//!
//! There is no thermal model on this machine: the errors are geometric and do not change over
//! time. Units: mm, degrees; errors in µm.

use nalgebra::Vector3;

use crate::motion::SegmentKind;
use vmc_identify::chain::{Geometry, Pose};
use vmc_identify::errors::ErrorState;
use vmc_identify::htm::{tip_in_workpiece_mm, tool_axis_in_workpiece};
use vmc_identify::inverse::linear_axes_for;
use vmc_identify::inverse_pose::axes_for_tool_pose;

use super::plan::{joints_for_tip, FivePlan, Piece};
pub use super::plan::{pose_of, FiveAxisRunError};

/// Where the trajectory is sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sampling {
    /// The middle of every dwell (G4).
    Dwells,
    /// Dwells and every interpolation cycle of this period (s) during motion.
    EveryCycle(f64),
}

/// One commanded point of the trajectory.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Commanded {
    /// Time from the start of the program, s.
    pub time_s: f64,
    /// Source line of the segment in effect.
    pub line: usize,
    /// Linear axes X, Y, Z, mm.
    pub q_mm: [f64; 3],
    /// Rotary axes A, B, C, degrees.
    pub abc_deg: [f64; 3],
    /// Whether the point is a dwell point.
    pub at_dwell: bool,
}

/// One evaluated point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FivePoint {
    /// The commanded point.
    pub commanded: Commanded,
    /// Commanded tool tip in the workpiece frame (nominal chain), mm.
    pub tip_w_mm: [f64; 3],
    /// Error without compensation, workpiece frame, µm.
    pub error_before_um: [f64; 3],
    /// Linear axes the compensating controller commands, mm.
    pub compensated_q_mm: Option<[f64; 3]>,
    /// Error with compensation, workpiece frame, µm.
    pub error_after_um: Option<[f64; 3]>,
    /// Angle between the actual and the commanded tool axis relative to the workpiece, without
    /// compensation, µrad.
    pub axis_error_before_urad: f64,
    /// Rotary axes A, B, C the compensating controller commands, degrees (the commanded ones
    /// when it corrects the linear axes only).
    pub compensated_abc_deg: Option<[f64; 3]>,
    /// Tool-axis error with compensation, µrad.
    pub axis_error_after_urad: Option<f64>,
}

/// The compensating controller: its model of the machine's errors (knowledge only) and
/// whether it corrects the rotary axes too.
#[derive(Clone, Copy)]
pub struct Controller<'a> {
    /// The model's errors at a pose.
    pub model: &'a dyn Fn(&Pose) -> ErrorState,
    /// Also correct the rotary axes for the tool-axis error
    /// ([`vmc_identify::inverse_pose::axes_for_tool_pose`]); else the linear axes only.
    pub rotary: bool,
}

/// The points where the run measures, in time order (as the three-axis simulation takes them);
/// under G43.4 the axes come from the nominal inverse kinematics of the programmed tip.
#[must_use]
pub fn commanded_points(plan: &FivePlan, sampling: Sampling) -> Vec<Commanded> {
    let mut out = Vec::new();
    for piece in &plan.pieces {
        piece_points(plan, piece, sampling, &mut out);
    }
    out
}

fn piece_points(plan: &FivePlan, piece: &Piece, sampling: Sampling, out: &mut Vec<Commanded>) {
    let joints =
        |p_mm, abc_deg| joints_for_tip(plan.geometry(), piece.tcp_length_mm, p_mm, abc_deg);
    for (i, seg) in piece.plan.segments().iter().enumerate() {
        let moving = matches!(
            seg.kind,
            SegmentKind::Rapid | SegmentKind::Feed | SegmentKind::Arc
        );
        let (t_start_s, duration_s) = (piece.segment_start_s(i), piece.segment_duration_s(i));
        match (seg.kind, sampling) {
            (SegmentKind::Dwell, _) => out.push(Commanded {
                time_s: piece.t0_s + t_start_s + 0.5 * duration_s,
                line: seg.line,
                q_mm: joints(seg.end_mm, seg.end_abc_deg),
                abc_deg: seg.end_abc_deg,
                at_dwell: true,
            }),
            (_, Sampling::EveryCycle(dt_s)) if moving && duration_s > 0.0 => {
                let n = (duration_s / dt_s).ceil() as usize;
                for k in 0..n {
                    let t_local_s = k as f64 * dt_s;
                    let (pos_mm, abc_deg) = piece.segment_state_at(i, t_local_s);
                    out.push(Commanded {
                        time_s: piece.t0_s + t_start_s + t_local_s,
                        line: seg.line,
                        q_mm: joints(pos_mm, abc_deg),
                        abc_deg,
                        at_dwell: false,
                    });
                }
            }
            _ => {}
        }
    }
}

fn um(v: Vector3<f64>) -> [f64; 3] {
    [v[0] * 1e3, v[1] * 1e3, v[2] * 1e3]
}

/// `abc_deg` with the machine's rotary axes set to the pose's angles.
fn abc_of(geom: &Geometry, rotary_deg: [f64; 2], mut abc_deg: [f64; 3]) -> [f64; 3] {
    for (i, r) in geom.rotary.iter().enumerate().take(2) {
        abc_deg[r.axis.index()] = rotary_deg[i];
    }
    abc_deg
}

/// Angle between two directions, µrad.
fn angle_urad(a: Vector3<f64>, b: Vector3<f64>) -> f64 {
    a.cross(&b).norm().atan2(a.dot(&b)) * 1e6
}

/// The error at every point: `truth` gives the machine's errors at a pose, `controller` (if
/// any) compensates. Position and tool-axis errors are those of the tool relative to the
/// workpiece, against the nominal chain at the commanded axes.
///
/// # Errors
/// [`FiveAxisRunError::Compensation`] when the controller's equation cannot be solved.
pub fn evaluate(
    geom: &Geometry,
    points: &[Commanded],
    truth: &dyn Fn(&Pose) -> ErrorState,
    controller: Option<Controller>,
) -> Result<Vec<FivePoint>, FiveAxisRunError> {
    let zero = ErrorState::default();
    points
        .iter()
        .map(|c| {
            let pose = pose_of(geom, c.q_mm, c.abc_deg);
            let tip = tip_in_workpiece_mm(geom, &pose, &zero);
            let axis = tool_axis_in_workpiece(geom, &pose, &zero);
            let real = |pose: &Pose| {
                let state = truth(pose);
                (
                    tip_in_workpiece_mm(geom, pose, &state),
                    tool_axis_in_workpiece(geom, pose, &state),
                )
            };
            let (tip_before, axis_before) = real(&pose);
            let mut point = FivePoint {
                commanded: *c,
                tip_w_mm: [tip[0], tip[1], tip[2]],
                error_before_um: um(tip_before - tip),
                compensated_q_mm: None,
                error_after_um: None,
                axis_error_before_urad: angle_urad(axis_before, axis),
                compensated_abc_deg: None,
                axis_error_after_urad: None,
            };
            if let Some(ctl) = controller {
                let fail = |err| FiveAxisRunError::Compensation { line: c.line, err };
                let comp = if ctl.rotary {
                    axes_for_tool_pose(geom, pose.rotary_deg, tip, axis, ctl.model).map_err(fail)?
                } else {
                    Pose {
                        linear_mm: linear_axes_for(geom, pose.rotary_deg, tip, ctl.model)
                            .map_err(fail)?,
                        rotary_deg: pose.rotary_deg,
                    }
                };
                let (tip_after, axis_after) = real(&comp);
                point.compensated_q_mm = Some(comp.linear_mm);
                point.compensated_abc_deg = Some(abc_of(geom, comp.rotary_deg, c.abc_deg));
                point.error_after_um = Some(um(tip_after - tip));
                point.axis_error_after_urad = Some(angle_urad(axis_after, axis));
            }
            Ok(point)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fiveaxis::plan::plan_program;
    use crate::fiveaxis::FiveAxisSpec;

    /// 1e-6 µm (1 pm): rounding of the exact transforms.
    const TOL_UM: f64 = 1e-6;

    fn norm_um(v: [f64; 3]) -> f64 {
        (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
    }

    fn spec() -> FiveAxisSpec {
        FiveAxisSpec::from_toml_str(
            include_str!("../../../../machines/trunnion-ac.toml"),
            "trunnion-ac.toml",
        )
        .unwrap()
    }

    fn points(spec: &FiveAxisSpec, sampling: Sampling) -> Vec<Commanded> {
        let text = "G0 A-30 C90\nG0 X10 Y20 Z-250\nG4 P1\nG1 X-20 A-60 C180 F1000\nG4 P2\nM2\n";
        let plan = plan_program(text, "t.ngc", spec, "m.toml").unwrap();
        commanded_points(&plan, sampling)
    }

    #[test]
    fn dwell_points_sit_in_the_middle_of_each_dwell_at_the_commanded_axes() {
        let s = spec();
        let text = "G0 A-30 C90\nG0 X10 Y20 Z-250\nG4 P1\nG1 X-20 A-60 C180 F1000\nG4 P2\nM2\n";
        let plan = plan_program(text, "t.ngc", &s, "m.toml").unwrap();
        let pts = commanded_points(&plan, Sampling::Dwells);
        assert_eq!(pts.len(), 2);
        let dwell = &plan.pieces[0].plan.segments()[2];
        assert_eq!(pts[0].line, 3);
        assert!((pts[0].time_s - (dwell.t_start_s + 0.5)).abs() < 1e-12);
        assert_eq!(pts[0].q_mm, [10.0, 20.0, -250.0]);
        assert_eq!(pts[0].abc_deg, [-30.0, 0.0, 90.0]);
        assert_eq!(pts[1].q_mm, [-20.0, 20.0, -250.0]);
        assert_eq!(pts[1].abc_deg, [-60.0, 0.0, 180.0]);
        // Every cycle: more points, the dwells among them.
        let all = commanded_points(&plan, Sampling::EveryCycle(0.01));
        assert!(all.len() > 100);
        assert_eq!(all.iter().filter(|p| p.at_dwell).count(), 2);
    }

    #[test]
    fn without_errors_the_tool_tip_error_is_zero() {
        let s = spec();
        let g = s.geometry();
        let zero = |_: &Pose| ErrorState::default();
        for p in evaluate(&g, &points(&s, Sampling::EveryCycle(0.01)), &zero, None).unwrap() {
            assert!(norm_um(p.error_before_um) < TOL_UM, "{p:?}");
        }
    }

    #[test]
    fn a_datum_offset_is_seen_reversed_in_the_workpiece_frame_at_every_pose() {
        // The workpiece frame moved by δW on the table: the tip relative to it is −δW, whatever
        // the angles (the workpiece frame turns with the table).
        let s = spec();
        let g = s.geometry();
        let offset = |_: &Pose| ErrorState {
            workpiece_mm: [0.010, -0.020, 0.005],
            ..ErrorState::default()
        };
        for p in evaluate(&g, &points(&s, Sampling::EveryCycle(0.01)), &offset, None).unwrap() {
            let e = p.error_before_um;
            for (k, want) in [-10.0, 20.0, -5.0].into_iter().enumerate() {
                assert!((e[k] - want).abs() < TOL_UM, "{e:?}");
            }
        }
    }

    #[test]
    fn a_stylus_offset_turns_into_the_workpiece_frame_with_the_table() {
        // δT = 10 µm along bed x. The table turned by −C about z (A = 0): in the workpiece frame
        // the offset reads R_z(C)·δT, (0, 10, 0) µm at C = 90°.
        let s = spec();
        let g = s.geometry();
        let tool = |_: &Pose| ErrorState {
            tool_mm: [0.010, 0.0, 0.0],
            ..ErrorState::default()
        };
        let c = Commanded {
            time_s: 0.0,
            line: 1,
            q_mm: [0.0, -150.0, -200.0],
            abc_deg: [0.0, 0.0, 90.0],
            at_dwell: true,
        };
        let e = evaluate(&g, &[c], &tool, None).unwrap()[0].error_before_um;
        assert!(
            e[0].abs() < TOL_UM && (e[1] - 10.0).abs() < TOL_UM && e[2].abs() < TOL_UM,
            "{e:?}"
        );
    }

    #[test]
    fn a_model_equal_to_the_machine_compensates_every_point_to_the_solver_tolerance() {
        let s = spec();
        let g = s.geometry();
        let truth = crate::fiveaxis::TrueMachine::new(&s, 3).unwrap();
        let t = |p: &Pose| truth.state_at(p);
        let ctl = |rotary| Controller { model: &t, rotary };
        let pts = evaluate(
            &g,
            &points(&s, Sampling::EveryCycle(0.01)),
            &t,
            Some(ctl(false)),
        )
        .unwrap();
        for p in &pts {
            assert_eq!(p.compensated_abc_deg, Some(p.commanded.abc_deg));
            // Linear axes alone do not turn the tool: the tool-axis error stays.
            assert!((p.axis_error_after_urad.unwrap() - p.axis_error_before_urad).abs() < 1.0);
        }
        let full = evaluate(
            &g,
            &points(&s, Sampling::EveryCycle(0.01)),
            &t,
            Some(ctl(true)),
        )
        .unwrap();
        for p in &full {
            assert!(norm_um(p.error_after_um.unwrap()) < 1e-3, "{p:?}");
            assert!(p.axis_error_before_urad > 5.0, "{p:?}");
            let after = p.axis_error_after_urad.unwrap();
            if p.commanded.abc_deg[0].abs() >= 10.0 {
                // The damping leaves λ²/σ² of it (|A| ≥ 10°: σ ≥ 0.17).
                assert!(after < 1e-3 * p.axis_error_before_urad, "{p:?}");
            } else {
                // Near A = 0 turning C does not move the tool axis: part of it stays.
                assert!(after < p.axis_error_before_urad, "{p:?}");
            }
        }
        for p in &pts {
            assert!(norm_um(p.error_before_um) > 1.0, "{p:?}");
            // Newton stops below 1e-10 mm; 1e-3 µm leaves room.
            assert!(norm_um(p.error_after_um.unwrap()) < 1e-3, "{p:?}");
        }
        let rms = |f: &dyn Fn(&FivePoint) -> f64| {
            (pts.iter().map(|p| f(p).powi(2)).sum::<f64>() / pts.len() as f64).sqrt()
        };
        let before = rms(&|p| norm_um(p.error_before_um));
        let after = rms(&|p| norm_um(p.error_after_um.unwrap()));
        assert!(1.0 - after / before > 0.999_99);
    }

    #[test]
    fn a_machine_without_rotary_speed_limits_cannot_run_programs() {
        let text = include_str!("../../../../machines/trunnion-ac.toml")
            .replace("max_speed_deg_per_s = 90.0", "");
        let s = FiveAxisSpec::from_toml_str(&text, "m.toml").unwrap();
        let e = plan_program("G0 A-10\nM2\n", "t.ngc", &s, "m.toml").unwrap_err();
        assert!(
            e.to_string().contains("rotary axis A has no speed limits"),
            "{e}"
        );
    }
}
