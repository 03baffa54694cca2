//! A program interpreted and planned as it runs: the interpreter is resumed for at most
//! [`super::MOVES_PER_PIECE`] canonical moves at a time ([`interp::ProgramRun::resume_at_most`]),
//! each batch is planned from where the previous one left the machine
//! ([`motion::plan_from`]), checked (rotary words, tools, travel, in the program's units) and
//! handed out. A program file is read as it runs ([`interp::ProgramRun::from_source`]: only
//! its O-word lines' places are held), so a program of any length holds one piece's moves and
//! plan, never its text, all its moves or its whole timed plan.
//!
//! Pieces join as those of [`super::PlanPieces`] do (the same planner state carried over); a
//! program of at most one piece is planned exactly as [`super::load_plan_placed`] plans it.

use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

use super::{check_tools, interp, interp_config, interp_config_in, refuse_rotary};
use super::{LineUnits, ProgramError};
use crate::machine::MachineSpec;
use crate::motion::{self, Plan, PlanStart, RotaryLimits};
use crate::setup::Placement;
use crate::tools::ToolTable;
use interp::{CanonKind, CanonMove, ProbeOutcome, ProbeParams, ProbeRequest, ProgramRun, RunEvent};

/// The plans of a program's pieces, in order, interpreted as they are asked for; stops after
/// the first error and after the piece that holds the program's end. Probe moves get the
/// stand-alone outcome, as in [`super::load_plan_placed`], unless the stream is
/// [`PlanStream::answering_probes`]: a piece then ends before each probe move, the caller
/// simulates it, gives the machine's answer ([`PlanStream::answer_probe`]) and the probe move
/// starts the next piece, planned to where the axes stopped.
#[derive(Debug)]
pub struct PlanStream<'a> {
    file: String,
    fingerprint: u64,
    run: ProgramRun,
    machine: &'a MachineSpec,
    tools: &'a ToolTable,
    start: PlanStart,
    /// The present piece's moves (the buffer is reused).
    moves: Vec<CanonMove>,
    /// Moves of the pieces handed out before.
    emitted: usize,
    moves_per_piece: usize,
    ended: bool,
    /// Probe moves wait for the caller's answer (else: the stand-alone outcome).
    answering: bool,
    /// The probe move waiting for its answer.
    pending: Option<ProbeRequest>,
    /// The probe move (and any stop of its block) held for the next piece.
    held: Vec<CanonMove>,
    /// Pieces are refused when a move leaves the travel (else: left to the caller's check).
    travel_checked: bool,
    /// The unit of length at each line of the last piece handed out.
    units: LineUnits,
    /// A probe answer stopped the program: the probe move is the last piece.
    stopped: bool,
}

impl<'a> PlanStream<'a> {
    /// The program at `path` placed by `placement` (work offsets; subroutine files from the
    /// program's folder, then the placement's), starting at rest at `start_mm`: the file is
    /// checked (UTF-8), scanned for its O-words and subroutine files and kept open, to be read
    /// as it is interpreted; nothing is interpreted yet.
    ///
    /// # Errors
    /// Reading, subroutine files (see [`ProgramRun::from_source`]).
    pub fn load(
        path: &Path,
        machine: &'a MachineSpec,
        start_mm: [f64; 3],
        tools: &'a ToolTable,
        placement: &Placement,
        moves_per_piece: usize,
    ) -> Result<Self, ProgramError> {
        let file = path.display().to_string();
        let (reader, fingerprint) = match crate::read::open_text(path) {
            Ok(opened) => opened,
            Err(err) => return Err(ProgramError::Io { file, err }),
        };
        let cfg = interp_config(machine, start_mm, tools, placement, Some(path));
        let run =
            ProgramRun::from_source(Box::new(reader), &cfg).map_err(|err| ProgramError::Gcode {
                file: file.clone(),
                err,
            })?;
        Ok(Self::with_run(
            file,
            fingerprint,
            run,
            (machine, tools),
            start_mm,
            moves_per_piece,
        ))
    }

    /// Program text placed by `source`; `moves_per_piece` at least 1.
    ///
    /// # Errors
    /// Subroutine files (see [`ProgramRun::from_source`]).
    pub fn from_source(
        source: Source<'_>,
        machine: &'a MachineSpec,
        start_mm: [f64; 3],
        tools: &'a ToolTable,
        moves_per_piece: usize,
    ) -> Result<Self, ProgramError> {
        let dirs = source.subroutine_dirs;
        let cfg = interp_config_in(machine, start_mm, tools, source.placement, dirs);
        let run = ProgramRun::new(source.text, &cfg).map_err(|err| ProgramError::Gcode {
            file: source.file.to_string(),
            err,
        })?;
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        source.text.hash(&mut hasher);
        let file = source.file.to_string();
        Ok(Self::with_run(
            file,
            hasher.finish(),
            run,
            (machine, tools),
            start_mm,
            moves_per_piece,
        ))
    }

    fn with_run(
        file: String,
        fingerprint: u64,
        run: ProgramRun,
        (machine, tools): (&'a MachineSpec, &'a ToolTable),
        start_mm: [f64; 3],
        moves_per_piece: usize,
    ) -> Self {
        Self {
            file,
            fingerprint,
            run,
            machine,
            tools,
            start: PlanStart::at_rest(start_mm),
            moves: Vec::new(),
            emitted: 0,
            moves_per_piece: moves_per_piece.max(1),
            ended: false,
            answering: false,
            pending: None,
            held: Vec::new(),
            travel_checked: true,
            units: LineUnits::default(),
            stopped: false,
        }
    }

    /// This stream with its probe moves answered by the caller (see [`PlanStream`]).
    #[must_use]
    pub fn answering_probes(mut self) -> Self {
        self.answering = true;
        self
    }

    /// This stream without the travel check: a move beyond the travel is planned and handed
    /// out, for a checker that reports every such move (as `check` does).
    #[must_use]
    pub fn without_travel_check(mut self) -> Self {
        self.travel_checked = false;
        self
    }

    /// The unit of length (G20/G21) at each line of the last piece handed out.
    pub fn units(&self) -> &LineUnits {
        &self.units
    }

    /// The probe move the last piece stopped before, while it waits for its answer.
    pub fn pending_probe(&self) -> Option<ProbeRequest> {
        self.pending
    }

    /// Gives the pending probe move the machine's answer; returns #5061…#5070 as the program
    /// reads them and its unit of length at the probe. After an answer that stops the program
    /// (an error), the stream's last piece is the probe move, made to its programmed end as on
    /// the machine.
    ///
    /// # Errors
    /// No probe move waits; a G38.2/G38.4 without contact (LinuxCNC's words, with the file and
    /// line), as [`ProgramRun::probe_result`].
    pub fn answer_probe(
        &mut self,
        outcome: ProbeOutcome,
    ) -> Result<(ProbeParams, interp::LengthUnit), ProgramError> {
        let gcode = |err| ProgramError::Gcode {
            file: self.file.clone(),
            err,
        };
        let Some(request) = self.pending.take() else {
            let msg = "a probe answer was given, but no probe move awaits one";
            return Err(gcode(interp::GcodeError::invalid(1, 1, msg)));
        };
        if let Some(mv) = self.held.first_mut() {
            super::end_probe_move(mv, &request, &outcome);
        }
        if let Err(err) = self.run.probe_result(outcome) {
            self.stopped = true;
            return Err(gcode(err));
        }
        let params = self.run.probe_params().unwrap_or_default();
        Ok((params, self.run.length_unit_at(self.emitted)))
    }

    /// The program's name in errors.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// A hash of the program's text: two streams of the same file read at different times
    /// agree on it unless the file changed in between.
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }

    /// Interprets up to the next piece's moves into `self.moves`; whether the program ended.
    fn interpret_piece(&mut self) -> Result<bool, ProgramError> {
        self.moves.clear();
        // The answered probe move starts this piece.
        self.moves.append(&mut self.held);
        if self.stopped {
            return Ok(true);
        }
        let gcode = |err| ProgramError::Gcode {
            file: self.file.clone(),
            err,
        };
        loop {
            let room = self.moves_per_piece.saturating_sub(self.moves.len());
            match self.run.resume_at_most(&mut self.moves, room) {
                Err(err) => return Err(gcode(err)),
                Ok(None) => return Ok(false),
                Ok(Some(RunEvent::Ended)) => return Ok(true),
                Ok(Some(RunEvent::Probe(request))) if self.answering => {
                    // The piece ends before the probe move: the machine answers it after
                    // simulating the moves before it.
                    let at = self
                        .moves
                        .iter()
                        .rposition(|m| matches!(m.kind, CanonKind::Probe { .. }))
                        .unwrap_or(self.moves.len());
                    self.held = self.moves.split_off(at);
                    self.pending = Some(request);
                    return Ok(false);
                }
                Ok(Some(RunEvent::Probe(_))) => self
                    .run
                    .probe_result(ProbeOutcome::Standalone)
                    .map_err(gcode)?,
            }
        }
    }

    /// Interprets, plans and checks the next piece; whether it holds the program's end.
    fn next_piece(&mut self) -> Result<(Plan, bool), ProgramError> {
        let program_ended = self.interpret_piece()?;
        let units: Vec<_> = (0..self.moves.len())
            .map(|i| self.run.length_unit_at(self.emitted + i))
            .collect();
        self.emitted += self.moves.len();
        let units = LineUnits::new(&self.moves, &units);
        refuse_rotary(&self.moves, &self.file, &self.machine.machine.name)?;
        let motion_err = |err: motion::MotionError| ProgramError::Motion {
            file: self.file.clone(),
            unit: units.at(super::err_line(&err)),
            err,
        };
        let plan = motion::plan_from(
            &self.moves,
            self.start,
            &self.machine.motion,
            &RotaryLimits::default(),
        )
        .map_err(|err| {
            // A wild work offset: the travel is what is wrong (as in a whole plan).
            let err = match err {
                motion::MotionError::ProgramTooLong { line, .. } => {
                    super::first_end_beyond_travel(&self.moves, line, self.machine).unwrap_or(err)
                }
                err => err,
            };
            motion_err(err)
        })?;
        check_tools(&plan, &self.file, self.machine, self.tools)?;
        if self.travel_checked {
            motion::check_travel(
                &plan,
                self.machine.axes.travel_min_mm,
                self.machine.axes.travel_max_mm,
            )
            .map_err(motion_err)?;
        }
        self.units = units;
        let ended = program_ended || plan.program_end_line().is_some();
        Ok((plan, ended))
    }
}

/// Program text and where it is placed, for [`PlanStream::from_source`].
#[derive(Debug, Clone)]
pub struct Source<'s> {
    /// The text.
    pub text: &'s str,
    /// Its name in errors.
    pub file: &'s str,
    /// Work offsets.
    pub placement: &'s Placement,
    /// Folders searched for subroutine files, in order.
    pub subroutine_dirs: Vec<PathBuf>,
}

impl Iterator for PlanStream<'_> {
    type Item = Result<Plan, ProgramError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.ended {
            return None;
        }
        match self.next_piece() {
            Ok((plan, ended)) => {
                self.ended = ended;
                self.start = plan.end_state();
                Some(Ok(plan))
            }
            Err(e) => {
                self.ended = true;
                Some(Err(e))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn source<'s>(text: &'s str, placement: &'s Placement) -> Source<'s> {
        Source {
            text,
            file: "p.ngc",
            placement,
            subroutine_dirs: Vec::new(),
        }
    }

    #[test]
    fn a_streamed_program_joins_into_its_whole_plan() {
        let spec = MachineSpec::reference();
        let text = "G21 G90 F3000\nG0 X20 Y20 Z-100\no1 repeat [200]\nG1 X540 Y20\nG4 P1\n\
                    G1 X20 Y380 Z-300\no1 endrepeat\nM30\n";
        let start = spec.axes.home_mm;
        let tools = ToolTable::default();
        let placement = Placement::of_machine(&spec);
        let whole = super::super::plan_source(text, "p.ngc", &spec, start).unwrap();
        let one = PlanStream::from_source(source(text, &placement), &spec, start, &tools, 1 << 20)
            .unwrap()
            .collect::<Result<Vec<_>, _>>()
            .unwrap();
        assert_eq!(one.len(), 1);
        assert_eq!(one[0].segments(), whole.segments());
        let pieces = PlanStream::from_source(source(text, &placement), &spec, start, &tools, 64)
            .unwrap()
            .collect::<Result<Vec<_>, _>>()
            .unwrap();
        assert!(pieces.len() >= 9, "{}", pieces.len());
        let segments: Vec<_> = pieces.iter().flat_map(|p| p.segments().iter()).collect();
        assert_eq!(segments.len(), whole.segments().len());
        for (s, w) in segments.iter().zip(whole.segments()) {
            assert_eq!((s.line, s.kind, s.end_mm), (w.line, w.kind, w.end_mm));
        }
        let total_s: f64 = pieces.iter().map(Plan::duration_s).sum();
        assert!((total_s - whole.duration_s()).abs() < 1e-6);
    }

    #[test]
    fn a_streamed_move_beyond_the_travel_is_refused_in_the_program_units() {
        let spec = MachineSpec::reference();
        let text = "G21 G90 F3000\no1 repeat [100]\nG1 X100\nG1 X200\no1 endrepeat\nG20\n\
                    G0 X200\nM30\n";
        let tools = ToolTable::default();
        let placement = Placement::of_machine(&spec);
        let start = spec.axes.home_mm;
        let results: Vec<_> =
            PlanStream::from_source(source(text, &placement), &spec, start, &tools, 16)
                .unwrap()
                .collect();
        let err = results.last().unwrap().as_ref().unwrap_err().to_string();
        let whole = super::super::plan_source(text, "p.ngc", &spec, start)
            .unwrap_err()
            .to_string();
        assert_eq!(err, whole);
        assert!(err.contains(" in"), "{err}");
        assert!(results[..results.len() - 1].iter().all(Result::is_ok));
    }

    #[test]
    fn a_probe_answer_that_stops_the_program_leaves_the_probe_move_as_the_last_piece() {
        let spec = MachineSpec::reference();
        let text = "G21 G90\nG0 X50 Y50 Z-100\nG38.2 Z-110 F50\nG0 Z-50\nM2\n";
        let tools = ToolTable::default();
        let placement = Placement::of_machine(&spec);
        let start = spec.axes.home_mm;
        let mut stream =
            PlanStream::from_source(source(text, &placement), &spec, start, &tools, 16)
                .unwrap()
                .answering_probes();
        let first = stream.next().unwrap().unwrap();
        assert_eq!(first.segments().last().map(|s| s.line), Some(2));
        assert!(stream.pending_probe().is_some());
        let err = stream.answer_probe(ProbeOutcome::NoContact).unwrap_err();
        assert!(err.to_string().contains("line 3"), "{err}");
        // The probe move, made to its programmed end, and nothing after it.
        let last = stream.next().unwrap().unwrap();
        let lines: Vec<usize> = last.segments().iter().map(|s| s.line).collect();
        assert!(
            !lines.is_empty() && lines.iter().all(|l| *l == 3),
            "{lines:?}"
        );
        assert_eq!(last.segments().last().unwrap().end_mm[2], -110.0);
        assert!(stream.next().is_none());
    }
}
