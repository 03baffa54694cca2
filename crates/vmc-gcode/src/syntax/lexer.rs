//! Line lexer: one line of text → one [`Line`] (see the parent module for the dialect). Works on
//! characters so that columns are character positions. Values (`X[#1+2]`) are read by
//! `value`.

use super::expr::{Assign, ExprWord, Line, OKind, OName, OWord};
use super::GcodeError;

/// Lines of at most this many bytes are lexed from a buffer on the stack.
const LINE_ON_STACK: usize = 128;

/// Letters whose words the interpreter understands.
const SUPPORTED_LETTERS: &str = "ABCDEFGHIJKLMNPQRSTXYZ";

/// Parses one line (1-based `line`). `Ok(None)` for a line that does nothing (blank, plain
/// comments only, or a lone N word).
pub fn parse_line(line: usize, text: &str) -> Result<Option<Line>, GcodeError> {
    // The characters of a usual line on the stack: one allocation less per line, which is a
    // tenth of the interpreter's time on a long program of short moves.
    let mut stack = ['\0'; LINE_ON_STACK];
    let heap: Vec<char>;
    let chars: &[char] = if text.len() <= LINE_ON_STACK {
        let mut n = 0;
        for (slot, c) in stack.iter_mut().zip(text.chars()) {
            *slot = c;
            n += 1;
        }
        &stack[..n]
    } else {
        heap = text.chars().collect();
        &heap
    };
    let mut lx = Lexer {
        chars,
        pos: 0,
        line,
        operations: 0,
    };
    let mut out = Line {
        line,
        first_col: 1,
        ..Line::default()
    };
    lx.skip_blanks();
    if lx.peek() == Some('/') {
        out.block_delete = true;
        lx.pos += 1;
    }
    let mut first_col = None;
    while let Some(c) = lx.skip_blanks_and_peek() {
        let start = lx.pos;
        match c {
            '(' => {
                if let Some(msg) = lx.comment()? {
                    out.messages.push(msg);
                }
            }
            ';' => break,
            _ if out.oword.is_some() => {
                return Err(lx.invalid(start, "nothing may follow an O-word statement on its line"))
            }
            '#' => {
                let target = lx.param()?;
                if lx.skip_blanks_and_peek() != Some('=') {
                    return Err(
                        lx.invalid(start, "parameter reference outside a word: '=' expected")
                    );
                }
                lx.pos += 1;
                let value = lx.value()?;
                first_col.get_or_insert(start + 1);
                out.assigns.push(Assign {
                    target,
                    value,
                    col: start + 1,
                });
            }
            '@' | '^' => {
                return Err(
                    lx.unsupported(start, format!("polar coordinate '{c}' is not supported"))
                )
            }
            'o' | 'O' => {
                if !out.words.is_empty() || !out.assigns.is_empty() {
                    return Err(lx.invalid(start, "an O-word must begin its line"));
                }
                out.oword = Some(lx.oword()?);
                first_col.get_or_insert(start + 1);
            }
            c if c.is_ascii_alphabetic() => {
                let word = lx.word()?;
                if word.letter == 'N' {
                    if !out.words.is_empty() || !out.assigns.is_empty() || out.line_number.is_some()
                    {
                        return Err(lx.invalid(start, "N word must come first on the line"));
                    }
                    let Some(n) = word.value.literal() else {
                        return Err(lx.invalid(start, "N word must be a plain number"));
                    };
                    out.line_number = Some(n);
                    continue;
                }
                if !matches!(word.letter, 'G' | 'M')
                    && out.words.iter().any(|w| w.letter == word.letter)
                {
                    return Err(lx.invalid(start, format!("more than one {} word", word.letter)));
                }
                first_col.get_or_insert(word.col);
                out.words.push(word);
            }
            other => return Err(lx.invalid(start, format!("unexpected character {other:?}"))),
        }
    }
    out.first_col = first_col.unwrap_or(1);
    Ok((!out.is_empty()).then_some(out))
}

/// Cursor over the characters of one line.
pub(super) struct Lexer<'a> {
    pub(super) chars: &'a [char],
    pub(super) pos: usize,
    pub(super) line: usize,
    /// Binary operations read so far on this line (bounded by `value::MAX_OPERATIONS`).
    pub(super) operations: usize,
}

impl Lexer<'_> {
    pub(super) fn peek(&self) -> Option<char> {
        self.chars.get(self.pos).copied()
    }

    pub(super) fn skip_blanks(&mut self) {
        while matches!(self.peek(), Some(c) if c.is_whitespace()) {
            self.pos += 1;
        }
    }

    pub(super) fn skip_blanks_and_peek(&mut self) -> Option<char> {
        self.skip_blanks();
        self.peek()
    }

    pub(super) fn invalid(&self, pos: usize, msg: impl Into<String>) -> GcodeError {
        GcodeError::invalid(self.line, pos + 1, msg)
    }

    pub(super) fn unsupported(&self, pos: usize, msg: impl Into<String>) -> GcodeError {
        GcodeError::unsupported(self.line, pos + 1, msg)
    }

    /// Consumes `( … )`; returns the text of a `(MSG, …)` comment. LinuxCNC rejects nested and
    /// unclosed comments; `(abort, …)` stops a LinuxCNC program, which we do not model.
    fn comment(&mut self) -> Result<Option<String>, GcodeError> {
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
        let trimmed = body.trim_start();
        let lower = trimmed.to_ascii_lowercase();
        if lower.starts_with("abort,") {
            return Err(self.unsupported(open, "'(abort, ...)' comment is not supported"));
        }
        Ok(lower.starts_with("msg,").then(|| trimmed[4..].to_string()))
    }

    /// Reads a letter and its value. The cursor is on the letter.
    fn word(&mut self) -> Result<ExprWord, GcodeError> {
        let col = self.pos + 1;
        let letter = self.peek().unwrap_or(' ').to_ascii_uppercase();
        let letter_pos = self.pos;
        if !SUPPORTED_LETTERS.contains(letter) {
            return Err(self.unsupported(letter_pos, unsupported_letter_msg(letter)));
        }
        self.pos += 1;
        self.skip_blanks();
        let value = self.value_for(letter, letter_pos)?;
        Ok(ExprWord { letter, value, col })
    }

    /// Reads `o100 keyword [args]` or `o<name> keyword [args]`. The cursor is on the `O`.
    fn oword(&mut self) -> Result<OWord, GcodeError> {
        let start = self.pos;
        self.pos += 1;
        self.skip_blanks();
        let name = if self.peek() == Some('<') {
            OName::Named(self.angle_name(start)?)
        } else {
            match self.number() {
                Ok(n) => OName::Number(n),
                Err(_) if matches!(self.peek(), Some('[' | '#')) => {
                    OName::Computed(Box::new(self.value()?))
                }
                Err(why) => return Err(self.invalid(start, format!("O word: {why}"))),
            }
        };
        self.skip_blanks();
        let kw_start = self.pos;
        // Blanks may split a keyword (`end sub`, `else if`), as everywhere outside comments.
        let mut keyword = String::new();
        while let Some(c) = self.peek() {
            if c.is_ascii_alphabetic() {
                keyword.push(c.to_ascii_lowercase());
            } else if !c.is_whitespace() {
                break;
            }
            self.pos += 1;
        }
        let kind = match keyword.as_str() {
            "sub" => OKind::Sub,
            "endsub" => OKind::EndSub,
            "call" => OKind::Call,
            "return" => OKind::Return,
            "if" => OKind::If,
            "elseif" => OKind::ElseIf,
            "else" => OKind::Else,
            "endif" => OKind::EndIf,
            "while" => OKind::While,
            "endwhile" => OKind::EndWhile,
            "do" => OKind::Do,
            "repeat" => OKind::Repeat,
            "endrepeat" => OKind::EndRepeat,
            "break" => OKind::Break,
            "continue" => OKind::Continue,
            "" => OKind::Program,
            other => {
                return Err(self.invalid(kw_start, format!("unknown O-word keyword {other:?}")))
            }
        };
        if matches!(name, OName::Computed(_)) && kind != OKind::Call {
            return Err(self.unsupported(
                start,
                format!(
                    "O-word with a computed number is supported with call only, not {keyword:?}"
                ),
            ));
        }
        let mut args = Vec::new();
        loop {
            match self.skip_blanks_and_peek() {
                Some('[') => args.push(self.value()?),
                Some('(') => {
                    self.comment()?;
                }
                _ => break,
            }
        }
        let want = match kind {
            OKind::If | OKind::ElseIf | OKind::While | OKind::Repeat => 1..=1,
            OKind::Return | OKind::EndSub => 0..=1,
            OKind::Call => 0..=30,
            _ => 0..=0,
        };
        if !want.contains(&args.len()) {
            return Err(self.invalid(
                kw_start,
                format!(
                    "O-word {keyword} takes {} bracketed value(s), got {}",
                    want.end(),
                    args.len()
                ),
            ));
        }
        Ok(OWord {
            name,
            kind,
            args,
            col: start + 1,
        })
    }

    /// Reads `<name>` (cursor on `<`): lower case, blanks removed.
    pub(super) fn angle_name(&mut self, at: usize) -> Result<String, GcodeError> {
        self.pos += 1;
        let mut name = String::new();
        loop {
            match self.peek() {
                None => return Err(self.invalid(at, "unclosed name '<'")),
                Some('>') => break,
                Some(c) if c.is_whitespace() => {}
                Some(c) => name.push(c.to_ascii_lowercase()),
            }
            self.pos += 1;
        }
        self.pos += 1;
        if name.is_empty() {
            return Err(self.invalid(at, "empty name '<>'"));
        }
        Ok(name)
    }

    /// Reads `[+-] digits [. digits]` with blanks allowed between the characters.
    pub(super) fn number(&mut self) -> Result<f64, String> {
        let save = self.pos;
        // Most numbers are a few characters: no allocation for them.
        let mut text = NumberText::default();
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
            self.pos = save;
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

/// The characters of one number as read, on the stack up to 32 bytes (a longer number moves to
/// the heap).
#[derive(Default)]
struct NumberText {
    bytes: [u8; 32],
    len: usize,
    long: Option<String>,
}

impl NumberText {
    fn push(&mut self, c: char) {
        if let Some(s) = &mut self.long {
            s.push(c);
        } else if c.is_ascii() && self.len < self.bytes.len() {
            self.bytes[self.len] = c as u8;
            self.len += 1;
        } else {
            let mut s = self.as_str().to_string();
            s.push(c);
            self.long = Some(s);
        }
    }

    fn as_str(&self) -> &str {
        match &self.long {
            Some(s) => s,
            // Only ASCII bytes are stored.
            None => std::str::from_utf8(&self.bytes[..self.len]).unwrap_or(""),
        }
    }

    fn parse(&self) -> Result<f64, std::num::ParseFloatError> {
        self.as_str().parse()
    }
}

impl std::fmt::Debug for NumberText {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Debug::fmt(self.as_str(), f)
    }
}

fn unsupported_letter_msg(letter: char) -> String {
    match letter {
        'U' | 'V' | 'W' => {
            format!("{letter} axis word is not supported (axes X, Y, Z, A, B, C only)")
        }
        _ => format!("unknown word letter '{letter}'"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::syntax::GcodeErrorKind;

    fn words(text: &str) -> Vec<(char, f64, usize)> {
        let block = parse_line(1, text)
            .expect("line parses")
            .expect("line has words");
        block
            .words
            .iter()
            .map(|w| (w.letter, w.value.literal().expect("literal"), w.col))
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
    fn parameters_expressions_and_o_words_are_read_as_syntax() {
        use crate::syntax::{BinOp, Expr, Func, OKind, OName, Param};
        let l = parse_line(1, "#1=2 G1 X[#1+2] Y-sin[30] (MSG, hi)")
            .unwrap()
            .unwrap();
        assert_eq!(l.assigns.len(), 1);
        assert_eq!(
            l.assigns[0].target,
            Param::Numbered(Box::new(Expr::Num(1.0)))
        );
        assert_eq!(
            l.words[1].value,
            Expr::Bin(
                BinOp::Add,
                Box::new(Expr::Param(Param::Numbered(Box::new(Expr::Num(1.0))))),
                Box::new(Expr::Num(2.0))
            )
        );
        assert_eq!(
            l.words[2].value,
            Expr::Neg(Box::new(Expr::Func(Func::Sin, Box::new(Expr::Num(30.0)))))
        );
        assert_eq!(l.messages, vec![" hi".to_string()]);
        let o = parse_line(1, "O<My Sub> call [1] [#<_a>]")
            .unwrap()
            .unwrap();
        let o = o.oword.unwrap();
        assert_eq!(
            (o.name, o.kind, o.args.len()),
            (OName::Named("mysub".into()), OKind::Call, 2)
        );
        assert!(parse_line(1, "/G0 X1").unwrap().unwrap().block_delete);
    }

    #[test]
    fn precedence_follows_linuxcnc() {
        use crate::syntax::{BinOp, Expr};
        let l = parse_line(1, "X[1+2*3**2 LT 4 OR 1]").unwrap().unwrap();
        let Expr::Bin(op, lhs, _) = &l.words[0].value else {
            panic!("binary expected")
        };
        assert_eq!(*op, BinOp::Or);
        assert!(matches!(**lhs, Expr::Bin(BinOp::Lt, _, _)));
    }

    #[test]
    fn malformed_expressions_are_invalid() {
        for text in [
            "X[1+]",
            "X[1 FOO 2]",
            "X[1",
            "#1 2",
            "o100 frobnicate",
            "G0 X1 o100 if [1]",
        ] {
            assert_eq!(err(text).kind, GcodeErrorKind::Invalid, "{text}");
        }
    }

    #[test]
    fn outside_the_subset_is_unsupported() {
        for (text, col) in [("G0 U1", 4), ("G1 @1 ^90", 4), ("(abort, stop)", 1)] {
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
