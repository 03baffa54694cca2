//! Subroutine files: `o<name> call` of a subroutine the program does not define runs
//! `o<name> sub … o<name> endsub` from the file `<name>.ngc` in the first of
//! [`InterpConfig::subroutine_dirs`](super::InterpConfig::subroutine_dirs) that has one
//! (LinuxCNC's subroutine path). Files are scanned before the program runs, for the calls of
//! the program and of the files read: every line is parsed (a syntax error anywhere in the
//! file is an error), only the O-word lines of the definition are kept, after the program's
//! (see `program`); the file stays open and execution reads the definition's lines
//! from it. An error inside a file names that file and the line in it ([`GcodeError::file`]).

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use super::source::{next_line, LineSource, Next, OEntry, Pos, Reading};
use crate::syntax::{CallSite, GcodeError, OKind, OName};

/// A subroutine file: where its definition is (`start` its `sub` line, `end` the offset
/// after its `endsub` line).
#[derive(Debug)]
pub(super) struct SubFile {
    /// The file as found (folder joined with `<name>.ngc`).
    pub path: PathBuf,
    /// The open file.
    pub source: LineSource,
    pub start: Pos,
    pub end: u64,
}

fn named(e: &OEntry, kind: OKind) -> Option<&str> {
    match &e.name {
        OName::Named(n) if e.kind == kind => Some(n.as_str()),
        _ => None,
    }
}

/// Appends to `owords` the O-word lines of the definitions of the named subroutines called
/// but not defined, read from the folders `dirs`, and to `files` the files. A file that
/// cannot be read, or that lacks the definition, is an error at the call; a syntax error in a
/// file is an error in that file, called from the call.
pub(super) fn load(
    owords: &mut Vec<OEntry>,
    files: &mut Vec<SubFile>,
    dirs: &[PathBuf],
) -> Result<(), GcodeError> {
    if dirs.is_empty() {
        return Ok(());
    }
    let mut tried: HashSet<String> = HashSet::new();
    let mut scanned = 0;
    while scanned < owords.len() {
        let defined: HashSet<&str> = owords.iter().filter_map(|e| named(e, OKind::Sub)).collect();
        let mut wanted = Vec::new();
        for e in &owords[scanned..] {
            if let Some(name) = named(e, OKind::Call) {
                if !defined.contains(name) && tried.insert(name.to_string()) {
                    wanted.push((name.to_string(), e.pos, e.col));
                }
            }
        }
        scanned = owords.len();
        for (name, at, col) in wanted {
            let Some(path) = dirs
                .iter()
                .map(|d| d.join(format!("{name}.ngc")))
                .find(|p| p.is_file())
            else {
                continue;
            };
            let caller = at.file.checked_sub(1).map(|k| files[k].path.clone());
            let call = Call {
                name: &name,
                caller,
                line: at.line,
                col,
            };
            let file = read_file(&path, files.len() + 1, &call, owords)?;
            files.push(file);
        }
    }
    Ok(())
}

/// The call that made a file be read.
struct Call<'a> {
    name: &'a str,
    caller: Option<PathBuf>,
    line: usize,
    col: usize,
}

impl Call<'_> {
    fn error(&self, msg: String) -> GcodeError {
        GcodeError {
            file: self.caller.clone(),
            ..GcodeError::invalid(self.line, self.col, msg)
        }
    }
}

/// Scans subroutine file `path` (file number `k`), appends its definition's O-word lines to
/// `owords`.
fn read_file(
    path: &Path,
    k: usize,
    call: &Call<'_>,
    owords: &mut Vec<OEntry>,
) -> Result<SubFile, GcodeError> {
    let name = call.name;
    let cannot_read = |e: std::io::Error| {
        call.error(format!(
            "o<{name}> call: cannot read {}: {e}",
            path.display()
        ))
    };
    let file = std::fs::File::open(path).map_err(cannot_read)?;
    let mut source = LineSource::new(Box::new(file)).map_err(cannot_read)?;
    let mut at = Reading {
        offset: 0,
        line: 1,
        seen_content: false,
    };
    let mut found = Vec::new();
    loop {
        let next = next_line(&mut source, &mut at, u64::MAX).map_err(|e| GcodeError {
            file: Some(path.to_path_buf()),
            calls: vec![CallSite {
                file: call.caller.clone(),
                line: call.line,
            }],
            ..e
        })?;
        let Next::Line(offset, l) = next else {
            break;
        };
        if let Some(o) = l.oword {
            let (pos, after) = at.places(k, offset, l.line);
            found.push(OEntry {
                pos,
                next: after,
                kind: o.kind,
                name: o.name,
                col: o.col,
            });
        }
    }
    let start = found
        .iter()
        .position(|e| named(e, OKind::Sub) == Some(name));
    let stop = found
        .iter()
        .position(|e| named(e, OKind::EndSub) == Some(name));
    match (start, stop) {
        (Some(a), Some(b)) if a < b => {
            let (start, end) = (found[a].pos, found[b].next.offset);
            owords.extend(found.drain(a..=b));
            Ok(SubFile {
                path: path.to_path_buf(),
                source,
                start,
                end,
            })
        }
        _ => Err(call.error(format!(
            "o<{name}> call: {} has no o<{name}> sub … endsub",
            path.display()
        ))),
    }
}
