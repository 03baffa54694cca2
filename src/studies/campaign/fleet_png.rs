//! The fleet's histograms as a PNG picture: four panels in a 2 × 2 grid — top left the
//! machines' median reduction (%), top right their worst-run reduction (%), bottom left their
//! max residual |E'| (µm), bottom right their worst residual share of the thermal part (%) —
//! each with its bars scaled to the tallest, and a red line at the goal where
//! the quantity has one (80 % reduction, 2 µm). The picture has no text: the axis ranges are
//! printed by the caller.

use super::fleet::{FleetSummary, GOAL_MAX_RESIDUAL_UM, GOAL_REDUCTION};
use super::histogram::Histogram;

/// Picture width and height, pixels.
pub const SIZE_PX: (u32, u32) = (800, 560);

/// One panel's histogram and its goal line, if any.
type Panel = (Option<Histogram>, Option<f64>);

/// The four panels, in grid order.
pub fn panels(fleet: &FleetSummary) -> Vec<(String, Panel)> {
    let goals = [
        None,
        Some(GOAL_REDUCTION * 100.0),
        Some(GOAL_MAX_RESIDUAL_UM),
        None,
    ];
    fleet
        .quantities
        .iter()
        .zip(goals)
        .map(|(q, goal)| (q.name.to_string(), (q.histogram.clone(), goal)))
        .collect()
}

/// The picture as RGB pixels, row by row.
pub fn raster(panels: &[(String, Panel)]) -> Vec<u8> {
    let (w, h) = (SIZE_PX.0 as usize, SIZE_PX.1 as usize);
    let mut px = vec![255u8; w * h * 3];
    let mut fill = |x0: usize, y0: usize, x1: usize, y1: usize, c: [u8; 3]| {
        for y in y0.min(h)..y1.min(h) {
            for x in x0.min(w)..x1.min(w) {
                px[(y * w + x) * 3..(y * w + x) * 3 + 3].copy_from_slice(&c);
            }
        }
    };
    let (pw, ph) = (w / 2, h / 2);
    for (k, (_, (hist, goal))) in panels.iter().enumerate().take(4) {
        let (ox, oy) = ((k % 2) * pw, (k / 2) * ph);
        let (l, r, t, b) = (ox + 30, ox + pw - 20, oy + 20, oy + ph - 30);
        fill(l, b, r, b + 2, [0, 0, 0]); // abscissa
        fill(l - 2, t, l, b, [0, 0, 0]); // ordinate
        let Some(hist) = hist else { continue };
        let n = hist.counts.len().max(1);
        let tallest = hist.counts.iter().copied().max().unwrap_or(1).max(1);
        let bar_w = (r - l) / n;
        for (i, &c) in hist.counts.iter().enumerate() {
            let top = b - ((b - t) as f64 * c as f64 / tallest as f64).round() as usize;
            fill(
                l + i * bar_w + 1,
                top,
                l + (i + 1) * bar_w - 1,
                b,
                [70, 110, 180],
            );
        }
        if let Some(g) = goal {
            let span = hist.width * n as f64;
            let at = (g - hist.lo) / span;
            if (0.0..=1.0).contains(&at) {
                let x = l + (at * (bar_w * n) as f64).round() as usize;
                fill(x.saturating_sub(1), t, x + 1, b, [210, 40, 40]);
            }
        }
    }
    px
}

/// The picture encoded as PNG.
///
/// # Errors
/// The encoder's.
pub fn encode_png(rgb: &[u8]) -> Result<Vec<u8>, png::EncodingError> {
    let mut bytes = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut bytes, SIZE_PX.0, SIZE_PX.1);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header()?;
        w.write_image_data(rgb)?;
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bars_are_as_tall_as_their_counts_and_the_png_decodes_to_the_raster() {
        let hist = Histogram {
            lo: 0.0,
            width: 1.0,
            counts: vec![1, 2],
        };
        let panels = vec![("q".to_string(), (Some(hist), None))];
        let px = raster(&panels);
        let blue = |x: usize, y: usize| px[(y * SIZE_PX.0 as usize + x) * 3] == 70;
        // Panel 0: bars from x = 30 to 380 (175 px each), from y = 250 up to 20.
        let height = |x: usize| (20..250).filter(|&y| blue(x, y)).count();
        assert_eq!(height(300), 230);
        assert_eq!(height(100), 115);
        let png = encode_png(&px).unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        reader.next_frame(&mut buf).unwrap();
        assert_eq!(buf, px);
    }
}
