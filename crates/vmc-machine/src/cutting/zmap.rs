//! The Z-map: the stock as a height field on a regular XY grid.
//!
//! The stock starts as a box. Each cell of the grid (centre (x_i, y_j)) holds the height of the
//! top of the material above it, `top_mm`; the material of a cell spans from the box's bottom to
//! that height, and a cell whose top is at or below the bottom is empty. A flat-end tool with
//! its tip at height z removes, in every cell whose centre lies in its disc, what is above z:
//! `top = min(top, z)`. Outside the box there is no material.
//!
//! The spacing is shrunk, per axis, so that a whole number of cells fits each side of the box
//! exactly: `n_x = ⌈(x_max − x_min)/g⌉`, `g_x = (x_max − x_min)/n_x ≤ g`.

use super::{CuttingError, StockBox};

/// Most cells a Z-map may have (memory: 8 bytes each, so 400 MB at the limit).
pub const MAX_CELLS: usize = 50_000_000;

/// Height field of the stock on a regular XY grid (mm).
#[derive(Debug, Clone, PartialEq)]
pub struct ZMap {
    min_mm: [f64; 2],
    spacing_mm: [f64; 2],
    cells: [usize; 2],
    bottom_mm: f64,
    top_mm: Vec<f64>,
}

impl ZMap {
    /// The whole stock box on a grid of at most `spacing_mm` (mm).
    ///
    /// # Errors
    /// A box with min ≥ max on an axis or a non-finite corner, a spacing that is not > 0, more
    /// than [`MAX_CELLS`] cells.
    pub fn new(stock: &StockBox, spacing_mm: f64) -> Result<Self, CuttingError> {
        stock.validate()?;
        if !(spacing_mm > 0.0 && spacing_mm.is_finite()) {
            return Err(CuttingError::Spacing { spacing_mm });
        }
        let mut cells = [0usize; 2];
        let mut spacing = [0.0; 2];
        for k in 0..2 {
            let side_mm = stock.max_mm[k] - stock.min_mm[k];
            let n = (side_mm / spacing_mm).ceil();
            if n > MAX_CELLS as f64 {
                return Err(CuttingError::TooManyCells {
                    cells: n,
                    max: MAX_CELLS,
                });
            }
            cells[k] = (n as usize).max(1);
            spacing[k] = side_mm / cells[k] as f64;
        }
        let total = cells[0] as f64 * cells[1] as f64;
        if total > MAX_CELLS as f64 {
            return Err(CuttingError::TooManyCells {
                cells: total,
                max: MAX_CELLS,
            });
        }
        Ok(Self {
            min_mm: [stock.min_mm[0], stock.min_mm[1]],
            spacing_mm: spacing,
            cells,
            bottom_mm: stock.min_mm[2],
            top_mm: vec![stock.max_mm[2]; cells[0] * cells[1]],
        })
    }

    /// Cell spacing along X and Y (mm).
    pub fn spacing_mm(&self) -> [f64; 2] {
        self.spacing_mm
    }

    /// Number of cells along X and Y.
    pub fn cells(&self) -> [usize; 2] {
        self.cells
    }

    /// Height of the stock's bottom (mm).
    pub fn bottom_mm(&self) -> f64 {
        self.bottom_mm
    }

    /// Centre of cell (i, j) (mm).
    pub fn cell_centre_mm(&self, i: usize, j: usize) -> [f64; 2] {
        [
            self.min_mm[0] + (i as f64 + 0.5) * self.spacing_mm[0],
            self.min_mm[1] + (j as f64 + 0.5) * self.spacing_mm[1],
        ]
    }

    /// Top of the material in cell (i, j) (mm); at or below [`ZMap::bottom_mm`] when empty.
    pub fn top_at_cell(&self, i: usize, j: usize) -> f64 {
        self.top_mm[j * self.cells[0] + i]
    }

    /// Top of the material in the cell that contains the point (x, y), or `None` outside the
    /// stock or where the cell is empty (mm).
    pub fn top_at(&self, x_mm: f64, y_mm: f64) -> Option<f64> {
        let fi = (x_mm - self.min_mm[0]) / self.spacing_mm[0];
        let fj = (y_mm - self.min_mm[1]) / self.spacing_mm[1];
        if !(fi >= 0.0 && fj >= 0.0) {
            return None;
        }
        let (i, j) = (fi as usize, fj as usize);
        if i >= self.cells[0] || j >= self.cells[1] {
            return None;
        }
        let top = self.top_at_cell(i, j);
        (top > self.bottom_mm).then_some(top)
    }

    /// Removes the material above `z_mm` in every cell whose centre lies within `radius_mm` of
    /// (x, y): the footprint of a flat-end tool with its tip at that point.
    pub fn cut_disc(&mut self, centre_mm: [f64; 2], radius_mm: f64, z_mm: f64) {
        let nx = self.cells[0];
        for (j, i_lo, i_hi) in self.disc_spans(centre_mm, radius_mm) {
            for top in &mut self.top_mm[j * nx + i_lo..=j * nx + i_hi] {
                *top = top.min(z_mm);
            }
        }
    }

    /// The highest material top (mm) among the non-empty cells whose centre lies within
    /// `radius_mm` of (x, y), with that cell's centre; `None` when the disc holds no material.
    #[must_use]
    pub fn highest_in_disc(&self, centre_mm: [f64; 2], radius_mm: f64) -> Option<(f64, [f64; 2])> {
        let nx = self.cells[0];
        let mut best: Option<(f64, [f64; 2])> = None;
        for (j, i_lo, i_hi) in self.disc_spans(centre_mm, radius_mm) {
            for i in i_lo..=i_hi {
                let top = self.top_mm[j * nx + i];
                if top > self.bottom_mm && best.is_none_or(|(b, _)| top > b) {
                    best = Some((top, self.cell_centre_mm(i, j)));
                }
            }
        }
        best
    }

    /// The cells whose centre lies within `radius_mm` of (x, y), row by row: (j, first i, last
    /// i), rows without such a cell left out.
    fn disc_spans(
        &self,
        centre_mm: [f64; 2],
        radius_mm: f64,
    ) -> impl Iterator<Item = (usize, usize, usize)> {
        let [gx, gy] = self.spacing_mm;
        let [nx, ny] = self.cells;
        let min_mm = self.min_mm;
        // Rows whose centre y is within the disc: (j + 0.5)·gy in [cy − r, cy + r].
        let j_lo = ((centre_mm[1] - radius_mm - min_mm[1]) / gy - 0.5).ceil();
        let j_hi = ((centre_mm[1] + radius_mm - min_mm[1]) / gy - 0.5).floor();
        let rows = if j_hi < 0.0 || j_lo >= ny as f64 || j_lo > j_hi {
            0..0
        } else {
            j_lo.max(0.0) as usize..(j_hi as usize).min(ny - 1) + 1
        };
        rows.filter_map(move |j| {
            let dy = min_mm[1] + (j as f64 + 0.5) * gy - centre_mm[1];
            let half = (radius_mm * radius_mm - dy * dy).max(0.0).sqrt();
            let i_lo = ((centre_mm[0] - half - min_mm[0]) / gx - 0.5).ceil();
            let i_hi = ((centre_mm[0] + half - min_mm[0]) / gx - 0.5).floor();
            if i_hi < 0.0 || i_lo >= nx as f64 || i_lo > i_hi {
                return None;
            }
            Some((j, i_lo.max(0.0) as usize, (i_hi as usize).min(nx - 1)))
        })
    }

    /// Volume of material left (mm³).
    pub fn volume_mm3(&self) -> f64 {
        let area = self.spacing_mm[0] * self.spacing_mm[1];
        self.top_mm
            .iter()
            .map(|t| (t - self.bottom_mm).max(0.0) * area)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block() -> StockBox {
        StockBox {
            min_mm: [0.0, 0.0, -10.0],
            max_mm: [40.0, 20.0, 0.0],
        }
    }

    #[test]
    fn the_grid_fits_the_box_exactly_with_at_most_the_asked_spacing() {
        let z = ZMap::new(&block(), 0.3).unwrap();
        assert_eq!(z.cells(), [134, 67]);
        assert!((z.spacing_mm()[0] * 134.0 - 40.0).abs() < 1e-12);
        assert!(z.spacing_mm()[1] <= 0.3);
        assert_eq!(z.top_at(39.999, 19.999), Some(0.0));
        assert_eq!(z.top_at(40.001, 10.0), None);
        assert_eq!(z.top_at(-0.001, 10.0), None);
        // 40 × 20 × 10 mm of material.
        assert!((z.volume_mm3() - 8000.0).abs() < 1e-6);
    }

    #[test]
    fn a_disc_removes_the_cells_whose_centres_it_covers_down_to_the_tip() {
        let mut z = ZMap::new(&block(), 0.5).unwrap();
        z.cut_disc([20.0, 10.0], 3.0, -2.0);
        for i in 0..80 {
            for j in 0..40 {
                let c = z.cell_centre_mm(i, j);
                let inside = (c[0] - 20.0).hypot(c[1] - 10.0) <= 3.0;
                let want = if inside { -2.0 } else { 0.0 };
                assert_eq!(z.top_at_cell(i, j), want, "cell {i} {j} at {c:?}");
            }
        }
        // π·3² mm² × 2 mm, to the grid's resolution (1 %).
        let removed = 8000.0 - z.volume_mm3();
        assert!((removed / (std::f64::consts::PI * 18.0) - 1.0).abs() < 0.01);
        // A disc hanging over the edge, and one wholly outside, do not panic.
        z.cut_disc([0.0, 0.0], 5.0, -20.0);
        assert_eq!(z.top_at(0.1, 0.1), None);
        z.cut_disc([100.0, -50.0], 5.0, -20.0);
    }

    #[test]
    fn the_highest_material_under_a_disc_ignores_cut_and_outside_cells() {
        let mut z = ZMap::new(&block(), 0.5).unwrap();
        z.cut_disc([20.0, 10.0], 3.0, -4.0);
        // The same disc sees the floor it cut; a wider one reaches the uncut top.
        let (top, _) = z.highest_in_disc([20.0, 10.0], 3.0).unwrap();
        assert_eq!(top, -4.0);
        let (top, at) = z.highest_in_disc([20.0, 10.0], 3.6).unwrap();
        assert_eq!(top, 0.0);
        assert!((at[0] - 20.0).hypot(at[1] - 10.0) > 3.0);
        // Empty cells and cells outside the stock hold nothing.
        z.cut_disc([30.0, 10.0], 2.0, -10.0);
        assert!(z.highest_in_disc([30.0, 10.0], 2.0).is_none());
        assert!(z.highest_in_disc([100.0, 10.0], 5.0).is_none());
    }

    #[test]
    fn bad_grids_are_refused() {
        assert!(matches!(
            ZMap::new(&block(), 0.0),
            Err(CuttingError::Spacing { .. })
        ));
        assert!(matches!(
            ZMap::new(&block(), 1e-4),
            Err(CuttingError::TooManyCells { .. })
        ));
    }
}
