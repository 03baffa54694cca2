//! Values: numbers, parameters `#…`, functions `SIN[…]` and bracketed expressions `[…]` with
//! LinuxCNC's operators and precedence (`**` > `* / MOD` > `+ -` > `EQ NE GT GE LT LE` >
//! `AND OR XOR`, left to right within a level).

use super::expr::{BinOp, Expr, Func, Param};
use super::lexer::Lexer;
use super::GcodeError;

/// Deepest nesting of brackets and functions accepted in one value (guards the stack).
const MAX_DEPTH: usize = 64;

/// Most binary operations accepted on one line. A chain `1+1+…` builds a tree as deep as it
/// is long, and evaluating (and dropping) that tree recurses once per level: this bound keeps
/// the deepest tree well inside a 2 MB thread stack. Real programs use a few dozen.
pub const MAX_OPERATIONS: usize = 1000;

impl Lexer<'_> {
    /// The value of a word (cursor after the letter). A plain number keeps the messages of
    /// the number reader (`X word: missing number`).
    pub(super) fn value_for(
        &mut self,
        letter: char,
        letter_pos: usize,
    ) -> Result<Expr, GcodeError> {
        let plain = match self.peek() {
            Some('0'..='9' | '.') => true,
            Some('+' | '-') => {
                let mut i = self.pos + 1;
                while matches!(self.chars.get(i), Some(c) if c.is_whitespace()) {
                    i += 1;
                }
                !matches!(self.chars.get(i), Some('[' | '#') | Some('a'..='z' | 'A'..='Z'))
            }
            Some('[' | '#') => false,
            Some(c) if c.is_ascii_alphabetic() => !self.starts_function(),
            _ => true,
        };
        if plain {
            return self
                .number()
                .map(Expr::Num)
                .map_err(|why| self.invalid(letter_pos, format!("{letter} word: {why}")));
        }
        self.value()
    }

    /// Reads one value (number, parameter, function, `[expression]`, or a signed value).
    pub(super) fn value(&mut self) -> Result<Expr, GcodeError> {
        self.value_at(0)
    }

    fn value_at(&mut self, depth: usize) -> Result<Expr, GcodeError> {
        let start = self.pos;
        if depth > MAX_DEPTH {
            return Err(self.invalid(start, format!("expression nested deeper than {MAX_DEPTH}")));
        }
        match self.skip_blanks_and_peek() {
            Some('[') => self.bracketed(depth + 1),
            Some('#') => Ok(Expr::Param(self.param_at(depth + 1)?)),
            Some(sign @ ('+' | '-')) => {
                let save = self.pos;
                self.pos += 1;
                if matches!(self.skip_blanks_and_peek(), Some('0'..='9' | '.')) {
                    self.pos = save;
                    return self
                        .number()
                        .map(Expr::Num)
                        .map_err(|why| self.invalid(save, why));
                }
                let inner = self.value_at(depth + 1)?;
                Ok(if sign == '-' {
                    Expr::Neg(Box::new(inner))
                } else {
                    inner
                })
            }
            Some('0'..='9' | '.') => {
                let at = self.pos;
                self.number()
                    .map(Expr::Num)
                    .map_err(|why| self.invalid(at, why))
            }
            Some(c) if c.is_ascii_alphabetic() => self.function(depth + 1),
            _ => Err(self.invalid(self.pos, "value expected (number, '#', '[' or function)")),
        }
    }

    /// Reads a parameter reference (cursor on `#`).
    pub(super) fn param(&mut self) -> Result<Param, GcodeError> {
        self.param_at(0)
    }

    fn param_at(&mut self, depth: usize) -> Result<Param, GcodeError> {
        let at = self.pos;
        self.pos += 1;
        if self.skip_blanks_and_peek() == Some('<') {
            return Ok(Param::Named(self.angle_name(at)?));
        }
        Ok(Param::Numbered(Box::new(self.value_at(depth + 1)?)))
    }

    /// True if the letters at the cursor spell a function name followed by `[`.
    fn starts_function(&self) -> bool {
        let mut end = self.pos;
        while matches!(self.chars.get(end), Some(c) if c.is_ascii_alphabetic()) {
            end += 1;
        }
        let name: String = self.chars[self.pos..end].iter().collect();
        let name = name.to_ascii_uppercase();
        (name == "ATAN" || name == "EXISTS" || func(&name).is_some())
            && self.chars[end..].iter().find(|c| !c.is_whitespace()) == Some(&'[')
    }

    /// `[ expression ]` (cursor on `[`).
    fn bracketed(&mut self, depth: usize) -> Result<Expr, GcodeError> {
        let open = self.pos;
        self.pos += 1;
        let e = self.binary(0, depth)?;
        if self.skip_blanks_and_peek() != Some(']') {
            return Err(match self.peek() {
                None => self.invalid(open, "unclosed '['"),
                Some(c) => self.invalid(self.pos, format!("operator or ']' expected, found {c:?}")),
            });
        }
        self.pos += 1;
        Ok(e)
    }

    fn binary(&mut self, min_prec: u8, depth: usize) -> Result<Expr, GcodeError> {
        let mut lhs = self.value_at(depth)?;
        loop {
            let save = self.pos;
            let Some(op) = self.operator()? else {
                break;
            };
            if op.precedence() < min_prec {
                self.pos = save;
                break;
            }
            self.operations += 1;
            if self.operations > MAX_OPERATIONS {
                return Err(self.invalid(
                    save,
                    format!(
                        "more than {MAX_OPERATIONS} operations on one line; \
                         split the expression over several parameters"
                    ),
                ));
            }
            let rhs = self.binary(op.precedence() + 1, depth + 1)?;
            lhs = Expr::Bin(op, Box::new(lhs), Box::new(rhs));
        }
        Ok(lhs)
    }

    /// Consumes a binary operator if one follows; `None` before `]` or the end of the line.
    fn operator(&mut self) -> Result<Option<BinOp>, GcodeError> {
        let at = self.pos;
        let op = match self.skip_blanks_and_peek() {
            Some('*') => {
                self.pos += 1;
                if self.skip_blanks_and_peek() == Some('*') {
                    self.pos += 1;
                    BinOp::Pow
                } else {
                    BinOp::Mul
                }
            }
            Some('/') => {
                self.pos += 1;
                BinOp::Div
            }
            Some('+') => {
                self.pos += 1;
                BinOp::Add
            }
            Some('-') => {
                self.pos += 1;
                BinOp::Sub
            }
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.pos;
                while matches!(self.peek(), Some(c) if c.is_ascii_alphabetic()) {
                    self.pos += 1;
                }
                let name: String = self.chars[start..self.pos].iter().collect();
                match name.to_ascii_uppercase().as_str() {
                    "MOD" => BinOp::Mod,
                    "EQ" => BinOp::Eq,
                    "NE" => BinOp::Ne,
                    "GT" => BinOp::Gt,
                    "GE" => BinOp::Ge,
                    "LT" => BinOp::Lt,
                    "LE" => BinOp::Le,
                    "AND" => BinOp::And,
                    "OR" => BinOp::Or,
                    "XOR" => BinOp::Xor,
                    _ => return Err(self.invalid(start, format!("unknown operator {name:?}"))),
                }
            }
            _ => {
                self.pos = at;
                return Ok(None);
            }
        };
        Ok(Some(op))
    }

    /// `NAME[…]`, `ATAN[…]/[…]`, `EXISTS[#<name>]` (cursor on the first letter).
    fn function(&mut self, depth: usize) -> Result<Expr, GcodeError> {
        let start = self.pos;
        while matches!(self.peek(), Some(c) if c.is_ascii_alphabetic()) {
            self.pos += 1;
        }
        let name: String = self.chars[start..self.pos].iter().collect();
        let name = name.to_ascii_uppercase();
        if self.skip_blanks_and_peek() != Some('[') {
            return Err(self.invalid(start, format!("value expected, found {name:?}")));
        }
        if name == "EXISTS" {
            self.pos += 1;
            if self.skip_blanks_and_peek() != Some('#') {
                return Err(self.invalid(self.pos, "EXISTS needs a parameter '#<name>'"));
            }
            let p = self.param_at(depth + 1)?;
            if self.skip_blanks_and_peek() != Some(']') {
                return Err(self.invalid(self.pos, "']' expected after EXISTS[#…"));
            }
            self.pos += 1;
            return Ok(Expr::Exists(p));
        }
        let arg = self.bracketed(depth + 1)?;
        if name == "ATAN" {
            if self.skip_blanks_and_peek() != Some('/') {
                return Err(self.invalid(self.pos, "ATAN needs the form ATAN[y]/[x]"));
            }
            self.pos += 1;
            if self.skip_blanks_and_peek() != Some('[') {
                return Err(self.invalid(self.pos, "ATAN needs the form ATAN[y]/[x]"));
            }
            let x = self.bracketed(depth + 1)?;
            return Ok(Expr::Atan(Box::new(arg), Box::new(x)));
        }
        match func(&name) {
            Some(f) => Ok(Expr::Func(f, Box::new(arg))),
            None => Err(self.invalid(start, format!("unknown function {name:?}"))),
        }
    }
}

fn func(name: &str) -> Option<Func> {
    Some(match name {
        "ABS" => Func::Abs,
        "ACOS" => Func::Acos,
        "ASIN" => Func::Asin,
        "COS" => Func::Cos,
        "EXP" => Func::Exp,
        "FIX" => Func::Fix,
        "FUP" => Func::Fup,
        "LN" => Func::Ln,
        "ROUND" => Func::Round,
        "SIN" => Func::Sin,
        "SQRT" => Func::Sqrt,
        "TAN" => Func::Tan,
        _ => return None,
    })
}
