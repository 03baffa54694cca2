//! Program flow: evaluates each line's values and parameter settings, and runs O-word control
//! flow (LinuxCNC semantics) around the modal interpreter.
//!
//! - Settings `#… = value` are evaluated with the values the parameters had when the line
//!   started and applied in order, before the line's block executes.
//! - `sub … endsub` defines a subroutine (anywhere in the file; not nested); reaching a
//!   definition skips it. `call [a]…` runs it with `#1…` = the arguments in a new scope;
//!   `return [v]` / `endsub [v]` set `#<_value>` and `#<_value_returned>`.
//! - `if/elseif/else/endif`, `while/endwhile`, `do … while`, `repeat/endrepeat`, `break` and
//!   `continue` pair up by O-word name and nesting.
//! - Fanuc style: `O100` alone starts a subroutine that ends at the next `M99`; `M98 P100
//!   L3` runs it 3 times (the rest of the M98 block executes first); it shares every parameter
//!   with its caller. Reached in the main flow, an `O` line is only a label; `M99` in the
//!   main program ends it (as in LinuxCNC's stand-alone interpreter; a controller would
//!   restart it).
//! - At most [`MAX_ITERATIONS`] loop iterations and [`MAX_CALL_DEPTH`] nested calls: a
//!   program beyond either is refused as unsupported (LinuxCNC itself would run forever).

use std::collections::HashMap;

use super::expr::{Params, Target, CALL_PARAMS};
use super::probe::{ProbeOutcome, ProbeParams, ProbeRequest, PROBE_PARAM_FIRST};
use super::program::{kw, sub_key, Pos, Program};
use super::{CanonKind, CanonMove, InterpConfig, Interpreter};
use crate::syntax::{Block, CallSite, GcodeError, Line, OKind, OName, OWord, Word};

/// Most loop iterations (all loops of a run together).
pub const MAX_ITERATIONS: u64 = 1_000_000;
/// Deepest subroutine call nesting.
pub const MAX_CALL_DEPTH: usize = 64;

/// One active call.
#[derive(Debug)]
pub(super) struct Frame {
    /// The call's line.
    called_from: Pos,
    return_to: Pos,
    /// `#1…#30` of the caller (O-word calls; Fanuc-style calls share all parameters).
    saved: Option<[f64; CALL_PARAMS]>,
    /// Fanuc-style call: (O-word index of the `O` line, repetitions left).
    fanuc: Option<(usize, i64)>,
}

/// Execution state around the modal interpreter.
#[derive(Debug)]
pub(super) struct Runner {
    pub(super) interp: Interpreter,
    params: Params,
    frames: Vec<Frame>,
    /// Remaining iterations of active `repeat` loops, by the O-word index of their `repeat` line.
    repeats: HashMap<usize, i64>,
    iterations: u64,
    block_delete: bool,
    /// Line of an M99 in the main program, which ends it.
    pub(super) main_m99_end: Option<usize>,
    /// The probe move of the last block executed, while its result is still to come.
    pub(super) probe: Option<ProbeRequest>,
    /// #5061…#5070 as the last probe result set them.
    pub(super) last_probe_params: Option<ProbeParams>,
}

impl Runner {
    /// A runner at the start of a program, in LinuxCNC's start-up state.
    pub(super) fn new(cfg: &InterpConfig) -> Self {
        let mut runner = Runner {
            interp: Interpreter::new(cfg.clone()),
            params: Params::new(),
            frames: Vec::new(),
            repeats: HashMap::new(),
            iterations: 0,
            block_delete: cfg.block_delete,
            main_m99_end: None,
            probe: None,
            last_probe_params: None,
        };
        runner.interp.sync_params_out(&mut runner.params);
        runner
    }

    /// The calls active now, innermost first (see [`GcodeError::calls`]).
    pub(super) fn call_sites(&self, prog: &Program) -> Vec<CallSite> {
        self.frames
            .iter()
            .rev()
            .map(|f| CallSite {
                file: prog.file_of(f.called_from).cloned(),
                line: f.called_from.line,
            })
            .collect()
    }

    /// Gives the pending probe move its result and writes #5061…#5070.
    pub(super) fn probe_result(&mut self, outcome: ProbeOutcome) -> Result<(), GcodeError> {
        let values = self.interp.probe_result(outcome)?;
        self.probe = None;
        self.last_probe_params = Some(values);
        for (i, v) in values.into_iter().enumerate() {
            self.params.set(PROBE_PARAM_FIRST + i, v);
        }
        // The tool rests elsewhere now: #5420… follow it.
        self.interp.sync_params_out(&mut self.params);
        Ok(())
    }

    /// Executes line `l`, at `at` (the line after it at `next`); returns where execution
    /// goes on.
    pub(super) fn step(
        &mut self,
        prog: &mut Program,
        (at, l, next): (Pos, &Line, Pos),
        out: &mut Vec<CanonMove>,
    ) -> Result<Pos, GcodeError> {
        if l.block_delete && self.block_delete {
            return Ok(next);
        }
        if let Some(o) = &l.oword {
            let i = prog.oword_at(at).ok_or_else(|| {
                GcodeError::invalid(l.line, o.col, "the program changed while it was running")
            })?;
            return self.oword(prog, (i, next), l, o, out);
        }
        // The line is read left to right: a named parameter a setting targets exists (0 if
        // it is new) for everything after its `#<…>` on the line, as in LinuxCNC; all values
        // are still read before any setting applies.
        let mut words = Vec::with_capacity(l.words.len());
        let mut settings: Vec<(Target, f64)> = Vec::with_capacity(l.assigns.len());
        let (mut wi, mut ai) = (0, 0);
        while wi < l.words.len() || ai < l.assigns.len() {
            let word_first = match (l.words.get(wi), l.assigns.get(ai)) {
                (Some(w), Some(a)) => w.col < a.col,
                (w, _) => w.is_some(),
            };
            if word_first {
                let w = &l.words[wi];
                wi += 1;
                let value = self.params.eval(&w.value, l.line, w.col)?;
                words.push(Word {
                    letter: w.letter,
                    value,
                    col: w.col,
                });
            } else {
                let a = &l.assigns[ai];
                ai += 1;
                let t = self.params.target(&a.target, l.line, a.col)?;
                self.params.define(&t);
                settings.push((t, self.params.eval(&a.value, l.line, a.col)?));
            }
        }
        for (t, v) in settings {
            self.params.assign(t, v);
        }
        for m in &l.messages {
            out.push(CanonMove {
                line: l.line,
                kind: CanonKind::Message(m.clone()),
            });
        }
        let m98 = take_m(&mut words, 98.0);
        let m99 = take_m(&mut words, 99.0);
        let (mut p, mut count) = (None, 1.0);
        if m98.is_some() {
            p = take_letter(&mut words, 'P');
            count = take_letter(&mut words, 'L').map_or(1.0, |w| w.value);
        }
        if !words.is_empty() {
            let block = Block {
                line: l.line,
                line_number: l.line_number,
                words,
                first_col: l.first_col,
            };
            self.interp.sync_params_in(&self.params);
            self.probe = self.interp.execute_block(&block, out)?;
            self.interp.sync_params_out(&mut self.params);
            if self.interp.is_ended() {
                return Ok(next);
            }
        }
        if let Some(col) = m98 {
            return self.fanuc_call(prog, (at, next), l, col, p, count);
        }
        if let Some(col) = m99 {
            return self.fanuc_return(prog, next, l, col);
        }
        Ok(next)
    }

    /// `M98 P… L…`: runs Fanuc-style subroutine `O…` L times.
    fn fanuc_call(
        &mut self,
        prog: &mut Program,
        (at, next): (Pos, Pos),
        l: &Line,
        col: usize,
        p: Option<Word>,
        count: f64,
    ) -> Result<Pos, GcodeError> {
        let Some(p) = p else {
            return Err(GcodeError::invalid(
                l.line,
                col,
                "M98 needs a P word (subroutine number)",
            ));
        };
        if count.fract() != 0.0 || count < 0.0 {
            return Err(GcodeError::invalid(
                l.line,
                col,
                "M98 L must be a whole number >= 0",
            ));
        }
        // The subroutine may lie ahead, unscanned yet.
        prog.complete()?;
        let name = sub_key(&OName::Number(p.value));
        let Some(&start) = prog.subs.get(&format!("fanuc {name}")) else {
            if let Some(e) = &prog.tail_error {
                return Err(e.clone());
            }
            let msg = if prog.subs.contains_key(&name) {
                format!(
                    "M98 P{}: {name} is an O-word subroutine (use {name} call)",
                    p.value
                )
            } else {
                format!("M98 P{}: no subroutine {name}", p.value)
            };
            return Err(GcodeError::invalid(l.line, p.col, msg));
        };
        if count < 1.0 {
            return Ok(next);
        }
        if self.frames.len() >= MAX_CALL_DEPTH {
            return Err(GcodeError::unsupported(
                l.line,
                col,
                format!("subroutine calls nested deeper than {MAX_CALL_DEPTH}"),
            ));
        }
        self.count_iteration(l.line, col)?;
        self.frames.push(Frame {
            called_from: at,
            return_to: next,
            saved: None,
            fanuc: Some((start, count as i64 - 1)),
        });
        Ok(prog.owords[start].next)
    }

    /// `M99`: repeats or ends the Fanuc-style subroutine.
    fn fanuc_return(
        &mut self,
        prog: &Program,
        next: Pos,
        l: &Line,
        col: usize,
    ) -> Result<Pos, GcodeError> {
        match self.frames.last_mut() {
            None => {
                // M99 in the main program: a controller restarts it; LinuxCNC's stand-alone
                // interpreter, like this one, ends the program there.
                self.main_m99_end = Some(l.line);
                Ok(next)
            }
            Some(Frame { fanuc: None, .. }) => Err(GcodeError::invalid(
                l.line,
                col,
                "M99 inside an O-word subroutine (use endsub or return)",
            )),
            Some(Frame {
                fanuc: Some((start, left)),
                return_to,
                ..
            }) => {
                if *left > 0 {
                    *left -= 1;
                    let start = *start;
                    self.count_iteration(l.line, col)?;
                    Ok(prog.owords[start].next)
                } else {
                    let to = *return_to;
                    self.frames.pop();
                    Ok(to)
                }
            }
        }
    }

    fn cond(&self, l: &Line, o: &OWord) -> Result<f64, GcodeError> {
        match o.args.first() {
            Some(e) => self.params.eval(e, l.line, o.col),
            None => Ok(0.0),
        }
    }

    fn count_iteration(&mut self, line: usize, col: usize) -> Result<(), GcodeError> {
        self.iterations += 1;
        if self.iterations > MAX_ITERATIONS {
            return Err(GcodeError::unsupported(
                line,
                col,
                format!("more than {MAX_ITERATIONS} loop iterations (endless loop?)"),
            ));
        }
        Ok(())
    }

    /// Runs O-word line `i` (`l`, its statement `o`; the line after it at `next`).
    fn oword(
        &mut self,
        prog: &mut Program,
        (i, next): (usize, Pos),
        l: &Line,
        o: &OWord,
        out: &mut Vec<CanonMove>,
    ) -> Result<Pos, GcodeError> {
        let after = |prog: &Program, j: usize| prog.owords[j].next;
        Ok(match o.kind {
            OKind::Sub => after(prog, prog.partner(i)?),
            // In the main flow (or inside a subroutine) an `O` line is only a label.
            OKind::Program => next,
            OKind::EndSub | OKind::Return => self.sub_return(l, o, out)?,
            OKind::Call => self.call(prog, (i, next), l, o)?,
            OKind::If => {
                let mut at = i;
                let mut take = self.cond(l, o)? != 0.0;
                loop {
                    if take {
                        break after(prog, at);
                    }
                    at = prog.partner(at)?;
                    match prog.owords[at].kind {
                        OKind::ElseIf => {
                            let bl = prog.oword_line(at)?;
                            let bo = bl.oword.as_ref().expect("an O-word line");
                            take = self.cond(&bl, bo)? != 0.0;
                        }
                        OKind::Else => take = true,
                        _ => break after(prog, at),
                    }
                }
            }
            OKind::ElseIf | OKind::Else => {
                // Reached at the end of a taken branch: skip to after `endif`.
                let mut at = i;
                while prog.owords[at].kind != OKind::EndIf {
                    at = prog.partner(at)?;
                }
                after(prog, at)
            }
            OKind::EndIf | OKind::Do => next,
            OKind::While => self.while_head(prog, (i, next), l, o)?,
            OKind::EndWhile => {
                self.count_iteration(l.line, o.col)?;
                prog.owords[prog.partner(i)?].pos
            }
            OKind::Repeat => {
                let n = self.cond(l, o)?.round() as i64;
                if n <= 0 {
                    after(prog, prog.partner(i)?)
                } else {
                    self.repeats.insert(i, n);
                    next
                }
            }
            OKind::EndRepeat => {
                let head = prog.partner(i)?;
                let left = self.repeats.get(&head).copied().unwrap_or(1) - 1;
                if left > 0 {
                    self.count_iteration(l.line, o.col)?;
                    self.repeats.insert(head, left);
                    after(prog, head)
                } else {
                    self.repeats.remove(&head);
                    next
                }
            }
            OKind::Break => {
                let head = prog.partner(i)?;
                self.repeats.remove(&head);
                after(prog, prog.partner(head)?)
            }
            OKind::Continue => {
                let head = prog.partner(i)?;
                match prog.owords[head].kind {
                    OKind::While => {
                        self.count_iteration(l.line, o.col)?;
                        prog.owords[head].pos
                    }
                    // `do … while` and `repeat`: go to the loop's end, which decides.
                    _ => prog.owords[prog.partner(head)?].pos,
                }
            }
        })
    }

    /// `while` (O-word line `i`): the head of a `while` loop, or the end of a `do` loop.
    fn while_head(
        &mut self,
        prog: &Program,
        (i, next): (usize, Pos),
        l: &Line,
        o: &OWord,
    ) -> Result<Pos, GcodeError> {
        Ok(match prog.partner(i).ok() {
            // The end of a `do` loop.
            Some(head) if prog.owords[head].kind == OKind::Do && head < i => {
                if self.cond(l, o)? != 0.0 {
                    self.count_iteration(l.line, o.col)?;
                    prog.owords[head].next
                } else {
                    next
                }
            }
            Some(end) => {
                if self.cond(l, o)? != 0.0 {
                    next
                } else {
                    prog.owords[end].next
                }
            }
            None => {
                return Err(GcodeError::invalid(
                    l.line,
                    o.col,
                    "O-word without its matching end",
                ))
            }
        })
    }

    /// `endsub` / `return`: back to the caller, with the value returned.
    fn sub_return(
        &mut self,
        l: &Line,
        o: &OWord,
        out: &mut Vec<CanonMove>,
    ) -> Result<Pos, GcodeError> {
        let Some(frame) = self.frames.pop().filter(|f| f.fanuc.is_none()) else {
            return Err(GcodeError::invalid(
                l.line,
                o.col,
                format!("{} {} outside a subroutine call", o.name, kw(o.kind)),
            ));
        };
        let value = match o.args.first() {
            Some(e) => Some(self.params.eval(e, l.line, o.col)?),
            None => None,
        };
        if let Some(saved) = &frame.saved {
            self.params.leave_call(saved);
        }
        // The state saved by M73 in the subroutine comes back.
        let restored = self.interp.leave_call();
        out.extend(
            restored
                .into_iter()
                .map(|kind| CanonMove { line: l.line, kind }),
        );
        self.params
            .set_global("_value_returned", f64::from(u8::from(value.is_some())));
        self.params.set_global("_value", value.unwrap_or(0.0));
        Ok(frame.return_to)
    }

    /// `call`: into the subroutine, with `#1…` the arguments.
    fn call(
        &mut self,
        prog: &Program,
        (i, next): (usize, Pos),
        l: &Line,
        o: &OWord,
    ) -> Result<Pos, GcodeError> {
        let name = match &o.name {
            OName::Computed(e) => OName::Number(self.params.eval(e, l.line, o.col)?),
            other => other.clone(),
        };
        let Some(&start) = prog.subs.get(&sub_key(&name)) else {
            // The definition may lie beyond a syntax error.
            if let Some(e) = &prog.tail_error {
                return Err(e.clone());
            }
            return Err(match name {
                OName::Named(ref n) => {
                    GcodeError::unsupported(l.line, o.col, not_found_msg(&name, n, &prog.searched))
                }
                _ => GcodeError::invalid(l.line, o.col, format!("{name} call: no such subroutine")),
            });
        };
        if self.frames.len() >= MAX_CALL_DEPTH {
            return Err(GcodeError::unsupported(
                l.line,
                o.col,
                format!("subroutine calls nested deeper than {MAX_CALL_DEPTH}"),
            ));
        }
        self.count_iteration(l.line, o.col)?;
        let mut args = Vec::with_capacity(o.args.len());
        for a in &o.args {
            args.push(self.params.eval(a, l.line, o.col)?);
        }
        let saved = self.params.enter_call(&args);
        self.interp.enter_call();
        self.frames.push(Frame {
            called_from: prog.owords[i].pos,
            return_to: next,
            saved: Some(saved),
            fanuc: None,
        });
        Ok(prog.owords[start].next)
    }
}

/// Removes the word M`code` from `words`; its column if it was there.
fn take_m(words: &mut Vec<Word>, code: f64) -> Option<usize> {
    let i = words
        .iter()
        .position(|w| w.letter == 'M' && w.value == code)?;
    Some(words.remove(i).col)
}

/// Removes the word with `letter` from `words`.
fn take_letter(words: &mut Vec<Word>, letter: char) -> Option<Word> {
    let i = words.iter().position(|w| w.letter == letter)?;
    Some(words.remove(i))
}

/// Why `o<n> call` found no subroutine: neither in the program nor as `<n>.ngc` in a
/// subroutine folder (the folders searched are listed, in order).
fn not_found_msg(name: &OName, n: &str, searched: &[std::path::PathBuf]) -> String {
    if searched.is_empty() {
        return format!(
            "{name} call: no subroutine {name} in this program, and no subroutine folder to \
             look for {n}.ngc in"
        );
    }
    let dirs: Vec<String> = searched
        .iter()
        .map(|d| match d.as_os_str().is_empty() {
            true => ".".to_string(),
            false => d.display().to_string(),
        })
        .collect();
    format!(
        "{name} call: no subroutine {name} in this program, and no file {n}.ngc in the \
         subroutine folders ({})",
        dirs.join(", ")
    )
}
