//! A program planned in pieces: interpreted once into canonical moves, then planned, checked
//! and handed out [`MOVES_PER_PIECE`] moves at a time, each piece starting where the previous
//! one left the machine (position, rotary axes, spindle). A long program (a week of duty cycles
//! in O-word loops) then holds its canonical moves but never its whole timed plan.
//!
//! Each piece is a [`Plan`] of its own: the sim runs it as it runs a warm-up program, ending it
//! exactly (one partial thermal step at its end) and starting the next at that time, which
//! changes nothing physical (the thermal network is integrated over the same heat input) but
//! shifts the thermal step grid by the remainder; programs of at most one piece are planned
//! exactly as [`super::plan_source_with_tools`] plans them.

use super::{check_tools, interp, refuse_rotary, InterpConfig, ProgramError};
use crate::machine::MachineSpec;
use crate::motion::{self, Plan, PlanStart, RotaryLimits};
use crate::tools::ToolTable;

/// Canonical moves per piece: 4096 moves plan into a few MB at most.
pub const MOVES_PER_PIECE: usize = 4096;

/// A program's canonical moves, read, interpreted and checked for rotary words.
#[derive(Debug, Clone)]
pub struct ProgramMoves {
    file: String,
    moves: Vec<interp::CanonMove>,
}

impl ProgramMoves {
    /// Reads and interprets the program at `path` with the machine's work offsets and the tool
    /// table's lengths and diameters.
    ///
    /// # Errors
    /// As [`super::load_plan_with_tools`] for reading, syntax and rotary words.
    pub fn load(
        path: &std::path::Path,
        machine: &MachineSpec,
        start_mm: [f64; 3],
        tools: &ToolTable,
    ) -> Result<Self, ProgramError> {
        let (file, text) = super::read_program(path)?;
        Self::from_source(&text, &file, machine, start_mm, tools)
    }

    /// Interprets program text; `file` names it in errors.
    ///
    /// # Errors
    /// Syntax, semantics and rotary words, as [`super::plan_source_with_tools`].
    pub fn from_source(
        text: &str,
        file: &str,
        machine: &MachineSpec,
        start_mm: [f64; 3],
        tools: &ToolTable,
    ) -> Result<Self, ProgramError> {
        let (tool_lengths_mm, tool_diameters_mm) = tools.interp_data(machine);
        let cfg = InterpConfig {
            start_mm,
            work_offsets_mm: crate::setup::Placement::of_machine(machine).work_offsets_mm,
            tool_lengths_mm,
            tool_diameters_mm,
            ..InterpConfig::default()
        };
        let mut moves = interp::run_program(text, &cfg).map_err(|err| ProgramError::Gcode {
            file: file.to_string(),
            err,
        })?;
        // Held for the whole run: not the up to twice its length the vector grew to.
        moves.shrink_to_fit();
        refuse_rotary(&moves, file, &machine.machine.name)?;
        Ok(ProgramMoves {
            file: file.to_string(),
            moves,
        })
    }

    /// The program's name in errors.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// Number of canonical moves.
    pub fn len(&self) -> usize {
        self.moves.len()
    }

    /// Whether the program has no canonical move.
    pub fn is_empty(&self) -> bool {
        self.moves.is_empty()
    }

    /// The pieces' plans from `start_mm` (at rest, spindle off), each travel-checked, with
    /// `moves_per_piece` moves each (at least 1).
    pub fn pieces<'a>(
        &'a self,
        machine: &'a MachineSpec,
        start_mm: [f64; 3],
        tools: &'a ToolTable,
        moves_per_piece: usize,
    ) -> PlanPieces<'a> {
        PlanPieces {
            program: self,
            machine,
            tools,
            next_move: 0,
            start: PlanStart::at_rest(start_mm),
            moves_per_piece: moves_per_piece.max(1),
            ended: false,
        }
    }
}

/// The plans of a program's pieces, in order (see [`ProgramMoves::pieces`]); stops after the
/// first error and after the piece that holds the program's end (M2, M30).
#[derive(Debug)]
pub struct PlanPieces<'a> {
    program: &'a ProgramMoves,
    machine: &'a MachineSpec,
    tools: &'a ToolTable,
    next_move: usize,
    start: PlanStart,
    moves_per_piece: usize,
    ended: bool,
}

impl PlanPieces<'_> {
    fn plan_next(&mut self, moves: &[interp::CanonMove]) -> Result<Plan, ProgramError> {
        let file = &self.program.file;
        // Warm-ups are told in mm: their pieces do not carry the program's units.
        let motion_err = |err| ProgramError::Motion {
            file: file.clone(),
            err,
            unit: interp::LengthUnit::Mm,
        };
        let plan = motion::plan_from(
            moves,
            self.start,
            &self.machine.motion,
            &RotaryLimits::default(),
        )
        .map_err(motion_err)?;
        check_tools(&plan, file, self.machine, self.tools)?;
        motion::check_travel(
            &plan,
            self.machine.axes.travel_min_mm,
            self.machine.axes.travel_max_mm,
        )
        .map_err(motion_err)?;
        Ok(plan)
    }
}

impl Iterator for PlanPieces<'_> {
    type Item = Result<Plan, ProgramError>;

    fn next(&mut self) -> Option<Self::Item> {
        let all = &self.program.moves;
        if self.ended || (self.next_move >= all.len() && self.next_move > 0) {
            return None;
        }
        let end = (self.next_move + self.moves_per_piece).min(all.len());
        let moves = &all[self.next_move..end];
        self.next_move = end;
        let plan = self.plan_next(moves);
        match &plan {
            Ok(p) => {
                self.start = p.end_state();
                self.ended = p.program_end_line().is_some() || end >= all.len();
            }
            Err(_) => self.ended = true,
        }
        Some(plan)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn duty(hours: usize) -> String {
        format!(
            "G21 G90\nG0 X20 Y20 Z-100\no100 repeat [{hours}]\nS6000 M3\no110 repeat [30]\n\
             G1 X540 Y20 Z-100 F3000\nG1 X540 Y380 Z-300\nG1 X20 Y380 Z-100\nG1 X20 Y20 Z-300\n\
             o110 endrepeat\nM5\nG4 P1800\no100 endrepeat\nM30\n"
        )
    }

    #[test]
    fn pieces_join_into_the_whole_plan() {
        let spec = MachineSpec::reference();
        let text = duty(3);
        let start = spec.axes.home_mm;
        let tools = ToolTable::default();
        let whole = super::super::plan_source(&text, "duty.ngc", &spec, start).unwrap();
        let program = ProgramMoves::from_source(&text, "duty.ngc", &spec, start, &tools).unwrap();
        let pieces: Vec<Plan> = program
            .pieces(&spec, start, &tools, 50)
            .collect::<Result<_, _>>()
            .unwrap();
        assert!(pieces.len() > 5, "{}", pieces.len());
        let segments: Vec<_> = pieces.iter().flat_map(|p| p.segments().iter()).collect();
        assert_eq!(segments.len(), whole.segments().len());
        let mut t0_s = 0.0;
        let mut k = 0;
        for p in &pieces {
            for s in p.segments() {
                let w = &whole.segments()[k];
                assert_eq!((s.line, s.kind, s.end_mm), (w.line, w.kind, w.end_mm));
                // The spindle carries over from one piece to the next.
                assert_eq!(s.spindle_rpm, w.spindle_rpm, "segment {k}");
                assert!(
                    (t0_s + s.t_start_s - w.t_start_s).abs() < 1e-6,
                    "segment {k}"
                );
                k += 1;
            }
            t0_s += p.duration_s();
        }
        assert!((t0_s - whole.duration_s()).abs() < 1e-6);
    }

    #[test]
    fn a_piece_outside_the_travel_is_refused_with_its_line() {
        let spec = MachineSpec::reference();
        let mut text = duty(1);
        text = text.replace("M30", "G0 X5000\nM30");
        let tools = ToolTable::default();
        let start = spec.axes.home_mm;
        let program = ProgramMoves::from_source(&text, "far.ngc", &spec, start, &tools).unwrap();
        let results: Vec<_> = program.pieces(&spec, start, &tools, 16).collect();
        let err = results.last().unwrap().as_ref().unwrap_err().to_string();
        assert!(err.starts_with("far.ngc: line 14"), "{err}");
        assert!(results[..results.len() - 1].iter().all(Result::is_ok));
    }

    #[test]
    fn an_empty_program_gives_one_empty_piece() {
        let spec = MachineSpec::reference();
        let tools = ToolTable::default();
        let program = ProgramMoves::from_source("", "empty.ngc", &spec, [0.0; 3], &tools).unwrap();
        let pieces: Vec<_> = program.pieces(&spec, [0.0; 3], &tools, 16).collect();
        assert_eq!(pieces.len(), 1);
        assert!(pieces[0].as_ref().unwrap().segments().is_empty());
    }
}
