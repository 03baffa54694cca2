//! The ISO 230-7 error vocabulary of a five-axis machine, an error state at a pose, and the
//! parameter vector that identification fits.
//!
//! Names follow ISO 230-1/230-7 with an underscore after the `E`:
//! - **linear-axis errors (21)**: the 18 motion errors `E_XX … E_CZ` (component, then moving
//!   axis: `E_XX` positioning of X, `E_YX` straightness of X along Y, `E_AX` roll …) and the 3
//!   squareness errors `E_C0Y`, `E_B0Z`, `E_A0Z` (as in the three-axis model);
//! - **rotary-axis motion errors (6 per axis, functions of the angle)**: `E_XA, E_YA, E_ZA`
//!   (translations of the axis point), `E_AA, E_BA, E_CA` (tilts; the component about the axis
//!   itself, e.g. `E_AA`, is the angular positioning error);
//! - **location errors of the axis average lines (5 per rotary axis)**: the two offsets across
//!   the axis and the three angles, e.g. `E_Y0A, E_Z0A, E_A0A, E_B0A, E_C0A` for A (`E_A0A` is
//!   the zero offset) and `E_X0C, E_Y0C, E_A0C, E_B0C, E_C0C` for C; the offset along the axis
//!   itself (`E_X0A`, `E_Z0C`) moves nothing and is not a parameter;
//! - **assembly errors**: the datum (reference sphere) offset on the table `E_XW, E_YW, E_ZW`
//!   and the tool (stylus) tip offset in the spindle frame `E_XT, E_YT, E_ZT`. Their six
//!   orientations move neither a sphere centre nor a ball tip and are not parameters.
//!
//! Count for `w C A Y X b Z t`: 18 + 12 = 30 motion errors (as the study), 3 + 10 = 13 location
//! errors (the study counts 19) and 6 assembly errors (the study counts 12, including the six
//! orientations that cannot act on a point).
//!
//! All lengths in mm and angles in rad; translations are physical motions of the element
//! relative to its parent, rotations right-handed about the bed axes through the element's
//! reference point (the axis point for a rotary axis).

use serde::{Deserialize, Serialize};

use crate::chain::{Geometry, LinearAxis, Pose, RotaryAxis};

/// Three translations (mm) and three rotations (rad) of one element.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SixErrors {
    /// Translations along bed x, y, z, mm.
    pub lin_mm: [f64; 3],
    /// Rotations about bed x, y, z, rad.
    pub ang_rad: [f64; 3],
}

impl SixErrors {
    /// Component `c` (0–2 translations, 3–5 rotations).
    #[must_use]
    pub fn get(&self, c: usize) -> f64 {
        if c < 3 {
            self.lin_mm[c]
        } else {
            self.ang_rad[c - 3]
        }
    }

    /// Mutable component `c` (0–2 translations, 3–5 rotations).
    pub fn get_mut(&mut self, c: usize) -> &mut f64 {
        if c < 3 {
            &mut self.lin_mm[c]
        } else {
            &mut self.ang_rad[c - 3]
        }
    }
}

/// Every geometric error acting at one pose: motion errors evaluated at the pose, location and
/// assembly errors.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorState {
    /// Motion errors of X, Y, Z at their positions.
    pub linear: [SixErrors; 3],
    /// Squareness α_xy (E_C0Y), α_xz (E_B0Z), α_yz (E_A0Z), rad.
    pub squareness_rad: [f64; 3],
    /// Motion errors of each rotary axis at its angle ([`Geometry::rotary`] order).
    pub rotary_motion: [SixErrors; 2],
    /// Location errors of each rotary axis's average line ([`Geometry::rotary`] order); the
    /// translation along the axis itself is ignored.
    pub rotary_location: [SixErrors; 2],
    /// Datum (workpiece) offset on the element carrying `w`, mm.
    pub workpiece_mm: [f64; 3],
    /// Tool tip offset in the spindle frame, mm.
    pub tool_mm: [f64; 3],
}

/// One elementary error of the chain: where its small displacement acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Component {
    /// Motion error `component` (0–5) of a linear axis.
    Linear {
        /// The axis.
        axis: LinearAxis,
        /// 0–2 translation x/y/z, 3–5 rotation about x/y/z.
        component: usize,
    },
    /// Squareness: 0 α_xy, 1 α_xz, 2 α_yz.
    Squareness(usize),
    /// Location error of a rotary axis line.
    Location {
        /// Index in [`Geometry::rotary`].
        rotary: usize,
        /// The axis (for the name).
        axis: RotaryAxis,
        /// 0–5 as in [`SixErrors::get`].
        component: usize,
    },
    /// Motion error of a rotary axis at its angle.
    Motion {
        /// Index in [`Geometry::rotary`].
        rotary: usize,
        /// The axis (for the name).
        axis: RotaryAxis,
        /// 0–5 as in [`SixErrors::get`].
        component: usize,
    },
    /// Datum offset along x/y/z.
    Workpiece(usize),
    /// Tool tip offset along x/y/z.
    Tool(usize),
    /// Where a relocated sphere really sits relative to where it was put, along x/y/z of the
    /// workpiece frame, for placement `placement` ≥ 1 of a probing campaign (a sphere moved
    /// over the table between blocks of configurations; its nominal position is known to a
    /// fraction of a millimetre only). Not a machine error: it moves only the readings of its
    /// own placement and never enters a compensation.
    Placement {
        /// 1-based placement.
        placement: usize,
        /// 0–2: x, y, z.
        axis: usize,
    },
}

const LETTERS: [char; 6] = ['X', 'Y', 'Z', 'A', 'B', 'C'];

impl Component {
    /// The ISO 230-7 style name, e.g. `E_Y0A`, `E_CA`, `E_XX`, `E_C0Y`, `E_ZT`.
    #[must_use]
    pub fn name(&self) -> String {
        match *self {
            Component::Linear { axis, component } => {
                format!("E_{}{}", LETTERS[component], axis.letter())
            }
            Component::Squareness(i) => ["E_C0Y", "E_B0Z", "E_A0Z"][i].to_string(),
            Component::Location {
                axis, component, ..
            } => format!("E_{}0{}", LETTERS[component], axis.letter()),
            Component::Motion {
                axis, component, ..
            } => format!("E_{}{}", LETTERS[component], axis.letter()),
            Component::Workpiece(i) => format!("E_{}W", LETTERS[i]),
            Component::Tool(i) => format!("E_{}T", LETTERS[i]),
            Component::Placement { placement, axis } => {
                format!("E_{}P{placement}", LETTERS[axis])
            }
        }
    }

    /// Whether the value is an angle (rad) rather than a length (mm).
    #[must_use]
    pub fn is_angle(&self) -> bool {
        match *self {
            Component::Linear { component, .. }
            | Component::Location { component, .. }
            | Component::Motion { component, .. } => component >= 3,
            Component::Squareness(_) => true,
            Component::Workpiece(_) | Component::Tool(_) | Component::Placement { .. } => false,
        }
    }

    /// Adds `value` to this component of `state`.
    pub fn add_to(&self, state: &mut ErrorState, value: f64) {
        match *self {
            Component::Linear { axis, component } => {
                *state.linear[axis.index()].get_mut(component) += value;
            }
            Component::Squareness(i) => state.squareness_rad[i] += value,
            Component::Location {
                rotary, component, ..
            } => *state.rotary_location[rotary].get_mut(component) += value,
            Component::Motion {
                rotary, component, ..
            } => *state.rotary_motion[rotary].get_mut(component) += value,
            Component::Workpiece(i) => state.workpiece_mm[i] += value,
            Component::Tool(i) => state.tool_mm[i] += value,
            // An artefact's position, not the machine's: nothing to compensate.
            Component::Placement { .. } => {}
        }
    }

    /// Every elementary error of a machine: 18 linear motion, 3 squareness, 6 motion and
    /// 5 location errors per rotary axis, 3 + 3 assembly errors.
    #[must_use]
    pub fn all(geom: &Geometry) -> Vec<Component> {
        let mut out = Vec::new();
        for axis in LinearAxis::ALL {
            for component in 0..6 {
                out.push(Component::Linear { axis, component });
            }
        }
        out.extend((0..3).map(Component::Squareness));
        for (rotary, r) in geom.rotary.iter().enumerate() {
            for component in 0..6 {
                out.push(Component::Motion {
                    rotary,
                    axis: r.axis,
                    component,
                });
            }
            out.extend(location_components(rotary, r.axis));
        }
        out.extend((0..3).map(Component::Workpiece));
        out.extend((0..3).map(Component::Tool));
        out
    }
}

/// The 5 location errors of rotary axis `axis` (index `rotary`): the two offsets across it and
/// the three angles.
fn location_components(rotary: usize, axis: RotaryAxis) -> impl Iterator<Item = Component> {
    (0..6)
        .filter(move |&c| c != axis.index())
        .map(move |component| Component::Location {
            rotary,
            axis,
            component,
        })
}

/// One fitted parameter: an elementary error, constant or as one harmonic of the angle of the
/// rotary axis it belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// The elementary error it feeds.
    pub component: Component,
    /// `None`: a constant. `Some((k, false))`: coefficient of `cos(k·θ)`, `Some((k, true))` of
    /// `sin(k·θ)`, θ the commanded angle of the component's rotary axis.
    pub harmonic: Option<(u32, bool)>,
}

impl Parameter {
    /// A constant parameter.
    #[must_use]
    pub const fn constant(component: Component) -> Self {
        Parameter {
            component,
            harmonic: None,
        }
    }

    /// Its name, e.g. `E_Y0A` or `E_CC·cos2C`.
    #[must_use]
    pub fn name(&self) -> String {
        let base = self.component.name();
        match (self.harmonic, self.component) {
            (Some((k, sine)), Component::Motion { axis, .. }) => {
                let f = if sine { "sin" } else { "cos" };
                format!("{base}·{f}{k}{}", axis.letter())
            }
            _ => base,
        }
    }

    /// The factor by which a unit value of this parameter feeds its component at `pose`.
    #[must_use]
    pub fn weight_at(&self, pose: &Pose) -> f64 {
        match (self.harmonic, self.component) {
            (Some((k, sine)), Component::Motion { rotary, .. }) => {
                let th = f64::from(k) * pose.rotary_deg[rotary].to_radians();
                if sine {
                    th.sin()
                } else {
                    th.cos()
                }
            }
            _ => 1.0,
        }
    }
}

/// The parameters identification fits, in a fixed order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterSet {
    /// The parameters.
    pub params: Vec<Parameter>,
}

impl ParameterSet {
    /// The default set: the 3 squareness errors, the 5 location errors of each rotary axis and
    /// the 6 assembly errors (19 for a two-rotary machine).
    #[must_use]
    pub fn location_and_assembly(geom: &Geometry) -> Self {
        let mut params: Vec<Parameter> = (0..3)
            .map(|i| Parameter::constant(Component::Squareness(i)))
            .collect();
        for (rotary, r) in geom.rotary.iter().enumerate() {
            params.extend(location_components(rotary, r.axis).map(Parameter::constant));
        }
        params.extend((0..3).map(|i| Parameter::constant(Component::Workpiece(i))));
        params.extend((0..3).map(|i| Parameter::constant(Component::Tool(i))));
        ParameterSet { params }
    }

    /// Adds the harmonics up to `max_order` of every rotary motion error (see
    /// [`ParameterSet::with_motion_harmonics_per_axis`]).
    #[must_use]
    pub fn with_motion_harmonics(self, geom: &Geometry, max_order: u32) -> Self {
        let orders = vec![max_order; geom.rotary.len()];
        self.with_motion_harmonics_per_axis(geom, &orders)
    }

    /// Adds the harmonics up to `max_orders[r]` (cos and sin) of the motion errors of rotary
    /// axis `r`, in the same order as [`ParameterSet::with_motion_harmonics`], so equal orders
    /// give the same set: orders 2…N of the five translations and tilts (their first harmonic
    /// is part of the average line) and orders 1…N of the angular positioning error (its first
    /// harmonic, e.g. an encoder's eccentricity, is not a location error). 0: none for that axis.
    #[must_use]
    pub fn with_motion_harmonics_per_axis(mut self, geom: &Geometry, max_orders: &[u32]) -> Self {
        for (rotary, r) in geom.rotary.iter().enumerate() {
            let max_order = max_orders.get(rotary).copied().unwrap_or(0);
            for component in 0..6 {
                let first = if component == r.axis.index() + 3 {
                    1
                } else {
                    2
                };
                for k in first..=max_order {
                    for sine in [false, true] {
                        self.params.push(Parameter {
                            component: Component::Motion {
                                rotary,
                                axis: r.axis,
                                component,
                            },
                            harmonic: Some((k, sine)),
                        });
                    }
                }
            }
        }
        self
    }

    /// Adds the offsets (x, y, z) of relocated-sphere placements 1…`n` ([`Component::Placement`]).
    #[must_use]
    pub fn with_placements(mut self, n: usize) -> Self {
        for placement in 1..=n {
            for axis in 0..3 {
                self.params.push(Parameter::constant(Component::Placement {
                    placement,
                    axis,
                }));
            }
        }
        self
    }

    /// The fitted offset of placement `placement` (zero for placement 0, the artefact, or a
    /// placement the set does not hold), mm.
    #[must_use]
    pub fn placement_offset_mm(&self, values: &[f64], placement: usize) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (p, v) in self.params.iter().zip(values) {
            if let Component::Placement { placement: k, axis } = p.component {
                if k == placement {
                    out[axis] += v;
                }
            }
        }
        out
    }

    /// Number of parameters.
    #[must_use]
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// Whether the set is empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// The names in order.
    #[must_use]
    pub fn names(&self) -> Vec<String> {
        self.params.iter().map(Parameter::name).collect()
    }

    /// The error state these parameter values produce at `pose` (all other errors zero).
    #[must_use]
    pub fn state_at(&self, values: &[f64], pose: &Pose) -> ErrorState {
        let mut s = ErrorState::default();
        for (p, v) in self.params.iter().zip(values) {
            p.component.add_to(&mut s, v * p.weight_at(pose));
        }
        s
    }
}

/// Shared test fixtures.
#[cfg(test)]
pub(crate) mod tests_support {
    use crate::chain::{Chain, Geometry, RotaryAxis, RotaryGeometry};

    /// The trunnion of `machines/trunnion-ac.toml` in its nominal geometry.
    pub(crate) fn trunnion() -> Geometry {
        Geometry {
            chain: Chain::parse("w C A Y X b Z t").unwrap(),
            rotary: vec![
                RotaryGeometry {
                    axis: RotaryAxis::C,
                    point_mm: [0.0, 0.0, -450.0],
                },
                RotaryGeometry {
                    axis: RotaryAxis::A,
                    point_mm: [0.0, 0.0, -500.0],
                },
            ],
            tool_offset_mm: [0.0, 0.0, -150.0],
            datum_mm: [150.0, 0.0, -350.0],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::tests_support::trunnion;
    use super::*;

    #[test]
    fn the_trunnion_has_30_motion_13_location_and_6_assembly_errors() {
        let all = Component::all(&trunnion());
        let motion = all
            .iter()
            .filter(|c| matches!(c, Component::Linear { .. } | Component::Motion { .. }))
            .count();
        let location = all
            .iter()
            .filter(|c| matches!(c, Component::Squareness(_) | Component::Location { .. }))
            .count();
        assert_eq!(
            (motion, location, all.len() - motion - location),
            (30, 13, 6)
        );
        let set = ParameterSet::location_and_assembly(&trunnion());
        assert_eq!(set.len(), 19);
        let names = set.names();
        for n in [
            "E_X0C", "E_Y0C", "E_C0C", "E_Y0A", "E_Z0A", "E_A0A", "E_C0Y", "E_ZT",
        ] {
            assert!(names.contains(&n.to_string()), "{n} in {names:?}");
        }
        assert!(!names.contains(&"E_Z0C".to_string()));
    }

    #[test]
    fn a_harmonic_feeds_its_motion_error_with_the_angle() {
        let g = trunnion();
        let set = ParameterSet { params: vec![] }.with_motion_harmonics(&g, 2);
        // 12 errors × order 2 × (cos, sin), and order 1 of E_CC and E_AA.
        assert_eq!(set.len(), 28);
        assert_eq!(set.params[10].name(), "E_CC·cos1C");
        let pose = Pose {
            linear_mm: [0.0; 3],
            rotary_deg: [45.0, 0.0],
        };
        let mut v = vec![0.0; 28];
        v[1] = 2.0; // E_XC·sin2C
        let s = set.state_at(&v, &pose);
        assert!((s.rotary_motion[0].lin_mm[0] - 2.0).abs() < 1e-12);
        assert_eq!(set.params[1].name(), "E_XC·sin2C");
    }
}
