//! A program whose probe moves (G38.2 … G38.5) are answered by a machine model rather than by
//! the stand-alone convention: the interpreter stops at each probe move, the caller's answer
//! (the nominal machine's for `check`, the twin's for `run`) gives #5061…#5070 and the rest
//! point, and the probe move is planned to where the axes stopped.
//!
//! A G38.2/G38.4 without contact (or starting in the state it seeks) stops the program, as on
//! the machine: the moves before it are kept and the stop is returned beside them, so a checker
//! can still check the path up to the probe and report it.

use super::{interp, plan_moves, read_program, InterpConfig, LineUnits, ProgramError};
use crate::machine::MachineSpec;
use crate::motion::Plan;
use crate::setup::Placement;
use crate::tools::ToolTable;
use interp::{CanonKind, CanonMove, GcodeError, ProbeOutcome, ProbeRequest, ProgramRun, RunEvent};

/// Sets the probe move `mv` (the last move the interpreter emitted) to end where the machine
/// left the axes after `outcome`: the rest point of a trip, the start for a probe already in
/// the state it seeks, the target otherwise (no contact, and the stand-alone convention, whose
/// plan keeps the programmed move).
pub fn end_probe_move(mv: &mut CanonMove, request: &ProbeRequest, outcome: &ProbeOutcome) {
    let CanonKind::Probe {
        end_mm,
        end_abc_deg,
        ..
    } = &mut mv.kind
    else {
        return;
    };
    match *outcome {
        ProbeOutcome::Tripped {
            rest_mm,
            rest_abc_deg,
            ..
        } => {
            *end_mm = rest_mm;
            *end_abc_deg = rest_abc_deg;
        }
        ProbeOutcome::AlreadyInState => {
            *end_mm = request.start_mm;
            *end_abc_deg = request.start_abc_deg;
        }
        ProbeOutcome::NoContact | ProbeOutcome::Standalone => {}
    }
}

/// One answered probe move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeRecord {
    /// The move.
    pub request: ProbeRequest,
    /// The machine's answer.
    pub outcome: ProbeOutcome,
    /// #5061…#5070 as the program reads them after it (`None` when the answer stopped the
    /// program).
    pub params: Option<interp::ProbeParams>,
}

/// A program's moves interpreted with answered probe moves.
#[derive(Debug, Clone)]
pub struct ProbedMoves {
    /// The canonical moves (probe moves ending where the axes stopped).
    pub moves: Vec<CanonMove>,
    /// The program's unit of length at each move.
    pub units: Vec<interp::LengthUnit>,
    /// The probe moves and their answers, in order.
    pub probes: Vec<ProbeRecord>,
    /// The error a probe result stopped the program with (G38.2 without contact…), if any.
    pub stopped: Option<GcodeError>,
}

/// Interprets `text` with `cfg`, every probe move answered by `answer`.
///
/// # Errors
/// The program's own errors (syntax, semantics); an error of a probe result is returned in
/// [`ProbedMoves::stopped`] instead.
pub fn interpret_probed(
    text: &str,
    cfg: &InterpConfig,
    answer: &mut dyn FnMut(&ProbeRequest) -> ProbeOutcome,
) -> Result<ProbedMoves, GcodeError> {
    let mut run = ProgramRun::new(text, cfg)?;
    let mut moves = Vec::new();
    let mut probes = Vec::new();
    let mut stopped = None;
    while let RunEvent::Probe(request) = run.resume(&mut moves)? {
        let outcome = answer(&request);
        if let Some(mv) = moves
            .iter_mut()
            .rev()
            .find(|m| matches!(m.kind, CanonKind::Probe { .. }))
        {
            end_probe_move(mv, &request, &outcome);
        }
        let result = run.probe_result(outcome);
        probes.push(ProbeRecord {
            request,
            outcome,
            params: result.is_ok().then(|| run.probe_params()).flatten(),
        });
        if let Err(e) = result {
            stopped = Some(e);
            break;
        }
    }
    let units = (0..moves.len()).map(|i| run.length_unit_at(i)).collect();
    Ok(ProbedMoves {
        moves,
        units,
        probes,
        stopped,
    })
}

/// A plan whose probe moves were answered, and how the program stopped.
#[derive(Debug)]
pub struct ProbedPlan {
    /// The plan (up to the stop, if the program stopped at a probe).
    pub plan: Plan,
    /// The unit of length at each line.
    pub units: LineUnits,
    /// The probe moves and their answers.
    pub probes: Vec<ProbeRecord>,
    /// A probe result that stopped the program, as the error `run` would give.
    pub stopped: Option<ProgramError>,
}

/// Reads, interprets (probe moves answered by `answer`) and plans the program at `path` placed
/// by `placement`, without the travel check (as [`super::load_plan_placed`] for `check`).
///
/// # Errors
/// Reading, syntax, semantics, planning.
pub fn load_plan_probed(
    path: &std::path::Path,
    machine: &MachineSpec,
    start_mm: [f64; 3],
    tools: &ToolTable,
    placement: &Placement,
    answer: &mut dyn FnMut(&ProbeRequest) -> ProbeOutcome,
) -> Result<ProbedPlan, ProgramError> {
    let (file, text) = read_program(path)?;
    let cfg = super::interp_config(machine, start_mm, tools, placement, Some(path));
    let gcode = |err| ProgramError::Gcode {
        file: file.clone(),
        err,
    };
    let probed = interpret_probed(&text, &cfg, answer).map_err(gcode)?;
    let (plan, units) = plan_moves(
        &probed.moves,
        &probed.units,
        &file,
        machine,
        start_mm,
        tools,
    )?;
    Ok(ProbedPlan {
        plan,
        units,
        probes: probed.probes,
        stopped: probed.stopped.map(gcode),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_probe_move_ends_where_the_machine_stopped_and_the_program_reads_the_trip() {
        let text = "G21 G90 F50\nG38.2 Z-10\nG0 Z[#5063 + 5]\nM2\n";
        let cfg = InterpConfig::default();
        let mut answer = |r: &ProbeRequest| ProbeOutcome::Tripped {
            trip_mm: [0.0, 0.0, -3.0],
            trip_abc_deg: r.end_abc_deg,
            rest_mm: [0.0, 0.0, -3.001],
            rest_abc_deg: r.end_abc_deg,
        };
        let p = interpret_probed(text, &cfg, &mut answer).unwrap();
        assert_eq!(p.probes.len(), 1);
        // #5063 the trip's Z, #5070 = 1.
        let params = p.probes[0].params.unwrap();
        assert_eq!((params[2], params[9]), (-3.0, 1.0));
        assert!(p.stopped.is_none());
        assert!(matches!(
            p.moves[0].kind,
            CanonKind::Probe {
                end_mm: [0.0, 0.0, -3.001],
                ..
            }
        ));
        assert!(matches!(
            p.moves[1].kind,
            CanonKind::Traverse {
                end_mm: [0.0, 0.0, 2.0],
                ..
            }
        ));
    }

    #[test]
    fn a_g38_2_without_contact_stops_the_program_after_the_moves_before_it() {
        let text = "G21 G90 F50\nG1 X1\nG38.2 Z-10\nG0 Z5\nM2\n";
        let mut answer = |_: &ProbeRequest| ProbeOutcome::NoContact;
        let p = interpret_probed(text, &InterpConfig::default(), &mut answer).unwrap();
        let e = p.stopped.unwrap();
        assert_eq!(e.line, 3);
        assert!(
            e.to_string()
                .contains("G38.2 move finished without making contact."),
            "{e}"
        );
        assert_eq!(p.moves.len(), 2);
    }
}
