//! A whole program run block by block, pausing at each probe move until the machine's result
//! comes back ([`ProgramRun`]); [`run_program`](super::run_program) drives one with the
//! stand-alone outcome. Errors are located here: the subroutine file a line belongs to and
//! the calls that led to it ([`GcodeError::file`], [`GcodeError::calls`]).

use super::flow::Runner;
use super::probe::{ProbeOutcome, ProbeRequest};
use super::program::{Pos, Program};
use super::source::ProgramSource;
use super::{CanonKind, CanonMove, InterpConfig};
use crate::syntax::GcodeError;

/// A program's unit of length (G20 / G21), for messages in the units it was written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    /// G21.
    Mm,
    /// G20.
    Inch,
}

impl LengthUnit {
    /// mm per unit.
    pub fn mm_per_unit(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::Inch => super::arc::MM_PER_INCH,
        }
    }

    /// `"mm"` or `"in"`.
    pub fn symbol(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::Inch => "in",
        }
    }

    /// A length given in mm, in this unit rounded as a person reads it: to the µm in mm
    /// (3 decimals), to the tenth of a thou in inches (4 decimals), trailing zeros dropped.
    ///
    /// ```
    /// use vmc_gcode::interp::LengthUnit;
    /// assert_eq!(LengthUnit::Mm.format_mm(-76.09585999999999), "-76.096 mm");
    /// assert_eq!(LengthUnit::Inch.format_mm(-76.09585999999999), "-2.9959 in");
    /// assert_eq!(LengthUnit::Mm.format_mm(600.0), "600 mm");
    /// ```
    pub fn format_mm(self, value_mm: f64) -> String {
        format!("{} {}", self.number_mm(value_mm), self.symbol())
    }

    /// [`Self::format_mm`] without the unit's symbol.
    pub fn number_mm(self, value_mm: f64) -> String {
        let decimals = match self {
            LengthUnit::Mm => 3,
            LengthUnit::Inch => 4,
        };
        let text = format!("{:.*}", decimals, value_mm / self.mm_per_unit());
        let text = text.trim_end_matches('0').trim_end_matches('.');
        let text = if text == "-0" { "0" } else { text };
        text.to_string()
    }
}

/// Where a [`ProgramRun`] stopped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RunEvent {
    /// The program is over (M2, M30, an M99 in the main program, or the end of the text):
    /// every canonical action has been emitted.
    Ended,
    /// A probe move was emitted: it is the last move in the output so far (only a stop of
    /// its own block — M0, M1, M60, M2, M30 — may follow it). Give its result with
    /// [`ProgramRun::probe_result`], then resume.
    Probe(ProbeRequest),
}

#[derive(Debug)]
enum State {
    Running,
    Probing(ProbeRequest),
    Ended,
    Failed(GcodeError),
}

/// A program being interpreted, resumable: [`Self::resume`] runs blocks until the program
/// ends or a probe move needs the machine's result (the machine simulator supplies the trip
/// point of its own geometry; [`super::run_program`] takes LinuxCNC's stand-alone `rs274`
/// convention, [`ProbeOutcome::Standalone`]).
///
/// ```
/// use vmc_gcode::interp::{CanonKind, InterpConfig, ProbeOutcome, ProgramRun, RunEvent};
/// let program = "G21 F100\nG38.2 Z-10\nG0 Z[#5063 + 5]\nM2";
/// let mut run = ProgramRun::new(program, &InterpConfig::default())?;
/// let mut moves = Vec::new();
/// while let RunEvent::Probe(request) = run.resume(&mut moves)? {
///     // The machine found the surface 3 mm down and stopped 0.1 mm further.
///     let mut trip_mm = request.start_mm;
///     trip_mm[2] -= 3.0;
///     let mut rest_mm = trip_mm;
///     rest_mm[2] -= 0.1;
///     run.probe_result(ProbeOutcome::Tripped {
///         trip_mm,
///         trip_abc_deg: request.end_abc_deg,
///         rest_mm,
///         rest_abc_deg: request.end_abc_deg,
///     })?;
/// }
/// // #5063 was the trip point's Z: 5 mm above the surface.
/// assert!(matches!(moves[1].kind, CanonKind::Traverse { end_mm: [0.0, 0.0, 2.0], .. }));
/// # Ok::<(), vmc_gcode::GcodeError>(())
/// ```
#[derive(Debug)]
pub struct ProgramRun {
    prog: Program,
    runner: Runner,
    /// Where the next line is read.
    pc: Pos,
    state: State,
    /// The place of the last probe block.
    probe_at: Pos,
    /// Where the length unit changed: (number of moves emitted before, the unit after).
    unit_changes: Vec<(usize, LengthUnit)>,
    /// Where tool centre point control (G43.4) changed: (moves emitted before, tool length
    /// after, `None` when off).
    tcp_changes: Vec<(usize, Option<f64>)>,
    /// Moves emitted by the calls before the present one (over every output given).
    emitted_before: usize,
}

impl ProgramRun {
    /// A run of the program text `src` (held as an in-memory source, see
    /// [`Self::from_source`]); nothing runs yet.
    ///
    /// # Errors
    /// As [`Self::from_source`].
    pub fn new(src: &str, cfg: &InterpConfig) -> Result<Self, GcodeError> {
        Self::from_source(Box::new(std::io::Cursor::new(src.as_bytes().to_vec())), cfg)
    }

    /// A run of the program read from `source` (a file, from its present position, or a
    /// `std::io::Cursor`): lines are read as execution reaches them, loops and calls seek
    /// back to them, and only the O-word lines' places are held (see `program`), so a program
    /// of any length runs in the same memory. With [`InterpConfig::subroutine_dirs`] the
    /// text is scanned once now and the subroutine files it calls are read; nothing runs yet.
    /// The source must not change during the run.
    ///
    /// # Errors
    /// A source that cannot be read; a subroutine file that cannot be read, lacks its
    /// definition or has a syntax error. (Errors of the program itself come from
    /// [`Self::resume`], when execution reaches them.)
    pub fn from_source(
        source: Box<dyn ProgramSource>,
        cfg: &InterpConfig,
    ) -> Result<Self, GcodeError> {
        let prog = Program::new(source, cfg)?;
        Ok(Self {
            pc: prog.origin(),
            probe_at: prog.origin(),
            prog,
            runner: Runner::new(cfg),
            state: State::Running,
            unit_changes: vec![(0, LengthUnit::Mm)],
            tcp_changes: vec![(0, None)],
            emitted_before: 0,
        })
    }

    /// Runs blocks, appending their canonical actions to `out`, until the program ends or a
    /// probe move waits for its result. After [`RunEvent::Ended`] it returns `Ended` again.
    ///
    /// # Errors
    /// The first error of the program (then every later call returns it again), or a probe
    /// move still without its result.
    pub fn resume(&mut self, out: &mut Vec<CanonMove>) -> Result<RunEvent, GcodeError> {
        let event = self.resume_at_most(out, usize::MAX)?;
        Ok(event.expect("an unbounded run pauses only at an event"))
    }

    /// [`Self::resume`] in bounded steps: runs blocks until the program ends, a probe move
    /// waits (`Some` event), or at least `max_moves` moves were appended to `out` in this call
    /// (`None`: call again for the rest). The caller may empty `out` between calls, so a long
    /// program is interpreted without holding all its moves; move indices
    /// ([`Self::length_unit_at`]) count every move emitted since the start.
    ///
    /// # Errors
    /// As [`Self::resume`].
    pub fn resume_at_most(
        &mut self,
        out: &mut Vec<CanonMove>,
        max_moves: usize,
    ) -> Result<Option<RunEvent>, GcodeError> {
        let first = out.len();
        let result = self.resume_inner(out, first.saturating_add(max_moves));
        self.emitted_before += out.len() - first;
        result
    }

    fn resume_inner(
        &mut self,
        out: &mut Vec<CanonMove>,
        stop_at_len: usize,
    ) -> Result<Option<RunEvent>, GcodeError> {
        match &self.state {
            State::Running => {}
            State::Ended => return Ok(Some(RunEvent::Ended)),
            State::Failed(e) => return Err(e.clone()),
            State::Probing(r) => {
                let msg = "the run was resumed before the probe move got its result \
                           (ProgramRun::probe_result)";
                return Err(GcodeError::invalid(r.line, 1, msg));
            }
        }
        match self.run_until_event(out, stop_at_len) {
            Ok(event) => {
                match event {
                    Some(RunEvent::Ended) => self.state = State::Ended,
                    Some(RunEvent::Probe(r)) => self.state = State::Probing(r),
                    None => {}
                }
                Ok(event)
            }
            Err(e) => {
                self.state = State::Failed(e.clone());
                Err(e)
            }
        }
    }

    /// Gives the probe move the run stopped at its result (see [`ProbeOutcome`]): #5061…#5070
    /// are set and the tool continues from where it came to rest.
    ///
    /// # Errors
    /// No probe move waits; G38.2/G38.4 without contact; a point that is not finite. The run
    /// is then over (every later [`Self::resume`] returns the error).
    pub fn probe_result(&mut self, outcome: ProbeOutcome) -> Result<(), GcodeError> {
        if !matches!(self.state, State::Probing(_)) {
            return Err(GcodeError::invalid(
                1,
                1,
                "a probe result was given, but no probe move awaits one",
            ));
        }
        match self.runner.probe_result(outcome) {
            Ok(()) => {
                self.state = State::Running;
                Ok(())
            }
            Err(e) => {
                let e = self.locate(e, Some(self.probe_at));
                self.state = State::Failed(e.clone());
                Err(e)
            }
        }
    }

    /// The values of #5061…#5070 the last probe result set (see [`super::ProbeParams`]: the
    /// probed point in the program's work coordinates and units, then the tripped flag), or
    /// `None` before the first.
    pub fn probe_params(&self) -> Option<super::probe::ProbeParams> {
        self.runner.last_probe_params
    }

    /// The program's length unit when it emitted move `index` (of the moves appended to one
    /// output by [`Self::resume`] from the start): the unit of the block it came from.
    pub fn length_unit_at(&self, index: usize) -> LengthUnit {
        self.unit_changes
            .iter()
            .rev()
            .find(|c| c.0 <= index)
            .map_or(LengthUnit::Mm, |c| c.1)
    }

    /// The tool length under G43.4 when move `index` was emitted (as [`Self::length_unit_at`]):
    /// `Some` when the move's X, Y, Z are the tool tip in the part frame, `None` when they are
    /// the machine's.
    pub fn tcp_length_at(&self, index: usize) -> Option<f64> {
        self.tcp_changes
            .iter()
            .rev()
            .find(|c| c.0 <= index)
            .and_then(|c| c.1)
    }

    /// Runs blocks until an event, or (`None`) until `out` holds `stop_at_len` moves.
    fn run_until_event(
        &mut self,
        out: &mut Vec<CanonMove>,
        stop_at_len: usize,
    ) -> Result<Option<RunEvent>, GcodeError> {
        let first = out.len();
        loop {
            if out.len() >= stop_at_len {
                return Ok(None);
            }
            if let Some(line) = self.runner.main_m99_end.take() {
                self.runner.interp.flush(out);
                out.push(CanonMove {
                    line,
                    kind: CanonKind::ProgramEnd,
                });
                return Ok(Some(RunEvent::Ended));
            }
            if self.runner.interp.is_ended() {
                return Ok(Some(RunEvent::Ended));
            }
            let fetched = self.prog.fetch(self.pc);
            let Some((at, line, next)) = fetched.map_err(|e| self.locate(e, Some(self.pc)))? else {
                break;
            };
            if let Some((first, index, e)) = self.prog.structure_error.as_deref() {
                if at >= *first {
                    return Err(self.locate(e.clone(), *index));
                }
            }
            let emitted = out.len();
            self.pc = match self.runner.step(&mut self.prog, (at, &line, next), out) {
                Ok(next) => next,
                Err(e) => return Err(self.locate(e, Some(at))),
            };
            let unit = self.runner.interp.length_unit();
            if self.unit_changes.last().map(|c| c.1) != Some(unit) {
                self.unit_changes
                    .push((self.emitted_before + emitted - first, unit));
            }
            let tcp = self.runner.interp.tcp_length_mm();
            if self.tcp_changes.last().map(|c| c.1) != Some(tcp) {
                self.tcp_changes
                    .push((self.emitted_before + emitted - first, tcp));
            }
            if let Some(request) = self.runner.probe {
                self.probe_at = at;
                return Ok(Some(RunEvent::Probe(request)));
            }
        }
        if let Some((_, index, e)) = self.prog.structure_error.take().map(|b| *b) {
            return Err(self.locate(e, index));
        }
        if let Some(e) = &self.prog.tail_error {
            return Err(e.clone());
        }
        self.runner.interp.flush(out);
        Ok(Some(RunEvent::Ended))
    }

    /// Places an error of the line at `index` (`None`: the main program) in its file, with
    /// the calls active now. Errors located already (those of reading a subroutine file) and
    /// the main program's syntax error are left as they are.
    fn locate(&self, mut e: GcodeError, index: Option<Pos>) -> GcodeError {
        if e.file.is_some() || !e.calls.is_empty() || self.prog.tail_error.as_ref() == Some(&e) {
            return e;
        }
        e.file = index.and_then(|i| self.prog.file_of(i).cloned());
        e.calls = self.runner.call_sites(&self.prog);
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_in_bounded_steps_emits_the_same_moves_and_units_as_a_whole_run() {
        let src = "G21 F1000\no1 repeat [20]\nG1 X10\nG1 Y10\nG20\nG1 X1\nG21\nG1 X0 Y0\n\
                   o1 endrepeat\nG38.3 Z-5\nG0 Z1\nM2\n";
        let cfg = InterpConfig::default();
        let (whole, units) = super::super::run_program_with_units(src, &cfg).unwrap();
        let mut run = ProgramRun::new(src, &cfg).unwrap();
        let (mut moves, mut chunk, mut bounded_units) = (Vec::new(), Vec::new(), Vec::new());
        let mut pauses = 0;
        loop {
            let event = run.resume_at_most(&mut chunk, 3).unwrap();
            // A pause comes between blocks: at most one block's moves beyond the bound.
            assert!(chunk.len() <= 6, "{}", chunk.len());
            for _ in &chunk {
                bounded_units.push(run.length_unit_at(bounded_units.len()));
            }
            moves.append(&mut chunk);
            match event {
                None => pauses += 1,
                Some(RunEvent::Probe(_)) => run.probe_result(ProbeOutcome::Standalone).unwrap(),
                Some(RunEvent::Ended) => break,
            }
        }
        assert!(pauses > 10, "{pauses}");
        assert_eq!(moves, whole);
        assert_eq!(bounded_units, units);
    }
}
