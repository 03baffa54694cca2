//! The move-by-move check of [`super`], over one plan or over a program's plans piece by piece:
//! a [`PlanChecker`] carries what one move's check needs from the moves before it (the pairs in
//! contact on the previous move, the stock's Z-map cut so far, the loaded tool's body, the
//! machine time of the pieces before) from one piece to the next, so a program checked in
//! pieces reports what its whole plan reports, holding one piece at a time.

use super::{
    crash_reason, line_window, move_kind, overlap, segment_bounds, CheckError, CheckObserver,
    CheckSummary, CutStock, HeadBody, Moving, PairHits, Problem, Scene, TravelViolation,
    CONTACT_TOLERANCE_MM, SAMPLE_SPACING_MM,
};
use crate::machine::MachineSpec;
use crate::motion::{self, Geometry, MotionError, Plan, Segment, SegmentKind};

/// Checks every segment of `plan` against the travel limits of `machine` and, with a `scene`,
/// for collisions; reports each problem to `observer` move by move, in plan order.
///
/// Errors when the machine's travel range itself is invalid or a contact query is unsupported.
pub fn check_plan(
    plan: &Plan,
    machine: &MachineSpec,
    scene: Option<&Scene>,
    observer: &mut dyn CheckObserver,
) -> Result<CheckSummary, CheckError> {
    let mut checker = PlanChecker::new(machine, scene)?;
    checker.check(plan, observer)?;
    Ok(checker.summary())
}

/// The check of a program's plans in order, as if they were one plan: each plan starts where
/// the previous one ended, in position and in time (see [`PlanChecker::check`]).
pub struct PlanChecker<'a> {
    machine: &'a MachineSpec,
    scene: Option<&'a Scene>,
    sum: CheckSummary,
    /// Pairs (head body, static body) reported on the previous move: a move that starts in
    /// such a contact and gets no deeper is the same crash continuing (e.g. the retraction out
    /// of it), and is not reported again.
    reported_prev: Vec<(HeadBody, usize)>,
    /// The stock boxes' Z-maps, cut by the moves checked so far.
    cut_stock: Option<CutStock>,
    /// The head's bodies; the tool's follows the tool changes.
    heads: Vec<Moving>,
    /// Machine time at the start of the next plan, s.
    t0_s: f64,
}

impl<'a> PlanChecker<'a> {
    /// A check of `machine`'s travel and, with a `scene`, of collisions, before any move.
    ///
    /// # Errors
    /// A stock box too large for its Z-map.
    pub fn new(machine: &'a MachineSpec, scene: Option<&'a Scene>) -> Result<Self, CheckError> {
        Ok(Self {
            machine,
            scene,
            sum: CheckSummary::default(),
            reported_prev: Vec::new(),
            cut_stock: scene.map(CutStock::new).transpose()?,
            heads: scene.map(|s| s.moving.clone()).unwrap_or_default(),
            t0_s: 0.0,
        })
    }

    /// Checks the next plan, which starts where the previous one ended (its times count from
    /// the previous plan's end); reports each problem to `observer` move by move, with times
    /// from the start of the first plan.
    ///
    /// # Errors
    /// An invalid travel range; an unsupported contact query.
    pub fn check(
        &mut self,
        plan: &Plan,
        observer: &mut dyn CheckObserver,
    ) -> Result<(), CheckError> {
        for seg in plan.segments() {
            self.check_segment(seg, observer)?;
        }
        self.t0_s += plan.duration_s();
        Ok(())
    }

    /// The counts so far.
    pub fn summary(&self) -> CheckSummary {
        self.sum
    }

    fn check_segment(
        &mut self,
        seg: &Segment,
        observer: &mut dyn CheckObserver,
    ) -> Result<(), CheckError> {
        let (tmin, tmax) = (
            self.machine.axes.travel_min_mm,
            self.machine.axes.travel_max_mm,
        );
        if let (SegmentKind::ToolChange { tool }, Some(sc)) = (seg.kind, self.scene) {
            if let Some(h) = self.heads.iter_mut().find(|h| h.body == HeadBody::Tool) {
                *h = sc.loaded_tool_body(tool, self.machine, h);
            }
        }
        let Some(kind) = move_kind(seg) else {
            return Ok(());
        };
        self.sum.segments += 1;
        let length_mm = seg.geometry.length_mm();
        self.sum.path_mm += length_mm;
        for err in motion::segment_travel_violations(seg, tmin, tmax)? {
            if let MotionError::AxisOutOfTravel {
                line,
                axis,
                pos_mm,
                min_mm,
                max_mm,
            } = err
            {
                self.sum.travel_violations += 1;
                observer.on_problem(&Problem::Travel(TravelViolation {
                    line,
                    time_s: self.t0_s + seg.t_start_s,
                    axis,
                    pos_mm,
                    min_mm,
                    max_mm,
                }));
            }
        }
        let Some(scene) = self.scene else {
            return Ok(());
        };
        if length_mm <= 0.0 {
            return Ok(());
        }
        let n = (length_mm / SAMPLE_SPACING_MM).ceil().max(1.0) as usize;
        let mut hits = self.static_hits(scene, seg, kind, n)?;
        if let Some(stock) = self.cut_stock.as_mut() {
            hits.extend(stock.check_and_cut(
                seg,
                kind,
                scene,
                &self.heads,
                n,
                &mut self.sum.samples,
            ));
        }
        let mut reported_now = Vec::new();
        for pair in hits {
            let Some(mut c) = pair.found else { continue };
            let continuing = self.reported_prev.contains(&(pair.head, pair.static_index))
                && pair.start_depth_mm > 0.0
                && c.depth_mm <= pair.start_depth_mm + CONTACT_TOLERANCE_MM;
            reported_now.push((pair.head, pair.static_index));
            if !continuing {
                self.sum.collisions += 1;
                c.time_s += self.t0_s;
                c.first_contact_time_s += self.t0_s;
                observer.on_problem(&Problem::Collision(c));
            }
        }
        self.reported_prev = reported_now;
        Ok(())
    }

    /// The contacts of the head's bodies with the static bodies that are not cut stock, along
    /// `seg` sampled at `n` steps.
    fn static_hits(
        &mut self,
        scene: &Scene,
        seg: &Segment,
        kind: super::MoveKind,
        n: usize,
    ) -> Result<Vec<PairHits>, CheckError> {
        let length_mm = seg.geometry.length_mm();
        let mut hits: Vec<PairHits> = Vec::new();
        let (lo, hi) = segment_bounds(seg);
        for m in &self.heads {
            let (mlo, mhi) = Scene::moving_box(m, lo, hi);
            for (si, s) in scene.statics.iter().enumerate() {
                if s.cut || !overlap(mlo, mhi, s.lo_mm, s.hi_mm) {
                    continue;
                }
                let Some(reason) = crash_reason(m.body, s.role, seg) else {
                    continue;
                };
                let mut pair = PairHits::new(m.body, si, reason);
                // On a line, only the samples whose bounding boxes can overlap (same results,
                // cost ∝ the length near the body rather than the whole move).
                let (k0, k1) = match line_window(seg, m, s) {
                    Some((s0, s1)) => {
                        let k0 = ((s0 / length_mm) * n as f64).floor().max(0.0) as usize;
                        let k1 = ((s1 / length_mm) * n as f64).ceil().min(n as f64) as usize;
                        (k0, k1)
                    }
                    None if matches!(seg.geometry, Geometry::Line { .. }) => continue,
                    None => (0, n),
                };
                for k in k0..=k1 {
                    let s_mm = length_mm * k as f64 / n as f64;
                    let tip = seg.geometry.point_at(seg.start_mm, s_mm);
                    self.sum.samples += 1;
                    if let Some((depth_mm, point)) = scene.penetration(m, s, tip)? {
                        pair.add(seg, kind, s, k, s_mm, tip, depth_mm, point);
                    }
                }
                hits.push(pair);
            }
        }
        Ok(hits)
    }
}
