//! Material removal in the check: every stock box is a Z-map ([`crate::cutting::ZMap`]) that the
//! tool cuts as the program runs.
//!
//! A feed move (G1/G2/G3) with the spindle running removes, at every sample of its path, the
//! material above the tool tip within the tool's disc (a flat-end tool). The head's bodies are
//! checked against what is left: a body (a vertical cylinder from height `z_b` up to `z_t`)
//! touches the stock when a non-empty cell whose centre lies within its radius has its top above
//! `z_b`; the depth reported is the vertical overlap, `min(top, z_t) − z_b`, and the contact point
//! that cell's centre at that height. So a rapid back into a drilled hole or a pocket already
//! cleared, a peck cycle's re-entry, or a holder over a cleared pocket is not a crash, while a
//! rapid into material still there is.
//!
//! Resolution: cells of at most [`CUT_GRID_MM`] (coarser for stocks above 4 million cells), so
//! a wall is known to about half a cell's diagonal; samples along the path as for the other
//! bodies ([`super::SAMPLE_SPACING_MM`]). Cylindrical stocks keep the whole-body check.

use super::{
    crash_reason, overlap, BodyRole, CheckError, HeadBody, MoveKind, Moving, PairHits, Scene,
    CONTACT_TOLERANCE_MM,
};
use crate::cutting::{StockBox, ZMap};
use crate::motion::{Segment, SegmentKind};

/// Largest cell side of a stock's Z-map in the check, mm.
pub const CUT_GRID_MM: f64 = 0.2;

/// Most cells of one stock's Z-map in the check (8 bytes each).
const MAX_CHECK_CELLS: f64 = 4.0e6;

/// The stock boxes of a scene as Z-maps, with their index among the scene's static bodies.
pub(super) struct CutStock {
    maps: Vec<(usize, ZMap)>,
}

impl CutStock {
    /// Z-maps of the scene's stock boxes, whole.
    pub(super) fn new(scene: &Scene) -> Result<Self, CheckError> {
        let mut maps = Vec::new();
        for (si, s) in scene.statics.iter().enumerate().filter(|(_, s)| s.cut) {
            let area_mm2 = (s.hi_mm[0] - s.lo_mm[0]) * (s.hi_mm[1] - s.lo_mm[1]);
            let spacing_mm = CUT_GRID_MM.max((area_mm2 / MAX_CHECK_CELLS).sqrt());
            let stock = StockBox {
                min_mm: s.lo_mm,
                max_mm: s.hi_mm,
            };
            let map = ZMap::new(&stock, spacing_mm).map_err(|e| CheckError::StockGrid {
                body: s.name.clone(),
                message: e.to_string(),
            })?;
            maps.push((si, map));
        }
        Ok(Self { maps })
    }

    /// Checks the head's bodies `heads` against the stocks along `seg` (sampled at `n + 1`
    /// points), then removes what the tool cuts at each sample. Returns the contacts per (body, stock) pair.
    pub(super) fn check_and_cut(
        &mut self,
        seg: &Segment,
        kind: MoveKind,
        scene: &Scene,
        heads: &[Moving],
        n: usize,
        samples: &mut usize,
    ) -> Vec<PairHits> {
        let mut pairs: Vec<(usize, usize, PairHits)> = Vec::new();
        for (mi, m) in heads.iter().enumerate() {
            for (ci, (si, _)) in self.maps.iter().enumerate() {
                if let Some(reason) = crash_reason(m.body, BodyRole::Stock, seg) {
                    pairs.push((mi, ci, PairHits::new(m.body, *si, reason)));
                }
            }
        }
        let cutting = matches!(seg.kind, SegmentKind::Feed | SegmentKind::Arc)
            && seg.spindle_rpm > 0.0
            && !seg.probe;
        let tool = heads.iter().find(|m| m.body == HeadBody::Tool);
        if pairs.is_empty() && !cutting {
            return Vec::new();
        }
        let length_mm = seg.geometry.length_mm();
        for k in 0..=n {
            let s_mm = length_mm * k as f64 / n as f64;
            let tip = seg.geometry.point_at(seg.start_mm, s_mm);
            for (mi, ci, pair) in &mut pairs {
                let (m, (si, map)) = (&heads[*mi], &self.maps[*ci]);
                let st = &scene.statics[*si];
                let (lo, hi) = Scene::moving_box(m, tip, tip);
                if !overlap(lo, hi, st.lo_mm, st.hi_mm) {
                    continue;
                }
                *samples += 1;
                if let Some((depth_mm, point)) = penetration(map, m, tip) {
                    pair.add(seg, kind, st, k, s_mm, tip, depth_mm, point);
                }
            }
            if let (true, Some(t)) = (cutting, tool) {
                let (lo, hi) = Scene::moving_box(t, tip, tip);
                for (si, map) in &mut self.maps {
                    let st = &scene.statics[*si];
                    if overlap(lo, hi, st.lo_mm, st.hi_mm) {
                        let tool_tip_mm = tip[2] + t.center_above_tip_mm - t.half_height_mm;
                        map.cut_disc([tip[0], tip[1]], t.radius_mm, tool_tip_mm);
                    }
                }
            }
        }
        pairs.into_iter().map(|(_, _, p)| p).collect()
    }
}

/// Vertical overlap (mm, above the contact tolerance) of body `m` with its tip at `tip` and the
/// material left in `map`, with the contact point.
fn penetration(map: &ZMap, m: &Moving, tip: [f64; 3]) -> Option<(f64, [f64; 3])> {
    let bottom_mm = tip[2] + m.center_above_tip_mm - m.half_height_mm;
    let top_mm = bottom_mm + 2.0 * m.half_height_mm;
    let (material_mm, at) = map.highest_in_disc([tip[0], tip[1]], m.radius_mm)?;
    let reach_mm = material_mm.min(top_mm);
    let depth_mm = reach_mm - bottom_mm;
    (depth_mm > CONTACT_TOLERANCE_MM).then_some((depth_mm, [at[0], at[1], reach_mm]))
}
