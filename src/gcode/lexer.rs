//! Line lexer: one line of text → one [`Block`] of words (see the parent module for the
//! dialect). Works on characters so that columns are character positions.

use super::{Block, GcodeError, Word};

/// Letters whose words the interpreter understands.
const SUPPORTED_LETTERS: &str = "FGIJKMNPRSTXYZ";

/// LinuxCNC's unary functions; a letter followed by one of these starts an expression.
const UNARY_FUNCTIONS: [&str; 13] = [
    "ABS", "ACOS", "ASIN", "ATAN", "COS", "EXISTS", "EXP", "FIX", "FUP", "LN", "ROUND", "SIN",
    "SQRT",
];

/// Parses one line (1-based `line`) into a block. `Ok(None)` for a line without words (blank,
/// comments only, or a lone N word).
pub fn parse_line(line: usize, text: &str) -> Result<Option<Block>, GcodeError> {
    let chars: Vec<char> = text.chars().collect();
    let mut lx = Lexer {
        chars: &chars,
        pos: 0,
        line,
    };
    lx.skip_blanks();
    if lx.peek() == Some('/') {
        return Err(lx.unsupported(lx.pos, "block delete '/' is not supported"));
    }
    let mut words: Vec<Word> = Vec::new();
    let mut line_number = None;
    while let Some(c) = lx.skip_blanks_and_peek() {
        let start = lx.pos;
        match c {
            '(' => lx.comment()?,
            ';' => break,
            '#' => return Err(lx.unsupported(start, "parameter '#' is not supported")),
            '[' => return Err(lx.unsupported(start, "expression '[...]' is not supported")),
            '@' | '^' => {
                return Err(
                    lx.unsupported(start, format!("polar coordinate '{c}' is not supported"))
                )
            }
            c if c.is_ascii_alphabetic() => {
                let word = lx.word()?;
                if word.letter == 'N' {
                    if !words.is_empty() || line_number.is_some() {
                        return Err(lx.invalid(start, "N word must come first on the line"));
                    }
                    line_number = Some(word.value);
                    continue;
                }
                if !matches!(word.letter, 'G' | 'M')
                    && words.iter().any(|w| w.letter == word.letter)
                {
                    return Err(lx.invalid(start, format!("more than one {} word", word.letter)));
                }
                words.push(word);
            }
            other => return Err(lx.invalid(start, format!("unexpected character {other:?}"))),
        }
    }
    let Some(first_col) = words.first().map(|w| w.col) else {
        return Ok(None);
    };
    Ok(Some(Block {
        line,
        line_number,
        words,
        first_col,
    }))
}

/// Cursor over the characters of one line.
struct Lexer<'a> {
    chars: &'a [char],
    pos: usize,
    line: usize,
}

impl Lexer<'_> {
    fn peek(&self) -> Option<char> {
        self.chars.get(self.pos).copied()
    }

    fn skip_blanks(&mut self) {
        while matches!(self.peek(), Some(c) if c.is_whitespace()) {
            self.pos += 1;
        }
    }

    fn skip_blanks_and_peek(&mut self) -> Option<char> {
        self.skip_blanks();
        self.peek()
    }

    fn invalid(&self, pos: usize, msg: impl Into<String>) -> GcodeError {
        GcodeError::invalid(self.line, pos + 1, msg)
    }

    fn unsupported(&self, pos: usize, msg: impl Into<String>) -> GcodeError {
        GcodeError::unsupported(self.line, pos + 1, msg)
    }

    /// Consumes `( … )`. LinuxCNC rejects nested and unclosed comments; `(abort, …)` stops a
    /// LinuxCNC program, which we do not model.
    fn comment(&mut self) -> Result<(), GcodeError> {
        let open = self.pos;
        self.pos += 1;
        let body_start = self.pos;
        loop {
            match self.peek() {
                None => return Err(self.invalid(open, "unclosed comment '('")),
                Some('(') => return Err(self.invalid(self.pos, "nested comment '(' inside '( )'")),
                Some(')') => break,
                Some(_) => self.pos += 1,
            }
        }
        let body: String = self.chars[body_start..self.pos].iter().collect();
        self.pos += 1;
        if body.trim_start().to_ascii_lowercase().starts_with("abort,") {
            return Err(self.unsupported(open, "'(abort, ...)' comment is not supported"));
        }
        Ok(())
    }

    /// Reads a letter and its number. The cursor is on the letter.
    fn word(&mut self) -> Result<Word, GcodeError> {
        let col = self.pos + 1;
        let letter = self.peek().unwrap_or(' ').to_ascii_uppercase();
        let letter_pos = self.pos;
        if !SUPPORTED_LETTERS.contains(letter) {
            return Err(self.unsupported(letter_pos, unsupported_letter_msg(letter)));
        }
        self.pos += 1;
        self.skip_blanks();
        match self.peek() {
            Some('#') => {
                return Err(self.unsupported(
                    letter_pos,
                    format!("{letter} word with a '#' parameter value is not supported"),
                ))
            }
            Some('[') => {
                return Err(self.unsupported(
                    letter_pos,
                    format!("{letter} word with an '[expression]' value is not supported"),
                ))
            }
            Some(c) if c.is_ascii_alphabetic() && self.starts_unary_function() => {
                return Err(self.unsupported(
                    letter_pos,
                    format!("{letter} word with a function value is not supported"),
                ))
            }
            _ => {}
        }
        let value = self
            .number()
            .map_err(|why| self.invalid(letter_pos, format!("{letter} word: {why}")))?;
        Ok(Word { letter, value, col })
    }

    /// True if the letters at the cursor spell a unary function name followed by `[`.
    fn starts_unary_function(&self) -> bool {
        let mut end = self.pos;
        while matches!(self.chars.get(end), Some(c) if c.is_ascii_alphabetic()) {
            end += 1;
        }
        let name: String = self.chars[self.pos..end]
            .iter()
            .collect::<String>()
            .to_ascii_uppercase();
        UNARY_FUNCTIONS.contains(&name.as_str())
    }

    /// Reads `[+-] digits [. digits]` with blanks allowed between the characters.
    fn number(&mut self) -> Result<f64, String> {
        let mut text = String::new();
        if let Some(sign @ ('+' | '-')) = self.peek() {
            text.push(sign);
            self.pos += 1;
            self.skip_blanks();
        }
        let (mut digits, mut dots) = (0usize, 0usize);
        while let Some(c) = self.peek() {
            match c {
                '0'..='9' => digits += 1,
                '.' => dots += 1,
                c if c.is_whitespace() => {
                    self.pos += 1;
                    continue;
                }
                _ => break,
            }
            text.push(c);
            self.pos += 1;
        }
        if digits == 0 {
            return Err("missing number".to_string());
        }
        if dots > 1 {
            return Err(format!("number {text:?} has more than one decimal point"));
        }
        let value: f64 = text
            .parse()
            .map_err(|_| format!("cannot read number {text:?}"))?;
        if !value.is_finite() {
            return Err(format!("number {text:?} is too large"));
        }
        Ok(value)
    }
}

fn unsupported_letter_msg(letter: char) -> String {
    match letter {
        'A' | 'B' | 'C' | 'U' | 'V' | 'W' => {
            format!("{letter} axis word is not supported (3-axis XYZ machine)")
        }
        'O' => "O word (subroutines and control flow) is not supported".to_string(),
        'D' | 'E' | 'H' | 'L' | 'Q' => format!("{letter} word is not supported"),
        _ => format!("unknown word letter '{letter}'"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gcode::GcodeErrorKind;

    fn words(text: &str) -> Vec<(char, f64, usize)> {
        let block = parse_line(1, text)
            .expect("line parses")
            .expect("line has words");
        block
            .words
            .iter()
            .map(|w| (w.letter, w.value, w.col))
            .collect()
    }

    fn err(text: &str) -> GcodeError {
        parse_line(7, text).expect_err("line must be rejected")
    }

    #[test]
    fn lower_case_words_with_spaces_inside_numbers_are_read() {
        assert_eq!(
            words("g1 x 1 2 . 5y-.5"),
            vec![('G', 1.0, 1), ('X', 12.5, 4), ('Y', -0.5, 13)]
        );
    }

    #[test]
    fn number_forms_plus_sign_trailing_dot_and_leading_dot_are_accepted() {
        assert_eq!(
            words("X+1. Y.25 Z-0"),
            vec![('X', 1.0, 1), ('Y', 0.25, 6), ('Z', 0.0, 11)]
        );
    }

    #[test]
    fn comments_are_skipped_and_semicolon_ends_the_line() {
        assert_eq!(
            words("G0 (move fast) X1 ; rest X9"),
            vec![('G', 0.0, 1), ('X', 1.0, 16)]
        );
        assert_eq!(
            words("(msg, hi) G0 X1"),
            vec![('G', 0.0, 11), ('X', 1.0, 14)]
        );
    }

    #[test]
    fn line_number_first_is_kept_apart_from_the_words() {
        let block = parse_line(3, "N4567.789 S1200").unwrap().unwrap();
        assert_eq!(block.line_number, Some(4567.789));
        assert_eq!(block.words.len(), 1);
        assert_eq!(block.first_col, 11);
    }

    #[test]
    fn line_number_after_a_word_is_invalid() {
        let e = err("G0 N10 X1");
        assert_eq!((e.line, e.col, e.kind), (7, 4, GcodeErrorKind::Invalid));
    }

    #[test]
    fn repeated_axis_word_is_invalid_but_repeated_g_is_lexically_fine() {
        assert_eq!(err("X1 X2").kind, GcodeErrorKind::Invalid);
        assert_eq!(words("G0 G90 X1").len(), 3);
    }

    #[test]
    fn missing_or_malformed_numbers_are_invalid_with_the_letter_column() {
        for (text, col) in [
            ("G1 X", 4),
            ("G1 X1.2.3", 4),
            ("Y-", 1),
            ("X.", 1),
            ("Xfoo", 1),
        ] {
            let e = err(text);
            assert_eq!((e.col, e.kind), (col, GcodeErrorKind::Invalid), "{text}");
        }
    }

    #[test]
    fn parameters_expressions_and_o_words_are_unsupported() {
        for (text, col) in [
            ("#1=2", 1),
            ("G1 X#1", 4),
            ("G1 X[1+2]", 4),
            ("G1 Xsin[30]", 4),
            ("o100 sub", 1),
            ("/G0 X1", 1),
            ("G0 A1", 4),
            ("G43 H1", 5),
            ("G1 @1 ^90", 4),
            ("(abort, stop)", 1),
        ] {
            let e = err(text);
            assert_eq!(
                (e.col, e.kind),
                (col, GcodeErrorKind::Unsupported),
                "{text}: {e}"
            );
        }
    }

    #[test]
    fn bad_characters_and_broken_comments_are_invalid() {
        for (text, col) in [
            ("G0 $", 4),
            ("G0 (open", 4),
            ("(a (b) c)", 4),
            ("G0 X1 é", 7),
        ] {
            let e = err(text);
            assert_eq!(
                (e.col, e.kind),
                (col, GcodeErrorKind::Invalid),
                "{text}: {e}"
            );
        }
    }

    #[test]
    fn columns_count_characters_not_bytes() {
        assert_eq!(words("(é) X1"), vec![('X', 1.0, 5)]);
    }

    #[test]
    fn blank_and_comment_lines_have_no_block() {
        assert_eq!(parse_line(1, "   ").unwrap(), None);
        assert_eq!(parse_line(1, "(x) ; y").unwrap(), None);
        assert_eq!(parse_line(1, "N10").unwrap(), None);
    }
}
