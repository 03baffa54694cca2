//! First-order model of what a probe reads: `δq = S·E`.
//!
//! # Small-displacement composition along the chain
//! An elementary error is a small twist `(δ, ε)` of one element relative to its parent, acting
//! about a point `o` of a frame `F` of the nominal chain at the pose (the carriage frame of a
//! linear axis with `o` its reference point, the parent frame of a rotary axis with `o` its axis
//! point, the last element's frame for an assembly error). A point `y` carried by the element
//! moves by `δ + ε × (y − o)` in `F`. The tool tip relative to the workpiece therefore moves by
//!
//! ```text
//! δtip_w = s · R_wF · (δ + ε × (y − o)),    y = F⁻¹ · tip (nominal tip in F)
//! ```
//!
//! with `R_wF` the rotation from `F` to the workpiece frame and `s = −1` for an element on the
//! workpiece side (it moves the workpiece, not the tip), `+1` on the tool side. A squareness
//! error turns a slide's travel direction: `δ = s·q_k·∂d_k/∂α`, `ε = 0`.
//!
//! The probe reads the linear axes `q` at which the tip meets the sphere centre; to first order
//! the reading shifts by `δq = −J_q⁻¹ · δtip_w` with `J_q = ∂tip_w/∂q`, whose column `k` is
//! `R_wF_k · e_k`. So the sensitivity of the reading to parameter `j` (weight `w_j(θ)`) is
//! `S_j = −J_q⁻¹ · w_j · δtip_w(unit twist of j)`. Second-order terms (ε² · arm, ε · δ) are
//! neglected: ≈ 1 nm for 50 µrad over 400 mm.

use nalgebra::{DMatrix, Isometry3, Matrix3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::chain::{Axis, Geometry, LinearAxis, Pose};
use crate::errors::{Component, ErrorState, ParameterSet};
use crate::htm::{bed_from_tip, bed_from_workpiece, rotary_index};

/// Where one element's error acts, at one pose.
#[derive(Debug, Clone, Copy)]
struct ErrorSite {
    /// Rotation from the error frame F to the workpiece frame.
    w_from_f: Matrix3<f64>,
    /// Arm `y − o` in F, mm.
    arm_mm: Vector3<f64>,
    /// `−1` workpiece side, `+1` tool side.
    sign: f64,
}

impl ErrorSite {
    fn effect(&self, lin: Vector3<f64>, ang: Vector3<f64>) -> Vector3<f64> {
        self.w_from_f * (lin + ang.cross(&self.arm_mm)) * self.sign
    }
}

/// The nominal chain at one pose, ready to give the first-order effect of any error.
#[derive(Debug, Clone)]
pub struct Frames {
    sites: Vec<ErrorSite>,
    workpiece: ErrorSite,
    tool: ErrorSite,
    /// Chain index of the X, Y, Z slides.
    linear_index: [usize; 3],
    /// Chain index of each rotary axis ([`Geometry::rotary`] order).
    rotary_index: Vec<usize>,
    pose: Pose,
    signs: Vec<f64>,
}

impl Frames {
    /// The nominal frames of `geom` at `pose`.
    #[must_use]
    pub fn new(geom: &Geometry, pose: &Pose) -> Frames {
        let zero = ErrorState::default();
        let w_from_bed = bed_from_workpiece(geom, pose, &zero).inverse();
        let tip_b = bed_from_tip(geom, pose, &zero).translation.vector;
        let elements = geom.chain.elements();
        let n_w = geom.chain.n_workpiece_side();
        let mut sites = vec![
            ErrorSite {
                w_from_f: Matrix3::identity(),
                arm_mm: Vector3::zeros(),
                sign: 1.0
            };
            elements.len()
        ];
        let mut linear_index = [0; 3];
        let mut rotary_idx = vec![0; geom.rotary.len()];
        let mut signs = vec![0.0; elements.len()];
        let site = |f: &Isometry3<f64>, o: Vector3<f64>, sign: f64| ErrorSite {
            w_from_f: (w_from_bed * f).rotation.to_rotation_matrix().into_inner(),
            arm_mm: f.inverse_transform_point(&tip_b.into()).coords - o,
            sign,
        };
        let mut last = [Isometry3::identity(); 2];
        for (side, range) in [
            (0, (0..n_w).rev().collect::<Vec<_>>()),
            (1, (n_w..elements.len()).collect()),
        ] {
            let mut b = Isometry3::identity();
            for i in range {
                let s = geom.chain.side_of(i).sign();
                signs[i] = s;
                match elements[i] {
                    Axis::Linear(axis) => {
                        let k = axis.index();
                        linear_index[k] = i;
                        let mut d = Vector3::zeros();
                        d[k] = s * pose.linear_mm[k];
                        b *= Translation3::from(d);
                        sites[i] = site(&b, Vector3::zeros(), s);
                    }
                    Axis::Rotary(axis) => {
                        let r = rotary_index(geom, i);
                        rotary_idx[r] = i;
                        let p = Vector3::from(geom.rotary[r].point_mm);
                        sites[i] = site(&b, p, s);
                        let turn = UnitQuaternion::from_axis_angle(
                            &Unit::new_unchecked(axis.nominal_direction()),
                            s * pose.rotary_deg[r].to_radians(),
                        );
                        b = b * Translation3::from(p) * turn * Translation3::from(-p);
                    }
                }
            }
            last[side] = b;
        }
        let workpiece = site(&last[0], Vector3::zeros(), -1.0);
        let tool = site(&last[1], Vector3::zeros(), 1.0);
        Frames {
            sites,
            workpiece,
            tool,
            linear_index,
            rotary_index: rotary_idx,
            pose: *pose,
            signs,
        }
    }

    /// `J_q = ∂tip_w/∂q`: how the tip moves in the workpiece frame per mm of each linear axis.
    #[must_use]
    pub fn jq(&self) -> Matrix3<f64> {
        let mut j = Matrix3::zeros();
        for k in 0..3 {
            let site = &self.sites[self.linear_index[k]];
            // The slide moves by s·e_k; the tip relative to the workpiece by s·(s·e_k) = e_k.
            let col = site.w_from_f * Vector3::ith(k, 1.0);
            j.set_column(k, &col);
        }
        j
    }

    /// First-order displacement of the tip in the workpiece frame per unit of `component`
    /// (per mm or per rad).
    #[must_use]
    pub fn tip_effect(&self, component: &Component) -> Vector3<f64> {
        let unit = |c: usize| {
            let mut lin = Vector3::zeros();
            let mut ang = Vector3::zeros();
            if c < 3 {
                lin[c] = 1.0;
            } else {
                ang[c - 3] = 1.0;
            }
            (lin, ang)
        };
        match *component {
            Component::Linear { axis, component } => {
                let (l, a) = unit(component);
                self.sites[self.linear_index[axis.index()]].effect(l, a)
            }
            Component::Squareness(i) => {
                let (axis, dir) = match i {
                    0 => (LinearAxis::Y, Vector3::new(-1.0, 0.0, 0.0)),
                    1 => (LinearAxis::Z, Vector3::new(1.0, 0.0, 0.0)),
                    _ => (LinearAxis::Z, Vector3::new(0.0, -1.0, 0.0)),
                };
                let idx = self.linear_index[axis.index()];
                let lin = dir * (self.signs[idx] * self.pose.linear_mm[axis.index()]);
                self.sites[idx].effect(lin, Vector3::zeros())
            }
            Component::Location {
                rotary,
                axis,
                component,
            } => {
                if component == axis.index() {
                    return Vector3::zeros();
                }
                let (l, a) = unit(component);
                self.sites[self.rotary_index[rotary]].effect(l, a)
            }
            Component::Motion {
                rotary, component, ..
            } => {
                let (l, a) = unit(component);
                self.sites[self.rotary_index[rotary]].effect(l, a)
            }
            // A relocated sphere's offset acts on its readings as the datum's does.
            Component::Workpiece(i) | Component::Placement { axis: i, .. } => {
                self.workpiece.effect(unit(i).0, Vector3::zeros())
            }
            Component::Tool(i) => self.tool.effect(unit(i).0, Vector3::zeros()),
        }
    }

    /// First-order tip error in the workpiece frame of a whole error state, mm.
    #[must_use]
    pub fn first_order_tip_error_mm(&self, geom: &Geometry, state: &ErrorState) -> Vector3<f64> {
        let mut e = Vector3::zeros();
        for c in Component::all(geom) {
            let v = value_of(&c, state);
            if v != 0.0 {
                e += self.tip_effect(&c) * v;
            }
        }
        e
    }
}

/// The value of `component` in `state`.
#[must_use]
pub fn value_of(component: &Component, state: &ErrorState) -> f64 {
    match *component {
        Component::Linear { axis, component } => state.linear[axis.index()].get(component),
        Component::Squareness(i) => state.squareness_rad[i],
        Component::Location {
            rotary, component, ..
        } => state.rotary_location[rotary].get(component),
        Component::Motion {
            rotary, component, ..
        } => state.rotary_motion[rotary].get(component),
        Component::Workpiece(i) => state.workpiece_mm[i],
        Component::Tool(i) => state.tool_mm[i],
        Component::Placement { .. } => 0.0,
    }
}

/// The 3 × p sensitivity of the probe reading (linear axes at the sphere centre) to the
/// parameters of `set` at `pose`: `δq = S·E`, mm per mm or per rad.
#[must_use]
pub fn probe_sensitivity(geom: &Geometry, pose: &Pose, set: &ParameterSet) -> DMatrix<f64> {
    let frames = Frames::new(geom, pose);
    let jq_inv = frames.jq().try_inverse().unwrap_or_else(Matrix3::identity);
    let mut s = DMatrix::zeros(3, set.len());
    for (j, p) in set.params.iter().enumerate() {
        let col = -(jq_inv * frames.tip_effect(&p.component)) * p.weight_at(pose);
        s.fixed_view_mut::<3, 1>(0, j).copy_from(&col);
    }
    s
}

#[cfg(test)]
#[path = "sensitivity_tests.rs"]
mod tests;
