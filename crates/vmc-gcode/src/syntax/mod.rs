//! G-code syntax: text → lines of words whose values may be expressions. Syntax only; what the
//! words mean, and the values of parameters and expressions, are the business of the
//! interpreter (`interp`), which builds on this module.
//!
//! Dialect: the RS274/NGC of LinuxCNC that a mill post-processor emits (axes X Y Z and the
//! rotary A B C).
//! - One block per line. Letters are case-insensitive; spaces and tabs may appear anywhere
//!   outside comments, even inside numbers (`X 1 2 . 5` is `X12.5`), as LinuxCNC allows.
//! - Comments: `( … )` (not nested) and `;` to the end of the line; `(MSG, text)` is kept as a
//!   message.
//! - `%` alone on the first non-blank line opens the program; the next `%` line ends it and the
//!   rest of the file is ignored (LinuxCNC's rule). A `%` line elsewhere also ends the program.
//! - `N` line numbers (also fractional, `N4567.789`) must come first on the line; their value is
//!   ignored (errors report the physical 1-based line instead). A leading `/` marks the line
//!   for block delete.
//! - Values ([`Expr`]): literals (`+`/`-`, digits, at most one `.`, at least one digit),
//!   parameters `#5`, `##1`, `#[…]`, `#<local>`, `#<_global>`, bracketed expressions with
//!   `** * / MOD + - EQ NE GT GE LT LE AND OR XOR`, unary minus, and the functions `ABS ACOS
//!   ASIN COS EXP FIX FUP LN ROUND SIN SQRT TAN`, `ATAN[y]/[x]`, `EXISTS[#<name>]`.
//! - Parameter settings `#… = value` anywhere on a line ([`Assign`]).
//! - O-word statements `o100 sub|endsub|call|return|if|elseif|else|endif|while|endwhile|do|
//!   repeat|endrepeat|break|continue [value]…` on a line of their own ([`OWord`]).
//! - Columns are 1-based character (not byte) positions in the line.
//!
//! Rejected with [`GcodeErrorKind::Unsupported`] (valid LinuxCNC we do not implement):
//! polar words `@ ^`, axis words `U V W`, the `D` word, O-words with a computed
//! number, and the `(abort, …)` comment. `O100` alone starts a Fanuc-style subroutine. Everything else that
//! cannot be read is [`GcodeErrorKind::Invalid`].
//!
//! G and M numbers are kept exactly as integers ×10 ([`Word::code_x10`]: `G91.1` → 911), so
//! comparisons never depend on float rounding.

mod error;
mod expr;
mod lexer;
mod value;

pub use error::{CallSite, ErrorIn, GcodeError, GcodeErrorKind};
pub use expr::{Assign, BinOp, Expr, ExprWord, Func, Line, OKind, OName, OWord, Param};
pub use lexer::parse_line;
pub use value::MAX_OPERATIONS;

/// One word: a letter and its number, e.g. `X-12.5` or `G91.1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Word {
    /// Upper-case letter.
    pub letter: char,
    /// The number as written (in program units for lengths).
    pub value: f64,
    /// 1-based character column of the letter.
    pub col: usize,
}

impl Word {
    /// The value ×10 as an exact integer (`G91.1` → 911, `M30` → 300), or `None` if the value
    /// is negative or has more than one decimal digit. Used for G and M numbers.
    pub fn code_x10(&self) -> Option<u32> {
        let scaled = self.value * 10.0;
        let rounded = scaled.round();
        // 1e-6 of a tenth: far below the last written digit of any sane code, far above the
        // rounding error of `91.1 * 10`.
        if self.value < 0.0 || (scaled - rounded).abs() > 1e-6 || rounded > f64::from(u32::MAX) {
            return None;
        }
        Some(rounded as u32)
    }

    /// Display form for messages: `G91.1`, `M3`, `X-1.5`.
    pub fn display(&self) -> String {
        match (self.letter, self.code_x10()) {
            ('G' | 'M', Some(c)) if c % 10 == 0 => format!("{}{}", self.letter, c / 10),
            ('G' | 'M', Some(c)) => format!("{}{}.{}", self.letter, c / 10, c % 10),
            _ => format!("{}{}", self.letter, self.value),
        }
    }
}

/// One block of G-code with its values evaluated: its words in source order (N word excluded).
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// 1-based physical line in the source text.
    pub line: usize,
    /// The `N` number if one was written (informational only).
    pub line_number: Option<f64>,
    /// Words in source order. No letter other than G and M occurs twice.
    pub words: Vec<Word>,
    /// Column of the first word (1 if the block only had an N word).
    pub first_col: usize,
}

impl Block {
    /// The block of a line whose values are all literals (`None` if one is not).
    pub fn from_literal_line(line: &Line) -> Option<Block> {
        let words = line
            .words
            .iter()
            .map(|w| {
                w.value.literal().map(|value| Word {
                    letter: w.letter,
                    value,
                    col: w.col,
                })
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Block {
            line: line.line,
            line_number: line.line_number,
            words,
            first_col: line.first_col,
        })
    }

    /// The word with this (upper-case) letter, if present. Not meaningful for G and M.
    pub fn get(&self, letter: char) -> Option<&Word> {
        self.words.iter().find(|w| w.letter == letter)
    }
}

/// Splits a program into lines, honouring `%` delimiters. Lines that do nothing (blank,
/// comment-only, N-only) produce no [`Line`]. Stops at the first error.
pub fn parse_program(src: &str) -> Lines<'_> {
    Lines {
        lines: src.lines().enumerate(),
        seen_content: false,
        done: false,
    }
}

/// Iterator over the lines of a program; see [`parse_program`].
#[derive(Debug)]
pub struct Lines<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    seen_content: bool,
    done: bool,
}

impl Iterator for Lines<'_> {
    type Item = Result<Line, GcodeError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        for (idx, text) in self.lines.by_ref() {
            let trimmed = text.trim();
            if trimmed.is_empty() {
                continue;
            }
            if trimmed == "%" {
                if self.seen_content {
                    // Closing `%`: LinuxCNC ignores everything after it.
                    self.done = true;
                    return None;
                }
                self.seen_content = true;
                continue;
            }
            self.seen_content = true;
            match parse_line(idx + 1, text) {
                Ok(Some(block)) => return Some(Ok(block)),
                Ok(None) => continue,
                Err(e) => {
                    self.done = true;
                    return Some(Err(e));
                }
            }
        }
        self.done = true;
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blocks(src: &str) -> Vec<Line> {
        parse_program(src)
            .collect::<Result<Vec<_>, _>>()
            .expect("program parses")
    }

    #[test]
    fn g91_1_is_exactly_911() {
        let b = blocks("g91.1");
        let w = Word {
            letter: 'G',
            value: b[0].words[0].value.literal().unwrap(),
            col: 1,
        };
        assert_eq!(w.code_x10(), Some(911));
        assert_eq!(w.display(), "G91.1");
    }

    #[test]
    fn percent_lines_delimit_the_program() {
        let b = blocks("\n%\nG0 X1\n%\nthis is ignored ###\n");
        assert_eq!(b.len(), 1);
        assert_eq!(b[0].line, 3);
    }

    #[test]
    fn comment_only_and_blank_lines_give_no_block() {
        let b = blocks("(hello)\n\n   ; nothing\nN10\nG1 X1\n");
        assert_eq!(b.len(), 1);
        assert_eq!(b[0].line, 5);
    }

    #[test]
    fn parsing_stops_at_the_first_error() {
        let results: Vec<_> = parse_program("G0 X1\nG0 X[1\nG0 X2\n").collect();
        assert_eq!(results.len(), 2);
        let err = results[1].clone().unwrap_err();
        assert_eq!(
            (err.line, err.col, err.kind),
            (2, 5, GcodeErrorKind::Invalid)
        );
    }

    #[test]
    fn error_display_names_line_and_column() {
        let e = GcodeError::invalid(12, 5, "G2 needs I/J/K or R");
        assert_eq!(e.to_string(), "line 12, column 5: G2 needs I/J/K or R");
    }

    #[test]
    fn code_x10_rejects_two_decimals_and_negatives() {
        let w = |v| Word {
            letter: 'G',
            value: v,
            col: 1,
        };
        assert_eq!(w(1.25).code_x10(), None);
        assert_eq!(w(-1.0).code_x10(), None);
        assert_eq!(w(59.3).code_x10(), Some(593));
    }
}
