//! Probe moves G38.2 … G38.5 in the modal state machine (see `probe` for the model): the
//! refusals LinuxCNC's interpreter makes before the move (its messages, in its order), the
//! move, and the result the caller brings back.

use super::super::decode::{CompMode, Decoded, FeedMode};
use super::super::probe::{ProbeKind, ProbeOutcome, ProbeParams, ProbeRequest};
use super::super::{CanonKind, XYZ_STILL_MM};
use super::Interpreter;
use crate::syntax::{Block, GcodeError};

/// A probe move emitted, its result still to come.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PendingProbe {
    pub(super) request: ProbeRequest,
    /// Column of the block's G38 word (or first axis word), for the error of no contact.
    pub(super) col: usize,
}

impl Interpreter {
    /// Refuses a probe block as LinuxCNC does: with cutter radius compensation on after the
    /// block's G40/G41/G42, with a zero feed, in G95. G93 is refused as unsupported: LinuxCNC
    /// then probes at the feed of the last inverse-time move, not at a programmed one.
    pub(super) fn check_probe(
        &self,
        block: &Block,
        d: &Decoded,
        col: usize,
        kind: ProbeKind,
    ) -> Result<(), GcodeError> {
        let line = block.line;
        let comp_on = d
            .cutter_comp
            .map_or(self.comp.is_on(), |(mode, _)| mode != CompMode::Off);
        if comp_on {
            return Err(GcodeError::invalid(
                line,
                col,
                "Cannot probe with cutter radius comp on",
            ));
        }
        let mode = d.feed_mode.map_or(self.feed_mode, |f| f.0);
        if mode == FeedMode::InverseTime {
            let msg = format!(
                "{} in G93 inverse time feed mode is not supported (LinuxCNC probes at the \
                 feed of the last inverse-time move)",
                kind.code()
            );
            return Err(GcodeError::unsupported(line, col, msg));
        }
        let kept = if d.feed_mode.is_some() {
            0.0
        } else {
            self.feed_mm_per_min
        };
        if d.f.map_or(kept, |f| f.value) <= 0.0 {
            return Err(GcodeError::invalid(
                line,
                col,
                "Cannot probe with zero feed rate",
            ));
        }
        if mode == FeedMode::PerRevolution {
            return Err(GcodeError::invalid(
                line,
                col,
                "Cannot probe with feed per rev mode",
            ));
        }
        Ok(())
    }

    /// The probe move of a block from the current point to (`end_mm`, `end_abc_deg`), left
    /// pending until [`Interpreter::probe_result`]. G38.2 and G38.4 refuse a move to where the
    /// tool already is (LinuxCNC's check, on its program coordinates; here X, Y, Z within
    /// [`XYZ_STILL_MM`], the rounding of a rotated frame, and A, B, C equal; G38.3 and G38.5
    /// accept it).
    pub(super) fn probe_move(
        &mut self,
        block: &Block,
        col: usize,
        kind: ProbeKind,
        (end_mm, end_abc_deg): ([f64; 3], [f64; 3]),
    ) -> Result<CanonKind, GcodeError> {
        let travel_mm = (0..3)
            .map(|a| (end_mm[a] - self.pos_mm[a]).powi(2))
            .sum::<f64>()
            .sqrt();
        let still = travel_mm <= XYZ_STILL_MM && end_abc_deg == self.rotary.pos_deg;
        if kind.error_on_no_contact && still {
            return Err(GcodeError::invalid(
                block.line,
                col,
                "Start point too close to probe point",
            ));
        }
        let request = ProbeRequest {
            line: block.line,
            kind,
            // After G40 the move leaves from the compensated point.
            start_mm: self.comp.tool_position().unwrap_or(self.pos_mm),
            start_abc_deg: self.rotary.pos_deg,
            end_mm,
            end_abc_deg,
            feed_mm_per_min: self.feed_mm_per_min,
        };
        self.probe = Some(PendingProbe { request, col });
        Ok(CanonKind::Probe {
            end_mm,
            end_abc_deg,
            feed_mm_per_min: self.feed_mm_per_min,
            kind,
        })
    }

    /// The probe move emitted by the last block, if its result is still to come.
    pub fn pending_probe(&self) -> Option<ProbeRequest> {
        self.probe.map(|p| p.request)
    }

    /// Gives the pending probe move its result (see [`ProbeOutcome`]): the tool continues from
    /// where it came to rest. Returns the values of #5061…#5070 (the caller keeps the
    /// parameters; [`super::super::ProgramRun`] writes them).
    ///
    /// # Errors
    /// No probe move pending; a G38.2/G38.4 that ended without contact or whose probe was
    /// already in the state it seeks (LinuxCNC's messages, at the probe block); a point that
    /// is not finite.
    pub fn probe_result(&mut self, outcome: ProbeOutcome) -> Result<ProbeParams, GcodeError> {
        let Some(PendingProbe { request: r, col }) = self.probe.take() else {
            return Err(GcodeError::invalid(
                1,
                1,
                "a probe result was given, but no probe move awaits one",
            ));
        };
        let (probed, rest, tripped) = match outcome {
            ProbeOutcome::Tripped {
                trip_mm,
                trip_abc_deg,
                rest_mm,
                rest_abc_deg,
            } => ((trip_mm, trip_abc_deg), (rest_mm, rest_abc_deg), true),
            ProbeOutcome::NoContact if r.kind.error_on_no_contact => {
                let what = if r.kind.toward { "making" } else { "breaking" };
                let msg = format!("{} move finished without {what} contact.", r.kind.code());
                return Err(GcodeError::invalid(r.line, col, msg));
            }
            ProbeOutcome::NoContact => {
                let end = (r.end_mm, r.end_abc_deg);
                (end, end, false)
            }
            ProbeOutcome::AlreadyInState if r.kind.error_on_no_contact => {
                let msg = if r.kind.toward {
                    "Probe is already tripped when starting G38.2 or G38.3 move"
                } else {
                    "Probe is already clear when starting G38.4 or G38.5 move"
                };
                return Err(GcodeError::invalid(r.line, col, msg));
            }
            ProbeOutcome::AlreadyInState => {
                let start = (r.start_mm, r.start_abc_deg);
                (start, start, true)
            }
            ProbeOutcome::Standalone => (
                (r.end_mm, r.end_abc_deg),
                (r.standalone_rest_mm(), r.end_abc_deg),
                false,
            ),
        };
        let points = [probed.0, probed.1, rest.0, rest.1];
        if points
            .iter()
            .flatten()
            .any(|v| !v.is_finite() || v.abs() > 1e9)
        {
            let msg = format!(
                "the result of the {} move is not a finite point within 1e9: {points:?}",
                r.kind.code()
            );
            return Err(GcodeError::invalid(r.line, col, msg));
        }
        self.pos_mm = rest.0;
        self.rotary.pos_deg = rest.1;
        let p_mm = self.program_from_machine(probed.0);
        let k = self.scale();
        let mut params = [0.0; 10];
        for a in 0..3 {
            params[a] = p_mm[a] / k;
            params[3 + a] = probed.1[a] - self.rotary_offset_deg(a);
        }
        params[9] = f64::from(u8::from(tripped));
        Ok(params)
    }
}
