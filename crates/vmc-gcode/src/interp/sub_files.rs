//! Subroutine files: `o<name> call` of a subroutine the program does not define runs
//! `o<name> sub … o<name> endsub` from the file `<name>.ngc` in the first of
//! [`InterpConfig::subroutine_dirs`] that has one (LinuxCNC's subroutine path). Files are read
//! before the program runs, for the calls of the program and of the files read; only the
//! definition's lines are taken. An error inside a file names the line in that file.

use std::collections::HashSet;

use super::InterpConfig;
use crate::syntax::{GcodeError, Line, OKind, OName};

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
/// from the subroutine folders. A file that cannot be read or parsed, or that lacks the
/// definition, is an error at the call.
pub(super) fn load(lines: &mut Vec<Line>, cfg: &InterpConfig) -> Result<(), GcodeError> {
    if cfg.subroutine_dirs.is_empty() {
        return Ok(());
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
        for l in &lines[scanned..end] {
            if let Some(name) = named(l, OKind::Call) {
                if !defined.contains(name) && tried.insert(name.to_string()) {
                    let col = l.oword.as_ref().map_or(1, |o| o.col);
                    wanted.push((name.to_string(), l.line, col));
                }
            }
        }
        scanned = end;
        for (name, line, col) in wanted {
            let Some(path) = cfg
                .subroutine_dirs
                .iter()
                .map(|d| d.join(format!("{name}.ngc")))
                .find(|p| p.is_file())
            else {
                continue;
            };
            let err = |msg: String| GcodeError::invalid(line, col, msg);
            let bytes = std::fs::read(&path).map_err(|e| {
                err(format!(
                    "o<{name}> call: cannot read {}: {e}",
                    path.display()
                ))
            })?;
            let text = String::from_utf8_lossy(&bytes);
            let mut file_lines = Vec::new();
            for l in crate::syntax::parse_program(&text) {
                let l = l.map_err(|e| err(format!("o<{name}> call: {}: {e}", path.display())))?;
                file_lines.push(l);
            }
            let start = file_lines
                .iter()
                .position(|l| named(l, OKind::Sub) == Some(&name));
            let stop = file_lines
                .iter()
                .position(|l| named(l, OKind::EndSub) == Some(&name));
            match (start, stop) {
                (Some(a), Some(b)) if a < b => lines.extend(file_lines.drain(a..=b)),
                _ => {
                    return Err(err(format!(
                        "o<{name}> call: {} has no o<{name}> sub … endsub",
                        path.display()
                    )))
                }
            }
        }
    }
    Ok(())
}
