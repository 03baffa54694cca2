//! Subroutine files: `o<name> call` of a subroutine the program does not define runs
//! `o<name> sub … o<name> endsub` from the file `<name>.ngc` in the first of
//! [`InterpConfig::subroutine_dirs`] that has one (LinuxCNC's subroutine path). Files are read
//! before the program runs, for the calls of the program and of the files read; only the
//! definition's lines are taken, appended after the program's. An error inside a file names
//! that file and the line in it ([`GcodeError::file`]).

use std::collections::HashSet;
use std::ops::Range;
use std::path::PathBuf;

use super::InterpConfig;
use crate::syntax::{CallSite, GcodeError, Line, OKind, OName};

/// The lines a subroutine file contributed: their indices in the program's lines.
#[derive(Debug, Clone)]
pub(super) struct SubFile {
    /// The file as found (folder joined with `<name>.ngc`).
    pub path: PathBuf,
    /// Indices of its lines among the program's lines.
    pub lines: Range<usize>,
}

/// The file of line index `i`: `None` for the main program, else the subroutine file.
pub(super) fn file_of(files: &[SubFile], i: usize) -> Option<&PathBuf> {
    files.iter().find(|f| f.lines.contains(&i)).map(|f| &f.path)
}

fn named(l: &Line, kind: OKind) -> Option<&str> {
    match &l.oword {
        Some(o) if o.kind == kind => match &o.name {
            OName::Named(n) => Some(n.as_str()),
            OName::Number(_) | OName::Computed(_) => None,
        },
        _ => None,
    }
}

/// Appends to `lines` the definitions of the named subroutines called but not defined, read
/// from the subroutine folders; returns where each file's lines went. A file that cannot be
/// read, or that lacks the definition, is an error at the call; a syntax error in a file is
/// an error in that file, called from the call.
pub(super) fn load(lines: &mut Vec<Line>, cfg: &InterpConfig) -> Result<Vec<SubFile>, GcodeError> {
    let mut files: Vec<SubFile> = Vec::new();
    if cfg.subroutine_dirs.is_empty() {
        return Ok(files);
    }
    let mut tried: HashSet<String> = HashSet::new();
    let mut scanned = 0;
    while scanned < lines.len() {
        let defined: HashSet<String> = lines
            .iter()
            .filter_map(|l| named(l, OKind::Sub).map(str::to_string))
            .collect();
        let end = lines.len();
        let mut wanted = Vec::new();
        for (i, l) in lines.iter().enumerate().take(end).skip(scanned) {
            if let Some(name) = named(l, OKind::Call) {
                if !defined.contains(name) && tried.insert(name.to_string()) {
                    let col = l.oword.as_ref().map_or(1, |o| o.col);
                    wanted.push((name.to_string(), i, l.line, col));
                }
            }
        }
        scanned = end;
        for (name, index, line, col) in wanted {
            let Some(path) = cfg
                .subroutine_dirs
                .iter()
                .map(|d| d.join(format!("{name}.ngc")))
                .find(|p| p.is_file())
            else {
                continue;
            };
            let caller = file_of(&files, index).cloned();
            let err = |msg: String| GcodeError {
                file: caller.clone(),
                ..GcodeError::invalid(line, col, msg)
            };
            let bytes = std::fs::read(&path).map_err(|e| {
                err(format!(
                    "o<{name}> call: cannot read {}: {e}",
                    path.display()
                ))
            })?;
            let text = String::from_utf8_lossy(&bytes);
            let mut file_lines = Vec::new();
            for l in crate::syntax::parse_program(&text) {
                let l = l.map_err(|e| GcodeError {
                    file: Some(path.clone()),
                    calls: vec![CallSite {
                        file: caller.clone(),
                        line,
                    }],
                    ..e
                })?;
                file_lines.push(l);
            }
            let start = file_lines
                .iter()
                .position(|l| named(l, OKind::Sub) == Some(&name));
            let stop = file_lines
                .iter()
                .position(|l| named(l, OKind::EndSub) == Some(&name));
            match (start, stop) {
                (Some(a), Some(b)) if a < b => {
                    let first = lines.len();
                    lines.extend(file_lines.drain(a..=b));
                    files.push(SubFile {
                        path,
                        lines: first..lines.len(),
                    });
                }
                _ => {
                    return Err(err(format!(
                        "o<{name}> call: {} has no o<{name}> sub … endsub",
                        path.display()
                    )))
                }
            }
        }
    }
    Ok(files)
}
