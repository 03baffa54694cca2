//! Five-axis kinematic chain (ISO 10791-6 notation, workpiece to tool) and nominal geometry.
//!
//! A chain such as `"w C A Y X b Z t"` reads from the workpiece to the tool: the workpiece `w`
//! sits on the C rotary table, C on the A trunnion, A on the Y slide, Y on X, X on the bed `b`;
//! on the other side of the bed Z carries the tool `t`. Elements between `w` and `b` are on the
//! *workpiece side*, those between `b` and `t` on the *tool side*; the same words as the
//! three-axis chain of `vmc-predict` (`LinearAxis`, `Side`).
//!
//! # Conventions (shared with the exact model in [`crate::htm`])
//! - **Bed frame**: axes along the nominal X, Y, Z travels, origin at the spindle gauge point with
//!   every axis at zero ("machine zero"). Every carriage frame coincides with the bed frame at
//!   machine zero, so all nominal geometry is given in bed coordinates at machine zero.
//! - **Linear axes** move the tool relative to the workpiece by `+q` (ISO 841): a workpiece-side
//!   slide physically moves by `−q`.
//! - **Rotary axes**: commanded angle `θ` (degrees at the interface, radians inside) is the
//!   rotation of the tool relative to the workpiece about the axis direction (ISO 841): a
//!   workpiece-side table physically turns by `−θ`, a tool-side head by `+θ`.
//!   A rotary axis is a line: a point `point_mm` and a unit direction `direction`.
//! - **Workpiece frame**: fixed to the element carrying `w`, origin at the datum `datum_mm` (the
//!   reference sphere's centre when probing), axes parallel to the bed's at machine zero.
//! - **Tool offset** `T`: tool (or stylus) tip relative to the gauge point, e.g. `(0, 0, −L)`.

use std::fmt;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// One of the three linear axes (index 0, 1, 2 in every `[_; 3]` array of this crate).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum LinearAxis {
    /// X axis (index 0).
    X,
    /// Y axis (index 1).
    Y,
    /// Z axis (index 2).
    Z,
}

impl LinearAxis {
    /// All three in index order.
    pub const ALL: [LinearAxis; 3] = [LinearAxis::X, LinearAxis::Y, LinearAxis::Z];

    /// Index in `[x, y, z]` arrays.
    #[must_use]
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The letter in chain notation.
    #[must_use]
    pub const fn letter(self) -> char {
        ['X', 'Y', 'Z'][self as usize]
    }
}

/// One of the rotary axes A, B, C (rotation about a line nominally parallel to X, Y, Z).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum RotaryAxis {
    /// About X.
    A,
    /// About Y.
    B,
    /// About Z.
    C,
}

impl RotaryAxis {
    /// Index of the bed axis it turns about (A → 0, B → 1, C → 2).
    #[must_use]
    pub const fn index(self) -> usize {
        self as usize
    }

    /// The letter in chain notation.
    #[must_use]
    pub const fn letter(self) -> char {
        ['A', 'B', 'C'][self as usize]
    }

    /// The nominal direction of its axis (unit vector of the bed axis it turns about).
    #[must_use]
    pub fn nominal_direction(self) -> Vector3<f64> {
        let mut d = Vector3::zeros();
        d[self.index()] = 1.0;
        d
    }
}

/// Which side of the bed an element sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Side {
    /// Between `w` and `b`: it carries the workpiece.
    Workpiece,
    /// Between `b` and `t`: it carries the tool.
    Tool,
}

impl Side {
    /// `−1` for the workpiece side (the element physically moves opposite to the command),
    /// `+1` for the tool side.
    #[must_use]
    pub const fn sign(self) -> f64 {
        match self {
            Side::Workpiece => -1.0,
            Side::Tool => 1.0,
        }
    }
}

/// A moving element of the chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Axis {
    /// A linear slide.
    Linear(LinearAxis),
    /// A rotary axis.
    Rotary(RotaryAxis),
}

impl Axis {
    /// The letter in chain notation.
    #[must_use]
    pub const fn letter(self) -> char {
        match self {
            Axis::Linear(a) => a.letter(),
            Axis::Rotary(a) => a.letter(),
        }
    }
}

/// What is wrong with a chain string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ChainError {
    /// A character that is not one of `w b t X Y Z A B C`.
    #[error("unknown axis letter '{element}' at position {index} in chain \"{chain}\" (expected w, b, t, X, Y, Z, A, B, C)")]
    UnknownElement {
        /// The offending character.
        element: char,
        /// Its 0-based index among the non-space characters.
        index: usize,
        /// The chain as given.
        chain: String,
    },
    /// An element given more than once.
    #[error("element '{element}' appears more than once in chain \"{chain}\"")]
    Duplicate {
        /// The repeated element.
        element: char,
        /// The chain as given.
        chain: String,
    },
    /// A required element is absent.
    #[error(
        "element '{element}' is missing from chain \"{chain}\" (need one each of w, b, t, X, Y, Z)"
    )]
    Missing {
        /// The absent element.
        element: char,
        /// The chain as given.
        chain: String,
    },
    /// `w` not first or `t` not last.
    #[error("chain \"{chain}\" must start with the workpiece 'w' and end with the tool 't'")]
    Ends {
        /// The chain as given.
        chain: String,
    },
}

/// A validated five-axis (or three/four-axis) chain: the moving elements from the workpiece to
/// the tool, and how many of them sit on the workpiece side.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct Chain {
    elements: Vec<Axis>,
    n_workpiece_side: usize,
}

impl Chain {
    /// Parses and validates a chain such as `"w C A Y X b Z t"` (spaces optional).
    ///
    /// # Errors
    /// [`ChainError`] naming the first problem: an unknown letter, a duplicate, a missing
    /// element, or `w`/`t` not at the ends.
    pub fn parse(text: &str) -> Result<Chain, ChainError> {
        let chain = || text.to_string();
        let letters: Vec<char> = text.chars().filter(|c| !c.is_whitespace()).collect();
        let mut seen = Vec::new();
        let mut elements = Vec::new();
        let mut n_workpiece_side = None;
        for (index, &c) in letters.iter().enumerate() {
            if !"wbtXYZABC".contains(c) {
                return Err(ChainError::UnknownElement {
                    element: c,
                    index,
                    chain: chain(),
                });
            }
            if seen.contains(&c) {
                return Err(ChainError::Duplicate {
                    element: c,
                    chain: chain(),
                });
            }
            seen.push(c);
            match c {
                'X' => elements.push(Axis::Linear(LinearAxis::X)),
                'Y' => elements.push(Axis::Linear(LinearAxis::Y)),
                'Z' => elements.push(Axis::Linear(LinearAxis::Z)),
                'A' => elements.push(Axis::Rotary(RotaryAxis::A)),
                'B' => elements.push(Axis::Rotary(RotaryAxis::B)),
                'C' => elements.push(Axis::Rotary(RotaryAxis::C)),
                'b' => n_workpiece_side = Some(elements.len()),
                _ => {}
            }
        }
        for required in ['w', 'b', 't', 'X', 'Y', 'Z'] {
            if !seen.contains(&required) {
                return Err(ChainError::Missing {
                    element: required,
                    chain: chain(),
                });
            }
        }
        if letters.first() != Some(&'w') || letters.last() != Some(&'t') {
            return Err(ChainError::Ends { chain: chain() });
        }
        Ok(Chain {
            elements,
            n_workpiece_side: n_workpiece_side.unwrap_or(0),
        })
    }

    /// The moving elements from the workpiece to the tool.
    #[must_use]
    pub fn elements(&self) -> &[Axis] {
        &self.elements
    }

    /// How many elements sit between `w` and `b`.
    #[must_use]
    pub fn n_workpiece_side(&self) -> usize {
        self.n_workpiece_side
    }

    /// Side of the element at `index` (in [`Chain::elements`] order).
    #[must_use]
    pub fn side_of(&self, index: usize) -> Side {
        if index < self.n_workpiece_side {
            Side::Workpiece
        } else {
            Side::Tool
        }
    }

    /// The rotary axes in chain order (workpiece to tool).
    #[must_use]
    pub fn rotary_axes(&self) -> Vec<RotaryAxis> {
        self.elements
            .iter()
            .filter_map(|e| match e {
                Axis::Rotary(r) => Some(*r),
                Axis::Linear(_) => None,
            })
            .collect()
    }
}

impl fmt::Display for Chain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = vec!['w'];
        for (i, e) in self.elements.iter().enumerate() {
            if i == self.n_workpiece_side {
                parts.push('b');
            }
            parts.push(e.letter());
        }
        if self.n_workpiece_side == self.elements.len() {
            parts.push('b');
        }
        parts.push('t');
        let text: Vec<String> = parts.iter().map(char::to_string).collect();
        f.write_str(&text.join(" "))
    }
}

impl TryFrom<String> for Chain {
    type Error = ChainError;
    fn try_from(s: String) -> Result<Self, Self::Error> {
        Chain::parse(&s)
    }
}

impl From<Chain> for String {
    fn from(c: Chain) -> String {
        c.to_string()
    }
}

/// Nominal average line of one rotary axis, in bed coordinates at machine zero.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RotaryGeometry {
    /// Which axis.
    pub axis: RotaryAxis,
    /// A point of its nominal axis line, mm.
    pub point_mm: [f64; 3],
}

/// Nominal geometry of a five-axis machine: what its builder publishes, hence knowledge-side.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Geometry {
    /// The chain.
    pub chain: Chain,
    /// Nominal line of each rotary axis, in [`Chain::rotary_axes`] order.
    pub rotary: Vec<RotaryGeometry>,
    /// Tool (stylus) tip relative to the spindle gauge point, mm, spindle frame.
    pub tool_offset_mm: [f64; 3],
    /// Origin of the workpiece frame (the reference sphere's centre), bed coordinates at
    /// machine zero, mm.
    pub datum_mm: [f64; 3],
}

/// What is inconsistent in a [`Geometry`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometryError {
    /// Rotary axis lines given do not match the chain's rotary axes.
    #[error("the chain {chain} has rotary axes {want:?} but geometry is given for {got:?}")]
    RotaryMismatch {
        /// The chain.
        chain: String,
        /// Its rotary axes.
        want: Vec<char>,
        /// The axes the geometry describes.
        got: Vec<char>,
    },
    /// A non-finite number.
    #[error("geometry value {what} is not finite")]
    NotFinite {
        /// Which value.
        what: &'static str,
    },
}

impl Geometry {
    /// Checks that the rotary lines match the chain and every number is finite.
    ///
    /// # Errors
    /// [`GeometryError`].
    pub fn validate(&self) -> Result<(), GeometryError> {
        let want: Vec<char> = self
            .chain
            .rotary_axes()
            .iter()
            .map(|a| a.letter())
            .collect();
        let got: Vec<char> = self.rotary.iter().map(|r| r.axis.letter()).collect();
        if want != got {
            return Err(GeometryError::RotaryMismatch {
                chain: self.chain.to_string(),
                want,
                got,
            });
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        if !finite(&self.tool_offset_mm) {
            return Err(GeometryError::NotFinite {
                what: "tool_offset_mm",
            });
        }
        if !finite(&self.datum_mm) {
            return Err(GeometryError::NotFinite { what: "datum_mm" });
        }
        if !self.rotary.iter().all(|r| finite(&r.point_mm)) {
            return Err(GeometryError::NotFinite {
                what: "rotary point_mm",
            });
        }
        Ok(())
    }

    /// Index into [`Geometry::rotary`] of the rotary axis `axis`, if the machine has it.
    #[must_use]
    pub fn rotary_index(&self, axis: RotaryAxis) -> Option<usize> {
        self.rotary.iter().position(|r| r.axis == axis)
    }
}

/// A commanded configuration: the three linear axes (mm) and the rotary angles (degrees) in
/// [`Geometry::rotary`] order (unused entries zero).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose {
    /// X, Y, Z, mm.
    pub linear_mm: [f64; 3],
    /// Rotary angles, degrees, in [`Geometry::rotary`] order.
    pub rotary_deg: [f64; 2],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_trunnion_chain_has_four_workpiece_side_elements() {
        let c = Chain::parse("w C A Y X b Z t").unwrap();
        assert_eq!(c.n_workpiece_side(), 4);
        assert_eq!(c.rotary_axes(), vec![RotaryAxis::C, RotaryAxis::A]);
        assert_eq!(c.side_of(3), Side::Workpiece);
        assert_eq!(c.side_of(4), Side::Tool);
        assert_eq!(c.to_string(), "w C A Y X b Z t");
        assert_eq!(Chain::parse("wCAYXbZt").unwrap(), c);
    }

    #[test]
    fn an_unknown_letter_is_named() {
        let e = Chain::parse("w C D Y X b Z t").unwrap_err();
        assert!(e.to_string().contains("unknown axis letter 'D'"), "{e}");
    }

    #[test]
    fn duplicates_missing_and_misplaced_ends_are_refused() {
        assert!(matches!(
            Chain::parse("w C C Y X b Z t"),
            Err(ChainError::Duplicate { element: 'C', .. })
        ));
        assert!(matches!(
            Chain::parse("w C A X b Z t"),
            Err(ChainError::Missing { element: 'Y', .. })
        ));
        assert!(matches!(
            Chain::parse("C w A Y X b Z t"),
            Err(ChainError::Ends { .. })
        ));
    }
}
