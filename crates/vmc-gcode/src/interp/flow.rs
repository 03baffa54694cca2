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
use super::sub_files::SubFile;
use super::{CanonKind, CanonMove, InterpConfig, Interpreter};
use crate::syntax::{Block, CallSite, GcodeError, Line, OKind, OName, OWord, Word};

/// Most loop iterations (all loops of a run together).
pub const MAX_ITERATIONS: u64 = 1_000_000;
/// Deepest subroutine call nesting.
pub const MAX_CALL_DEPTH: usize = 64;

/// A parsed program: its lines and the syntax error that ended parsing, if any.
#[derive(Debug)]
pub(super) struct Program {
    pub(super) lines: Vec<Line>,
    pub(super) tail_error: Option<GcodeError>,
    /// For each line index: the index of its partner (see [`pair`]).
    partner: Vec<Option<usize>>,
    /// Subroutine name → index of its `sub` line.
    subs: HashMap<String, usize>,
    /// The subroutine files whose definitions follow the program's own lines.
    pub(super) files: Vec<SubFile>,
    /// The folders searched for subroutine files (named in the error of a call not found).
    searched: Vec<std::path::PathBuf>,
}

/// An O-word structure error: (the index from which execution meets it, the index of the
/// offending line — `None` for the main program's syntax error that cut it short — the error).
pub(super) type StructureError = (usize, Option<usize>, GcodeError);

impl Program {
    /// Parses `src`, reads the subroutine files it needs and pairs its O-words. The structure
    /// error, if any, is returned for the caller to report when execution reaches it.
    pub(super) fn new(
        src: &str,
        cfg: &InterpConfig,
    ) -> Result<(Self, Option<StructureError>), GcodeError> {
        let mut lines = Vec::new();
        let mut tail_error = None;
        for line in crate::syntax::parse_program(src) {
            match line {
                Ok(l) => lines.push(l),
                Err(e) => tail_error = Some(e),
            }
        }
        let files = super::sub_files::load(&mut lines, cfg)?;
        let mut prog = Program {
            partner: vec![None; lines.len()],
            lines,
            tail_error,
            subs: HashMap::new(),
            files,
            searched: cfg.subroutine_dirs.clone(),
        };
        let structure_error = pair(&mut prog).err();
        Ok((prog, structure_error))
    }

    /// The subroutine file of line index `i` (`None`: the main program).
    pub(super) fn file_of(&self, i: usize) -> Option<&std::path::PathBuf> {
        super::sub_files::file_of(&self.files, i)
    }
}

/// One active call.
#[derive(Debug)]
pub(super) struct Frame {
    return_to: usize,
    /// `#1…#30` of the caller (O-word calls; Fanuc-style calls share all parameters).
    saved: Option<[f64; CALL_PARAMS]>,
    /// Fanuc-style call: (index of the `O` line, repetitions left).
    fanuc: Option<(usize, i64)>,
}

fn key(name: &OName) -> String {
    name.to_string()
}

/// Pairs O-word statements by name and nesting: `if`/`elseif`/`else` → next branch,
/// `while`/`do`/`repeat` → their end, ends → their head, `break`/`continue` → their loop's
/// head, `sub` → `endsub`. On error see [`StructureError`].
fn pair(prog: &mut Program) -> Result<(), StructureError> {
    let mut stack: Vec<usize> = Vec::new();
    for i in 0..prog.lines.len() {
        let l = &prog.lines[i];
        let Some(o) = &l.oword else {
            continue;
        };
        let first_open = stack.first().copied().unwrap_or(i).min(i);
        let fail =
            |msg: String| Err((first_open, Some(i), GcodeError::invalid(l.line, o.col, msg)));
        let open = stack
            .last()
            .map(|&j| (j, prog.lines[j].oword.as_ref().expect("stacked O-word")));
        let same = |j: usize| prog.lines[j].oword.as_ref().map(|p| &p.name) == Some(&o.name);
        match o.kind {
            OKind::Sub => {
                if stack
                    .iter()
                    .any(|&j| prog.lines[j].oword.as_ref().map(|p| p.kind) == Some(OKind::Sub))
                {
                    return fail(format!(
                        "{} sub: subroutine definitions cannot be nested",
                        o.name
                    ));
                }
                prog.subs.entry(key(&o.name)).or_insert(i);
                stack.push(i);
            }
            OKind::If | OKind::Do | OKind::Repeat => stack.push(i),
            OKind::While => match open {
                Some((j, p)) if p.kind == OKind::Do && same(j) => {
                    prog.partner[j] = Some(i);
                    prog.partner[i] = Some(j);
                    stack.pop();
                }
                _ => stack.push(i),
            },
            OKind::ElseIf | OKind::Else | OKind::EndIf => match open {
                Some((j, p))
                    if matches!(p.kind, OKind::If | OKind::ElseIf | OKind::Else) && same(j) =>
                {
                    if p.kind == OKind::Else && o.kind != OKind::EndIf {
                        return fail(format!("{} {:?} after else", o.name, o.kind).to_lowercase());
                    }
                    prog.partner[j] = Some(i);
                    stack.pop();
                    if o.kind != OKind::EndIf {
                        stack.push(i);
                    }
                }
                _ => return fail(format!("{} without a matching {} if", kw(o.kind), o.name)),
            },
            OKind::EndWhile | OKind::EndRepeat | OKind::EndSub => {
                let head = match o.kind {
                    OKind::EndWhile => OKind::While,
                    OKind::EndRepeat => OKind::Repeat,
                    _ => OKind::Sub,
                };
                match open {
                    Some((j, p)) if p.kind == head && same(j) => {
                        prog.partner[j] = Some(i);
                        prog.partner[i] = Some(j);
                        stack.pop();
                    }
                    _ => {
                        return fail(format!(
                            "{} without a matching {} {}",
                            kw(o.kind),
                            o.name,
                            kw(head)
                        ))
                    }
                }
            }
            OKind::Break | OKind::Continue => {
                let head = stack.iter().rev().copied().find(|&j| {
                    same(j)
                        && matches!(
                            prog.lines[j].oword.as_ref().map(|p| p.kind),
                            Some(OKind::While | OKind::Do | OKind::Repeat)
                        )
                });
                match head {
                    Some(j) => prog.partner[i] = Some(j),
                    None => return fail(format!("{} outside a loop named {}", kw(o.kind), o.name)),
                }
            }
            OKind::Program => {
                prog.subs
                    .entry(format!("fanuc {}", key(&o.name)))
                    .or_insert(i);
            }
            OKind::Call | OKind::Return => {}
        }
    }
    if let Some(&j) = stack.first() {
        // An open structure: the syntax error that cut the program short explains it best.
        let last = stack[stack.len() - 1];
        let l = &prog.lines[last];
        let o = l.oword.as_ref().expect("stacked O-word");
        return Err(match prog.tail_error.clone() {
            Some(e) => (j, None, e),
            None => {
                let msg = format!("{} {} is never closed", o.name, kw(o.kind));
                (j, Some(last), GcodeError::invalid(l.line, o.col, msg))
            }
        });
    }
    Ok(())
}

fn kw(k: OKind) -> &'static str {
    match k {
        OKind::Program => "",
        OKind::Sub => "sub",
        OKind::EndSub => "endsub",
        OKind::Call => "call",
        OKind::Return => "return",
        OKind::If => "if",
        OKind::ElseIf => "elseif",
        OKind::Else => "else",
        OKind::EndIf => "endif",
        OKind::While => "while",
        OKind::EndWhile => "endwhile",
        OKind::Do => "do",
        OKind::Repeat => "repeat",
        OKind::EndRepeat => "endrepeat",
        OKind::Break => "break",
        OKind::Continue => "continue",
    }
}

/// Execution state around the modal interpreter.
#[derive(Debug)]
pub(super) struct Runner {
    pub(super) interp: Interpreter,
    params: Params,
    frames: Vec<Frame>,
    /// Remaining iterations of active `repeat` loops, by the index of their `repeat` line.
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
                file: prog.file_of(f.return_to - 1).cloned(),
                line: prog.lines[f.return_to - 1].line,
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

    /// Executes line `pc`; returns the index of the next line.
    pub(super) fn step(
        &mut self,
        prog: &Program,
        pc: usize,
        out: &mut Vec<CanonMove>,
    ) -> Result<usize, GcodeError> {
        let l = &prog.lines[pc];
        if l.block_delete && self.block_delete {
            return Ok(pc + 1);
        }
        if let Some(o) = &l.oword {
            return self.oword(prog, pc, l, o, out);
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
                return Ok(pc + 1);
            }
        }
        if let Some(col) = m98 {
            return self.fanuc_call(prog, pc, l, col, p, count);
        }
        if let Some(col) = m99 {
            return self.fanuc_return(l, col);
        }
        Ok(pc + 1)
    }

    /// `M98 P… L…`: runs Fanuc-style subroutine `O…` L times.
    fn fanuc_call(
        &mut self,
        prog: &Program,
        pc: usize,
        l: &Line,
        col: usize,
        p: Option<Word>,
        count: f64,
    ) -> Result<usize, GcodeError> {
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
        let name = key(&OName::Number(p.value));
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
            return Ok(pc + 1);
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
            return_to: pc + 1,
            saved: None,
            fanuc: Some((start, count as i64 - 1)),
        });
        Ok(start + 1)
    }

    /// `M99`: repeats or ends the Fanuc-style subroutine.
    fn fanuc_return(&mut self, l: &Line, col: usize) -> Result<usize, GcodeError> {
        match self.frames.last_mut() {
            None => {
                // M99 in the main program: a controller restarts it; LinuxCNC's stand-alone
                // interpreter, like this one, ends the program there.
                self.main_m99_end = Some(l.line);
                Ok(usize::MAX)
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
                    Ok(start + 1)
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

    fn partner(prog: &Program, pc: usize) -> Result<usize, GcodeError> {
        prog.partner[pc].ok_or_else(|| {
            let l = &prog.lines[pc];
            let col = l.oword.as_ref().map_or(1, |o| o.col);
            GcodeError::invalid(l.line, col, "O-word without its matching end")
        })
    }

    fn oword(
        &mut self,
        prog: &Program,
        pc: usize,
        l: &Line,
        o: &OWord,
        out: &mut Vec<CanonMove>,
    ) -> Result<usize, GcodeError> {
        Ok(match o.kind {
            OKind::Sub => Self::partner(prog, pc)? + 1,
            // In the main flow (or inside a subroutine) an `O` line is only a label.
            OKind::Program => pc + 1,
            OKind::EndSub | OKind::Return => {
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
                frame.return_to
            }
            OKind::Call => {
                let name = match &o.name {
                    OName::Computed(e) => OName::Number(self.params.eval(e, l.line, o.col)?),
                    other => other.clone(),
                };
                let Some(&start) = prog.subs.get(&key(&name)) else {
                    // The definition may lie beyond a syntax error.
                    if let Some(e) = &prog.tail_error {
                        return Err(e.clone());
                    }
                    return Err(match name {
                        OName::Named(ref n) => GcodeError::unsupported(
                            l.line,
                            o.col,
                            not_found_msg(&name, n, &prog.searched),
                        ),
                        _ => GcodeError::invalid(
                            l.line,
                            o.col,
                            format!("{name} call: no such subroutine"),
                        ),
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
                    return_to: pc + 1,
                    saved: Some(saved),
                    fanuc: None,
                });
                start + 1
            }
            OKind::If => {
                let mut at = pc;
                let mut take = self.cond(l, o)? != 0.0;
                loop {
                    if take {
                        break at + 1;
                    }
                    at = Self::partner(prog, at)?;
                    let bl = &prog.lines[at];
                    let Some(bo) = bl.oword.as_ref() else {
                        break at + 1;
                    };
                    match bo.kind {
                        OKind::ElseIf => take = self.cond(bl, bo)? != 0.0,
                        OKind::Else => take = true,
                        _ => break at + 1,
                    }
                }
            }
            OKind::ElseIf | OKind::Else => {
                // Reached at the end of a taken branch: skip to after `endif`.
                let mut at = pc;
                while prog.lines[at].oword.as_ref().map(|p| p.kind) != Some(OKind::EndIf) {
                    at = Self::partner(prog, at)?;
                }
                at + 1
            }
            OKind::EndIf | OKind::Do => pc + 1,
            OKind::While => match prog.partner[pc] {
                // The end of a `do` loop.
                Some(head)
                    if prog.lines[head].oword.as_ref().map(|p| p.kind) == Some(OKind::Do)
                        && head < pc =>
                {
                    if self.cond(l, o)? != 0.0 {
                        self.count_iteration(l.line, o.col)?;
                        head + 1
                    } else {
                        pc + 1
                    }
                }
                Some(end) => {
                    if self.cond(l, o)? != 0.0 {
                        pc + 1
                    } else {
                        end + 1
                    }
                }
                None => {
                    return Err(GcodeError::invalid(
                        l.line,
                        o.col,
                        "O-word without its matching end",
                    ))
                }
            },
            OKind::EndWhile => {
                self.count_iteration(l.line, o.col)?;
                Self::partner(prog, pc)?
            }
            OKind::Repeat => {
                let n = self.cond(l, o)?.round() as i64;
                if n <= 0 {
                    Self::partner(prog, pc)? + 1
                } else {
                    self.repeats.insert(pc, n);
                    pc + 1
                }
            }
            OKind::EndRepeat => {
                let head = Self::partner(prog, pc)?;
                let left = self.repeats.get(&head).copied().unwrap_or(1) - 1;
                if left > 0 {
                    self.count_iteration(l.line, o.col)?;
                    self.repeats.insert(head, left);
                    head + 1
                } else {
                    self.repeats.remove(&head);
                    pc + 1
                }
            }
            OKind::Break => {
                let head = Self::partner(prog, pc)?;
                self.repeats.remove(&head);
                Self::partner(prog, head)? + 1
            }
            OKind::Continue => {
                let head = Self::partner(prog, pc)?;
                match prog.lines[head].oword.as_ref().map(|p| p.kind) {
                    Some(OKind::While) => {
                        self.count_iteration(l.line, o.col)?;
                        head
                    }
                    // `do … while` and `repeat`: go to the loop's end, which decides.
                    _ => Self::partner(prog, head)?,
                }
            }
        })
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
