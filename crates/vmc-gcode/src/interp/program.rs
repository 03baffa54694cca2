//! The program as the interpreter reads it: lines are read from a seekable source
//! ([`super::source`]) where execution is, and only the O-word lines are known ahead — their
//! places (file, byte offset, line number), keywords and names, paired by name and nesting
//! ([`pair`]) — with the places of the subroutines. Loops and calls seek back or ahead to
//! those places; nothing else of the text is held, whatever its length.
//!
//! The O-word table needs the whole text read once (a scan: every line parsed, the O-word
//! lines kept). A program that never reaches an O-word or an `M98` is run without it: its
//! lines are scanned as they execute, and the first O-word or `M98` reached completes the scan
//! before it runs (the table is then as if it had been built first). With subroutine folders
//! the scan is done at once, to read the subroutine files the program calls before it runs
//! (their errors come from [`Program::new`]).

use std::collections::HashMap;
use std::path::PathBuf;

use super::source::{next_line, LineSource, Next, ProgramSource, Reading};
pub(super) use super::source::{OEntry, Pos};
use super::sub_files::SubFile;
use super::InterpConfig;
use crate::syntax::{GcodeError, Line, OKind, OName};

/// An O-word structure error: (the place from which execution meets it, the place of the
/// offending line — `None` for the main program's syntax error that cut it short — the error).
pub(super) type StructureError = Box<(Pos, Option<Pos>, GcodeError)>;

/// A program being read: its source, its O-word table, its subroutine files.
#[derive(Debug)]
pub(super) struct Program {
    main: LineSource,
    /// Where the main program's first line is.
    origin: Pos,
    /// Where the main program's text ends (the closing `%`, the line of its syntax error, the
    /// source's end); unbounded until the scan is complete.
    main_end: u64,
    /// The subroutine files whose definitions follow the program's own lines.
    pub(super) files: Vec<SubFile>,
    /// The syntax error that ended the main program's text, once scanned.
    pub(super) tail_error: Option<GcodeError>,
    /// The O-word lines, in the order of [`Pos`].
    pub(super) owords: Vec<OEntry>,
    /// For each O-word line: the index of its partner (see [`pair`]).
    partner: Vec<Option<usize>>,
    /// Subroutine name → index of its `sub` line (`fanuc <n>`: its `O<n>` line).
    pub(super) subs: HashMap<String, usize>,
    /// The first O-word structure error, for execution to report when it gets there.
    pub(super) structure_error: Option<StructureError>,
    /// Where the scan of the main program stands, until it is complete.
    scan: Option<Reading>,
    /// The folders searched for subroutine files (named in the error of a call not found).
    pub(super) searched: Vec<PathBuf>,
}

impl Program {
    /// A program read from `source` (from its present position). With subroutine folders the
    /// whole text is scanned now and the files it calls are read.
    ///
    /// # Errors
    /// The source's position cannot be read; a subroutine file cannot be read, lacks its
    /// definition or has a syntax error.
    pub(super) fn new(
        source: Box<dyn ProgramSource>,
        cfg: &InterpConfig,
    ) -> Result<Self, GcodeError> {
        let main = LineSource::new(source)
            .map_err(|e| GcodeError::invalid(1, 1, format!("cannot read the program: {e}")))?;
        let origin = Pos {
            file: 0,
            offset: main.start(),
            line: 1,
        };
        let mut prog = Program {
            main,
            origin,
            main_end: u64::MAX,
            files: Vec::new(),
            tail_error: None,
            owords: Vec::new(),
            partner: Vec::new(),
            subs: HashMap::new(),
            structure_error: None,
            scan: Some(Reading {
                offset: origin.offset,
                line: 1,
                seen_content: false,
            }),
            searched: cfg.subroutine_dirs.clone(),
        };
        if !cfg.subroutine_dirs.is_empty() {
            prog.complete()?;
        }
        Ok(prog)
    }

    /// Where execution starts.
    pub(super) fn origin(&self) -> Pos {
        self.origin
    }

    /// The subroutine file of a place (`None`: the main program).
    pub(super) fn file_of(&self, pos: Pos) -> Option<&PathBuf> {
        pos.file.checked_sub(1).map(|k| &self.files[k].path)
    }

    /// The next line that does something from `pc`: its place, the line, the place after
    /// it; `None` at the end of the program (main program and subroutine definitions).
    ///
    /// # Errors
    /// A source that cannot be read, or a text that changed since it was scanned; completing
    /// the scan (see [`Self::complete`]).
    pub(super) fn fetch(&mut self, pc: Pos) -> Result<Option<(Pos, Line, Pos)>, GcodeError> {
        if let Some(mut at) = self.scan {
            if pc.file == 0 && pc.offset == at.offset && pc.line == at.line {
                // At the scan's front: this read is the scan's too.
                if let Ok(Next::Line(offset, l)) = next_line(&mut self.main, &mut at, u64::MAX) {
                    let (pos, next) = at.places(0, offset, l.line);
                    self.scan = Some(at);
                    if let Some(o) = &l.oword {
                        self.owords.push(OEntry {
                            pos,
                            next,
                            kind: o.kind,
                            name: o.name.clone(),
                            col: o.col,
                        });
                        self.complete()?;
                    }
                    return Ok(Some((pos, l, next)));
                }
            }
            self.complete()?;
        }
        let mut pc = pc;
        loop {
            let (src, end) = match pc.file {
                0 => (&mut self.main, self.main_end),
                k => {
                    let f = &mut self.files[k - 1];
                    (&mut f.source, f.end)
                }
            };
            let mut at = Reading {
                offset: pc.offset,
                line: pc.line,
                seen_content: pc != self.origin,
            };
            match next_line(src, &mut at, end)? {
                Next::Line(offset, l) => {
                    let (pos, next) = at.places(pc.file, offset, l.line);
                    return Ok(Some((pos, l, next)));
                }
                Next::End if pc.file < self.files.len() => pc = self.files[pc.file].start,
                Next::End => return Ok(None),
            }
        }
    }

    /// The O-word line at `pos` (index into [`Self::owords`]).
    pub(super) fn oword_at(&self, pos: Pos) -> Option<usize> {
        self.owords.binary_search_by(|e| e.pos.cmp(&pos)).ok()
    }

    /// The O-word line `i`, read again (for the values it holds).
    ///
    /// # Errors
    /// As [`Self::fetch`].
    pub(super) fn oword_line(&mut self, i: usize) -> Result<Line, GcodeError> {
        let pos = self.owords[i].pos;
        match self.fetch(pos)? {
            Some((at, l, _)) if at == pos => Ok(l),
            _ => Err(GcodeError::invalid(
                pos.line,
                1,
                "the program changed while it was running",
            )),
        }
    }

    /// The partner of O-word line `i` (see [`pair`]).
    ///
    /// # Errors
    /// A line without one.
    pub(super) fn partner(&self, i: usize) -> Result<usize, GcodeError> {
        self.partner[i].ok_or_else(|| {
            let e = &self.owords[i];
            GcodeError::invalid(e.pos.line, e.col, "O-word without its matching end")
        })
    }

    /// Scans the rest of the main program (its O-word lines and the syntax error that ends
    /// it), reads the subroutine files it calls and pairs the O-words. Nothing once done.
    ///
    /// # Errors
    /// A subroutine file that cannot be read, lacks its definition or has a syntax error.
    pub(super) fn complete(&mut self) -> Result<(), GcodeError> {
        let Some(mut at) = self.scan.take() else {
            return Ok(());
        };
        loop {
            match next_line(&mut self.main, &mut at, u64::MAX) {
                Ok(Next::Line(offset, l)) => {
                    if let Some(o) = l.oword {
                        let (pos, next) = at.places(0, offset, l.line);
                        self.owords.push(OEntry {
                            pos,
                            next,
                            kind: o.kind,
                            name: o.name,
                            col: o.col,
                        });
                    }
                }
                Ok(Next::End) => break,
                Err(e) => {
                    self.tail_error = Some(e);
                    break;
                }
            }
        }
        self.main_end = at.offset;
        let dirs = std::mem::take(&mut self.searched);
        let loaded = super::sub_files::load(&mut self.owords, &mut self.files, &dirs);
        self.searched = dirs;
        loaded?;
        self.partner = vec![None; self.owords.len()];
        self.structure_error = pair(self).err();
        Ok(())
    }
}

fn key(name: &OName) -> String {
    name.to_string()
}

/// The key of a subroutine in [`Program::subs`].
pub(super) fn sub_key(name: &OName) -> String {
    key(name)
}

/// Pairs O-word statements by name and nesting: `if`/`elseif`/`else` → next branch,
/// `while`/`do`/`repeat` → their end, ends → their head, `break`/`continue` → their loop's
/// head, `sub` → `endsub`. On error see [`StructureError`].
fn pair(prog: &mut Program) -> Result<(), StructureError> {
    let mut stack: Vec<usize> = Vec::new();
    let ow = std::mem::take(&mut prog.owords);
    let result = pair_entries(prog, &ow, &mut stack);
    prog.owords = ow;
    result?;
    if let Some(&j) = stack.first() {
        // An open structure: the syntax error that cut the program short explains it best.
        let o = &prog.owords[stack[stack.len() - 1]];
        let first = prog.owords[j].pos;
        let (index, e) = match prog.tail_error.clone() {
            Some(e) => (None, e),
            None => {
                let msg = format!("{} {} is never closed", o.name, kw(o.kind));
                (Some(o.pos), GcodeError::invalid(o.pos.line, o.col, msg))
            }
        };
        return Err(Box::new((first, index, e)));
    }
    Ok(())
}

/// [`pair`] over the O-word lines `ow`, leaving the structures still open on `stack`.
fn pair_entries(
    prog: &mut Program,
    ow: &[OEntry],
    stack: &mut Vec<usize>,
) -> Result<(), StructureError> {
    for (i, o) in ow.iter().enumerate() {
        let first_open = ow[stack.first().copied().unwrap_or(i).min(i)].pos;
        let fail = |msg: String| {
            let e = GcodeError::invalid(o.pos.line, o.col, msg);
            Err(Box::new((first_open, Some(o.pos), e)))
        };
        let open = stack.last().map(|&j| (j, &ow[j]));
        let same = |j: usize| ow[j].name == o.name;
        match o.kind {
            OKind::Sub => {
                if stack.iter().any(|&j| ow[j].kind == OKind::Sub) {
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
                    same(j) && matches!(ow[j].kind, OKind::While | OKind::Do | OKind::Repeat)
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
    Ok(())
}

/// The keyword of an O-word statement, as written.
pub(super) fn kw(k: OKind) -> &'static str {
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

#[cfg(test)]
mod tests {
    use super::super::{run_program, InterpConfig, ProgramRun, RunEvent};

    /// With a subroutine folder the whole text is scanned before the run; without, as it runs
    /// until the first O-word or `M98`. Both must give the same moves and errors.
    #[test]
    fn a_program_scanned_as_it_runs_behaves_as_one_scanned_first() {
        let eager = InterpConfig {
            subroutine_dirs: vec![std::path::PathBuf::from("/no/such/folder")],
            ..InterpConfig::default()
        };
        let programs = [
            "G1 X1 F100\nM98 P100 L2\nM30\nO100\nG1 Y1\nM99\n",
            "G1 X1 F100\nG1 X[1\no1 repeat [2]\nG1 Y1\no1 endrepeat\n",
            "G1 X1 F100\n\no1 while [1]\nG1 X2\n",
            "G0 X1\no<s> call [3]\nM2\no<s> sub\nG1 X#1 F100\no<s> endsub\n",
            "\n%\nG0 X1\n%\nG0 X2\n",
            "G0 X1\nG0 X2\no1 endwhile\n",
            "G0 X1\nM2\nG1 X[\n",
            "G0 X1\no1 if [1]\nG0 X3\no1 elseif [1]\nG0 X4\no1 else\nG0 X5\no1 endif\nG0 X6\nM2\n",
        ];
        for p in programs {
            let lazy = run_program(p, &InterpConfig::default()).map_err(|e| e.to_string());
            let first = run_program(p, &eager).map_err(|e| e.to_string());
            assert_eq!(lazy, first, "{p:?}");
        }
    }

    #[test]
    fn a_source_is_read_from_its_position_with_line_numbers_from_there() {
        let bytes = b"\xEF\xBB\xBFG0 X1\nG0 X[\n".to_vec();
        let mut cursor = std::io::Cursor::new(bytes);
        cursor.set_position(3);
        let mut run = ProgramRun::from_source(Box::new(cursor), &InterpConfig::default()).unwrap();
        let mut moves = Vec::new();
        let err = run.resume(&mut moves).unwrap_err();
        assert_eq!(moves.len(), 1);
        assert_eq!((moves[0].line, err.line), (1, 2));
        assert!(matches!(run.resume(&mut moves), Err(e) if e == err));
        let mut loop_run = ProgramRun::new(
            "o1 repeat [3]\nG1 X1 F100\nG1 X0\no1 endrepeat\nM2",
            &InterpConfig::default(),
        )
        .unwrap();
        let mut looped = Vec::new();
        assert_eq!(loop_run.resume(&mut looped).unwrap(), RunEvent::Ended);
        let lines: Vec<usize> = looped.iter().map(|m| m.line).collect();
        assert_eq!(lines, [2, 3, 2, 3, 2, 3, 5]);
    }
}
