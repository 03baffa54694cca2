//! Material removal and tool engagement for 3-axis milling with a flat-end mill.
//!
//! Model: the stock is a Z-map ([`zmap`]: a height field on a regular XY grid) cut by a
//! cylindrical tool of radius R whose tip follows a path. Along each path the tool is sampled
//! at equal steps; at each sample [`engagement`] finds which part of the tool's periphery is in
//! material (the engaged arc, hence the radial immersion a_e/D and the side of the feed
//! direction it is on) and how much material stands above the tip there (the axial depth a_p),
//! then removes the tool's disc from the stock. Arcs and helices are sampled on their true path
//! by the caller's [`ToolPath`].
//!
//! Units: mm and rad. The module is pure: no files, no terminal, no G-code; the chatter check
//! feeds it the paths of a program.

pub mod engagement;
pub mod zmap;

use thiserror::Error;

pub use engagement::{Contact, ContactKind, EngagedArc, Line, Side, Sweep, ToolPath};
pub use zmap::ZMap;

/// A box of stock, axis-aligned, in the coordinates of the tool paths (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StockBox {
    /// Lowest corner (mm).
    pub min_mm: [f64; 3],
    /// Highest corner (mm).
    pub max_mm: [f64; 3],
}

impl StockBox {
    /// Checks that every corner coordinate is finite and min < max on each axis.
    ///
    /// # Errors
    /// [`CuttingError::EmptyStock`] naming the first axis at fault.
    pub fn validate(&self) -> Result<(), CuttingError> {
        for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
            let (lo, hi) = (self.min_mm[k], self.max_mm[k]);
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(CuttingError::EmptyStock {
                    axis,
                    min_mm: lo,
                    max_mm: hi,
                });
            }
        }
        Ok(())
    }
}

/// A stock, grid or tool that the material-removal model cannot use.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CuttingError {
    /// min ≥ max (or a non-finite value) on an axis of the stock box.
    #[error("the stock box is empty along {axis}: min_mm {min_mm} must be below max_mm {max_mm}")]
    EmptyStock {
        /// `x`, `y` or `z`.
        axis: &'static str,
        /// The box's minimum on that axis (mm).
        min_mm: f64,
        /// The box's maximum on that axis (mm).
        max_mm: f64,
    },
    /// The grid spacing is not a positive number.
    #[error("the grid spacing must be > 0 mm, got {spacing_mm}")]
    Spacing {
        /// The spacing given (mm).
        spacing_mm: f64,
    },
    /// The grid would have too many cells.
    #[error("the Z-map would have {cells:.3e} cells, more than {max}: use a larger grid spacing")]
    TooManyCells {
        /// Cells asked for.
        cells: f64,
        /// The limit.
        max: usize,
    },
    /// The grid is too coarse to see the tool's engagement.
    #[error("the grid spacing {spacing_mm} mm is too coarse for a {diameter_mm} mm tool: at most a quarter of its diameter")]
    CoarseGrid {
        /// The spacing given (mm).
        spacing_mm: f64,
        /// The tool's diameter (mm).
        diameter_mm: f64,
    },
    /// The tool's diameter is not a positive number.
    #[error("the tool diameter must be > 0 mm, got {diameter_mm}")]
    ToolDiameter {
        /// The diameter given (mm).
        diameter_mm: f64,
    },
}
