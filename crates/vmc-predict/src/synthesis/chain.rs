//! Kinematic chain of a 3-axis machine in ISO 10791-6 notation, workpiece to tool.
//!
//! A chain is six elements read from the workpiece to the tool, e.g. `"w X Y b Z t"`:
//! the workpiece `w` sits on the X carriage (table), X on Y (saddle), Y on the bed `b`; on the
//! other side of the bed the Z carriage (head) carries the tool `t`. Axes between `w` and `b` are
//! *workpiece-side* (they move the workpiece, so by ISO 841 the carriage physically moves opposite
//! to the commanded direction); axes between `b` and `t` are *tool-side*.
//!
//! Parsing validates the structure once and precomputes what the first-order synthesis needs per
//! axis (side sign and which axis positions enter its Abbe arm), so a query is a few flops.
//! Whitespace between elements is optional: `"wXYbZt"` is the same chain.

use std::fmt;
use std::str::FromStr;

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
    /// All three axes in index order.
    pub const ALL: [LinearAxis; 3] = [LinearAxis::X, LinearAxis::Y, LinearAxis::Z];

    /// Index of the axis in `[x, y, z]` arrays.
    #[must_use]
    pub const fn index(self) -> usize {
        match self {
            LinearAxis::X => 0,
            LinearAxis::Y => 1,
            LinearAxis::Z => 2,
        }
    }

    /// The axis named by an upper-case letter in chain notation, if any.
    #[must_use]
    pub const fn from_letter(letter: char) -> Option<LinearAxis> {
        match letter {
            'X' => Some(LinearAxis::X),
            'Y' => Some(LinearAxis::Y),
            'Z' => Some(LinearAxis::Z),
            _ => None,
        }
    }

    /// The letter of the axis in chain notation.
    #[must_use]
    pub const fn letter(self) -> char {
        match self {
            LinearAxis::X => 'X',
            LinearAxis::Y => 'Y',
            LinearAxis::Z => 'Z',
        }
    }
}

/// Which side of the bed an axis sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Side {
    /// Between `w` and `b`: the axis carries the workpiece (e.g. a table or saddle).
    Workpiece,
    /// Between `b` and `t`: the axis carries the tool (e.g. a head or column slide).
    Tool,
}

impl Side {
    /// Sign with which this side's carriage errors enter the tool-to-workpiece error:
    /// `+1` for the tool side, `−1` for the workpiece side.
    #[must_use]
    pub const fn sign(self) -> f64 {
        match self {
            Side::Workpiece => -1.0,
            Side::Tool => 1.0,
        }
    }
}

/// What is wrong with a chain string.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ChainError {
    /// A character that is not one of `w b t X Y Z`.
    #[error("unknown element '{element}' at position {index} in chain \"{chain}\" (expected w, b, t, X, Y, Z)")]
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
    #[error("element '{element}' is missing from chain \"{chain}\" (need exactly one each of w, b, t, X, Y, Z)")]
    Missing {
        /// The absent element.
        element: char,
        /// The chain as given.
        chain: String,
    },
    /// The chain does not start at the workpiece.
    #[error("chain \"{chain}\" must start with the workpiece 'w', found '{found}'")]
    WorkpieceNotFirst {
        /// The first element found.
        found: char,
        /// The chain as given.
        chain: String,
    },
    /// The chain does not end at the tool.
    #[error("chain \"{chain}\" must end with the tool 't', found '{found}'")]
    ToolNotLast {
        /// The last element found.
        found: char,
        /// The chain as given.
        chain: String,
    },
}

/// A validated workpiece-to-tool chain of a 3-axis machine, with the per-axis data the
/// first-order synthesis needs precomputed.
///
/// Serialises as its canonical string (`"w X Y b Z t"`), so machine files hold the ISO notation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct Chain {
    /// Axes in chain order from `w` to `t` (the bed sits after the first `n_workpiece_side`).
    order: [LinearAxis; 3],
    /// How many axes sit between `w` and `b`.
    n_workpiece_side: usize,
    /// Side of each axis, indexed by axis.
    side: [Side; 3],
    /// `arm_mask[k][i]` is 1.0 when the position of axis `i` enters the Abbe arm of axis `k`'s
    /// angular errors, else 0.0 (see the `synthesis` module doc for the rule).
    arm_mask: [[f64; 3]; 3],
}

impl Chain {
    /// Parses and validates an ISO 10791-6 style chain such as `"w X Y b Z t"`.
    ///
    /// # Errors
    /// [`ChainError`] naming the first problem found: an unknown element, a duplicate, a missing
    /// element, `w` not first or `t` not last.
    pub fn parse(text: &str) -> Result<Chain, ChainError> {
        let chain = || text.to_string();
        let elements: Vec<char> = text.chars().filter(|c| !c.is_whitespace()).collect();
        for (index, &element) in elements.iter().enumerate() {
            if !"wbtXYZ".contains(element) {
                return Err(ChainError::UnknownElement {
                    element,
                    index,
                    chain: chain(),
                });
            }
        }
        for (i, &element) in elements.iter().enumerate() {
            if elements[..i].contains(&element) {
                return Err(ChainError::Duplicate {
                    element,
                    chain: chain(),
                });
            }
        }
        if let Some(element) = "wbtXYZ".chars().find(|c| !elements.contains(c)) {
            return Err(ChainError::Missing {
                element,
                chain: chain(),
            });
        }
        // Now exactly six distinct known elements.
        if elements[0] != 'w' {
            return Err(ChainError::WorkpieceNotFirst {
                found: elements[0],
                chain: chain(),
            });
        }
        if elements[5] != 't' {
            return Err(ChainError::ToolNotLast {
                found: elements[5],
                chain: chain(),
            });
        }
        let mut order = [LinearAxis::X; 3];
        let mut n = 0;
        let mut n_workpiece_side = 0;
        for &element in &elements[1..5] {
            if element == 'b' {
                n_workpiece_side = n;
            } else if let Some(axis) = LinearAxis::from_letter(element) {
                order[n] = axis;
                n += 1;
            }
        }
        Ok(Chain::from_order(order, n_workpiece_side))
    }

    /// Builds the precomputed tables from a validated axis order.
    fn from_order(order: [LinearAxis; 3], n_workpiece_side: usize) -> Chain {
        let mut side = [Side::Tool; 3];
        let mut arm_mask = [[0.0; 3]; 3];
        for (pos, &axis) in order.iter().enumerate() {
            let k = axis.index();
            side[k] = if pos < n_workpiece_side {
                Side::Workpiece
            } else {
                Side::Tool
            };
            for (other_pos, &other) in order.iter().enumerate() {
                // "carried by k": further from the bed than k on k's own side.
                let carried_by_k = if pos < n_workpiece_side {
                    other_pos < pos
                } else {
                    other_pos > pos
                };
                let in_arm = match side[k] {
                    // The arm runs from k's reference point to the tool tip: the axes k carries
                    // (tool side) move the tip away from that point.
                    Side::Tool => carried_by_k,
                    // The tip is fixed in the bed while k's reference point moves with k and every
                    // axis under it: all positions enter except those of axes k carries.
                    Side::Workpiece => !carried_by_k,
                };
                arm_mask[k][other.index()] = if in_arm { 1.0 } else { 0.0 };
            }
        }
        Chain {
            order,
            n_workpiece_side,
            side,
            arm_mask,
        }
    }

    /// Workpiece-side axes in chain order, from the one carrying the workpiece to the one on the bed.
    #[must_use]
    pub fn workpiece_side(&self) -> &[LinearAxis] {
        &self.order[..self.n_workpiece_side]
    }

    /// Tool-side axes in chain order, from the one on the bed to the one carrying the tool.
    #[must_use]
    pub fn tool_side(&self) -> &[LinearAxis] {
        &self.order[self.n_workpiece_side..]
    }

    /// Which side of the bed `axis` sits on.
    #[must_use]
    pub fn side(&self, axis: LinearAxis) -> Side {
        self.side[axis.index()]
    }

    /// Whether the position of `position_axis` enters the Abbe arm of `error_axis`'s angular errors.
    #[must_use]
    pub fn arm_includes(&self, error_axis: LinearAxis, position_axis: LinearAxis) -> bool {
        self.arm_mask[error_axis.index()][position_axis.index()] != 0.0
    }

    /// Arm of `error_axis`'s angular errors at axis positions `pos_mm` with tool offset
    /// `tool_offset_mm`: from the axis's reference point to the nominal tool tip, in mm.
    #[inline]
    #[must_use]
    pub fn abbe_arm_mm(
        &self,
        error_axis: LinearAxis,
        pos_mm: [f64; 3],
        tool_offset_mm: [f64; 3],
    ) -> [f64; 3] {
        let m = &self.arm_mask[error_axis.index()];
        [
            tool_offset_mm[0] + m[0] * pos_mm[0],
            tool_offset_mm[1] + m[1] * pos_mm[1],
            tool_offset_mm[2] + m[2] * pos_mm[2],
        ]
    }
}

impl fmt::Display for Chain {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "w")?;
        for axis in self.workpiece_side() {
            write!(f, " {}", axis.letter())?;
        }
        write!(f, " b")?;
        for axis in self.tool_side() {
            write!(f, " {}", axis.letter())?;
        }
        write!(f, " t")
    }
}

impl FromStr for Chain {
    type Err = ChainError;
    fn from_str(s: &str) -> Result<Chain, ChainError> {
        Chain::parse(s)
    }
}

impl TryFrom<String> for Chain {
    type Error = ChainError;
    fn try_from(s: String) -> Result<Chain, ChainError> {
        Chain::parse(&s)
    }
}

impl From<Chain> for String {
    fn from(chain: Chain) -> String {
        chain.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use LinearAxis::{X, Y, Z};

    #[test]
    fn reference_chain_parses_into_sides_and_orders() {
        let chain = Chain::parse("w X Y b Z t").unwrap();
        assert_eq!(chain.workpiece_side(), &[X, Y]);
        assert_eq!(chain.tool_side(), &[Z]);
        assert_eq!(chain.side(X), Side::Workpiece);
        assert_eq!(chain.side(Z), Side::Tool);
        assert_eq!(chain.to_string(), "w X Y b Z t");
    }

    #[test]
    fn spaces_are_optional_and_display_is_canonical() {
        let chain: Chain = "wYbXZt".parse().unwrap();
        assert_eq!(chain.to_string(), "w Y b X Z t");
        assert_eq!(chain.tool_side(), &[X, Z]);
    }

    #[test]
    fn bed_may_sit_at_either_end() {
        let all_tool = Chain::parse("w b X Y Z t").unwrap();
        assert!(all_tool.workpiece_side().is_empty());
        let all_work = Chain::parse("w Z Y X b t").unwrap();
        assert!(all_work.tool_side().is_empty());
        assert_eq!(all_work.workpiece_side(), &[Z, Y, X]);
    }

    #[test]
    fn arms_of_the_reference_chain_follow_the_carried_rule() {
        let chain = Chain::parse("w X Y b Z t").unwrap();
        // X carries only the workpiece: arm sees X, Y and Z.
        assert!(chain.arm_includes(X, X) && chain.arm_includes(X, Y) && chain.arm_includes(X, Z));
        // Y carries X: arm sees Y and Z, not X.
        assert!(!chain.arm_includes(Y, X) && chain.arm_includes(Y, Y) && chain.arm_includes(Y, Z));
        // Z carries only the tool: arm is the tool offset alone.
        assert!(LinearAxis::ALL.iter().all(|&i| !chain.arm_includes(Z, i)));
        assert_eq!(
            chain.abbe_arm_mm(Y, [100.0, 200.0, -300.0], [1.0, 2.0, -150.0]),
            [1.0, 202.0, -450.0]
        );
    }

    #[test]
    fn tool_side_axis_arm_includes_the_axes_it_carries() {
        let chain = Chain::parse("w Y b X Z t").unwrap();
        assert!(chain.arm_includes(X, Z) && !chain.arm_includes(X, X) && !chain.arm_includes(X, Y));
    }

    #[test]
    fn errors_name_the_problem() {
        let cases = [
            ("w X Q b Z t", "unknown element 'Q' at position 2"),
            ("w X X b Z t", "'X' appears more than once"),
            ("w X Y b Z", "'t' is missing"),
            ("", "'w' is missing"),
            (
                "X w Y b Z t",
                "must start with the workpiece 'w', found 'X'",
            ),
            ("w X Y b t Z", "must end with the tool 't', found 'Z'"),
            ("w x y b z t", "unknown element 'x'"),
        ];
        for (text, expected) in cases {
            let msg = Chain::parse(text).unwrap_err().to_string();
            assert!(msg.contains(expected), "{text:?}: {msg}");
        }
    }

    #[test]
    fn chain_round_trips_through_serde_as_a_string() {
        let chain = Chain::parse("w X Y b Z t").unwrap();
        let json = serde_json::to_string(&chain).unwrap();
        assert_eq!(json, "\"w X Y b Z t\"");
        let back: Chain = serde_json::from_str(&json).unwrap();
        assert_eq!(back, chain);
        assert!(serde_json::from_str::<Chain>("\"w X b Z t\"").is_err());
    }
}
