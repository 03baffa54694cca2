//! The error of a rejected program: what is wrong and where — the line and column, the
//! subroutine file when the line is in one, and the calls that led there.

use std::fmt;
use std::path::PathBuf;

/// Why a program was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GcodeErrorKind {
    /// Valid RS274/NGC (LinuxCNC dialect) that this interpreter deliberately does not implement.
    Unsupported,
    /// Malformed or semantically wrong input (also wrong for LinuxCNC).
    Invalid,
}

/// One call on the way to an error: the line of an `o… call` or `M98` block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CallSite {
    /// The subroutine file the calling line is in; `None`: the main program.
    pub file: Option<PathBuf>,
    /// 1-based line of the call in that file.
    pub line: usize,
}

/// A rejected program: where and why.
///
/// Display of an error in the main program (the text given to the interpreter, whose file
/// name only the caller knows): `line 12, column 5: G2 needs I/J/K or R`. Display of an error
/// in a subroutine file: `/subs/probe.ngc: line 3, column 5: … (called from line 12)`, the
/// calls innermost first (`(called from /subs/outer.ngc line 4, from line 12)`).
/// [`GcodeError::display_in`] names the main program too.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}", self.display_in(""))]
pub struct GcodeError {
    /// 1-based physical line in the source text (of `file` when it is set).
    pub line: usize,
    /// 1-based character column of the offending word (or of the block when no single word is
    /// to blame).
    pub col: usize,
    /// Unsupported (outside our subset) or invalid (wrong).
    pub kind: GcodeErrorKind,
    /// Human-readable reason, naming the word.
    pub msg: String,
    /// The subroutine file (read for `o<name> call` from a subroutine folder) that holds the
    /// line in error; `None`: the main program.
    pub file: Option<PathBuf>,
    /// The subroutine calls active when the error happened, innermost first (the call of the
    /// subroutine the error is in, then the call of that one's caller, …, last a line of the
    /// main program). Empty for an error outside any call. Shown by `Display` only for an
    /// error in a subroutine file, so that the main program's messages keep their form.
    pub calls: Vec<CallSite>,
}

impl GcodeError {
    /// An error for input that is valid RS274/NGC but outside the implemented subset.
    pub fn unsupported(line: usize, col: usize, msg: impl Into<String>) -> Self {
        Self {
            line,
            col: col.max(1),
            kind: GcodeErrorKind::Unsupported,
            msg: msg.into(),
            file: None,
            calls: Vec::new(),
        }
    }

    /// An error for malformed or semantically wrong input.
    pub fn invalid(line: usize, col: usize, msg: impl Into<String>) -> Self {
        Self {
            line: line.max(1),
            col: col.max(1),
            kind: GcodeErrorKind::Invalid,
            msg: msg.into(),
            file: None,
            calls: Vec::new(),
        }
    }

    /// True if the program is valid RS274/NGC that we do not implement.
    pub fn is_unsupported(&self) -> bool {
        self.kind == GcodeErrorKind::Unsupported
    }

    /// The message with the main program named `program` (a file name, as the caller knows
    /// it): `prog.ngc: line 12, column 5: …` for an error in the main program,
    /// `/subs/probe.ngc: line 3, column 5: … (called from prog.ngc line 12)` for one in a
    /// subroutine file. An empty `program` gives the plain [`Display`](fmt::Display) form.
    pub fn display_in<'a>(&'a self, program: &'a str) -> ErrorIn<'a> {
        ErrorIn { err: self, program }
    }
}

/// A [`GcodeError`] displayed with the name of its main program (see
/// [`GcodeError::display_in`]).
#[derive(Debug, Clone, Copy)]
pub struct ErrorIn<'a> {
    err: &'a GcodeError,
    program: &'a str,
}

impl fmt::Display for ErrorIn<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = self.err;
        let file = |f: &mut fmt::Formatter<'_>, file: &Option<PathBuf>, sep: &str| match file {
            Some(path) => write!(f, "{}{sep}", path.display()),
            None if !self.program.is_empty() => write!(f, "{}{sep}", self.program),
            None => Ok(()),
        };
        file(f, &e.file, ": ")?;
        write!(f, "line {}, column {}: {}", e.line, e.col, e.msg)?;
        if e.file.is_none() || e.calls.is_empty() {
            return Ok(());
        }
        for (i, call) in e.calls.iter().enumerate() {
            f.write_str(if i == 0 { " (called from " } else { ", from " })?;
            file(f, &call.file, " ")?;
            write!(f, "line {}", call.line)?;
        }
        f.write_str(")")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn in_sub() -> GcodeError {
        GcodeError {
            file: Some(PathBuf::from("subs/probe.ngc")),
            calls: vec![
                CallSite {
                    file: Some(PathBuf::from("subs/outer.ngc")),
                    line: 4,
                },
                CallSite {
                    file: None,
                    line: 12,
                },
            ],
            ..GcodeError::invalid(3, 5, "G2 needs I/J/K or R")
        }
    }

    #[test]
    fn an_error_in_the_main_program_reads_as_line_and_column() {
        let e = GcodeError::invalid(12, 5, "G2 needs I/J/K or R");
        assert_eq!(e.to_string(), "line 12, column 5: G2 needs I/J/K or R");
        assert_eq!(
            e.display_in("prog.ngc").to_string(),
            "prog.ngc: line 12, column 5: G2 needs I/J/K or R"
        );
        // Calls are data, not shown, for a line of the main program.
        let called = GcodeError {
            calls: vec![CallSite {
                file: None,
                line: 20,
            }],
            ..e
        };
        assert_eq!(called.to_string(), "line 12, column 5: G2 needs I/J/K or R");
    }

    #[test]
    fn an_error_in_a_subroutine_file_names_the_file_and_the_calls() {
        let e = in_sub();
        assert_eq!(
            e.to_string(),
            "subs/probe.ngc: line 3, column 5: G2 needs I/J/K or R \
             (called from subs/outer.ngc line 4, from line 12)"
        );
        assert_eq!(
            e.display_in("prog.ngc").to_string(),
            "subs/probe.ngc: line 3, column 5: G2 needs I/J/K or R \
             (called from subs/outer.ngc line 4, from prog.ngc line 12)"
        );
    }
}
