//! Syntax trees of values, parameter settings and O-word statements (LinuxCNC's RS274/NGC).
//! Built by the lexer; evaluated by the interpreter (`interp::expr`).

/// A binary operator of a bracketed expression.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `**`: power.
    Pow,
    /// `*`.
    Mul,
    /// `/`.
    Div,
    /// `MOD`: remainder with the sign of the divisor's magnitude (LinuxCNC: never negative).
    Mod,
    /// `+`.
    Add,
    /// `-`.
    Sub,
    /// `EQ` (equal within 1e-6).
    Eq,
    /// `NE`.
    Ne,
    /// `GT`.
    Gt,
    /// `GE`.
    Ge,
    /// `LT`.
    Lt,
    /// `LE`.
    Le,
    /// `AND` (logical).
    And,
    /// `OR` (logical).
    Or,
    /// `XOR` (logical).
    Xor,
}

impl BinOp {
    /// Binding strength (higher binds tighter): `**` > `* / MOD` > `+ -` > comparisons >
    /// `AND OR XOR`.
    pub fn precedence(self) -> u8 {
        match self {
            BinOp::Pow => 5,
            BinOp::Mul | BinOp::Div | BinOp::Mod => 4,
            BinOp::Add | BinOp::Sub => 3,
            BinOp::Eq | BinOp::Ne | BinOp::Gt | BinOp::Ge | BinOp::Lt | BinOp::Le => 2,
            BinOp::And | BinOp::Or | BinOp::Xor => 1,
        }
    }
}

/// A unary function (`SIN[…]`); `ATAN` and `EXISTS` have their own [`Expr`] forms.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    /// `ABS`.
    Abs,
    /// `ACOS` (degrees).
    Acos,
    /// `ASIN` (degrees).
    Asin,
    /// `COS` (argument in degrees).
    Cos,
    /// `EXP`.
    Exp,
    /// `FIX`: round down.
    Fix,
    /// `FUP`: round up.
    Fup,
    /// `LN`.
    Ln,
    /// `ROUND`: to the nearest integer, halves away from zero.
    Round,
    /// `SIN` (degrees).
    Sin,
    /// `SQRT`.
    Sqrt,
    /// `TAN` (degrees).
    Tan,
}

/// A parameter reference: `#5`, `#[1+2]`, `##1`, `#<name>` (local) or `#<_name>` (global).
#[derive(Debug, Clone, PartialEq)]
pub enum Param {
    /// A numbered parameter; the number is itself a value.
    Numbered(Box<Expr>),
    /// A named parameter, lower case without blanks; global if it starts with `_`.
    Named(String),
}

/// A value: a number, a parameter, a function or a bracketed expression.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    /// A literal number.
    Num(f64),
    /// The value of a parameter.
    Param(Param),
    /// Unary minus.
    Neg(Box<Expr>),
    /// A unary function.
    Func(Func, Box<Expr>),
    /// `ATAN[y]/[x]` in degrees.
    Atan(Box<Expr>, Box<Expr>),
    /// `EXISTS[#<name>]`: 1 if the parameter is defined, else 0.
    Exists(Param),
    /// A binary operation.
    Bin(BinOp, Box<Expr>, Box<Expr>),
}

impl Expr {
    /// The number if this is a literal.
    pub fn literal(&self) -> Option<f64> {
        match self {
            Expr::Num(v) => Some(*v),
            _ => None,
        }
    }
}

/// A word whose value may be an expression: `X[#1+2]`.
#[derive(Debug, Clone, PartialEq)]
pub struct ExprWord {
    /// Upper-case letter.
    pub letter: char,
    /// The value, evaluated by the interpreter.
    pub value: Expr,
    /// 1-based character column of the letter.
    pub col: usize,
}

/// A parameter setting `#1 = value`, applied after the line's words are read.
#[derive(Debug, Clone, PartialEq)]
pub struct Assign {
    /// The parameter set.
    pub target: Param,
    /// The value.
    pub value: Expr,
    /// 1-based column of the `#`.
    pub col: usize,
}

/// The name of an O-word: `o100` or `o<name>` (lower case without blanks).
#[derive(Debug, Clone, PartialEq)]
pub enum OName {
    /// A number.
    Number(f64),
    /// A name.
    Named(String),
    /// A number computed when the statement runs: `o[#2 * 10] call`, `o#<sub> call` (only
    /// with `call`).
    Computed(Box<Expr>),
}

impl std::fmt::Display for OName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OName::Number(n) => write!(f, "o{n}"),
            OName::Named(s) => write!(f, "o<{s}>"),
            OName::Computed(_) => write!(f, "o[…]"),
        }
    }
}

/// The keyword of an O-word statement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OKind {
    /// `sub`.
    Sub,
    /// `endsub [value]`.
    EndSub,
    /// `call [args]…`.
    Call,
    /// `return [value]`.
    Return,
    /// `if [cond]`.
    If,
    /// `elseif [cond]`.
    ElseIf,
    /// `else`.
    Else,
    /// `endif`.
    EndIf,
    /// `while [cond]` (loop head, or the end of a `do` loop).
    While,
    /// `endwhile`.
    EndWhile,
    /// `do`.
    Do,
    /// `repeat [count]`.
    Repeat,
    /// `endrepeat`.
    EndRepeat,
    /// `break`.
    Break,
    /// `continue`.
    Continue,
    /// No keyword: `O100` alone starts a Fanuc-style subroutine (called by `M98 P100`, ended
    /// by `M99`) or names the program (`O<name>`).
    Program,
}

/// An O-word statement: `o100 if [#1 GT 2]`.
#[derive(Debug, Clone, PartialEq)]
pub struct OWord {
    /// Its name.
    pub name: OName,
    /// Its keyword.
    pub kind: OKind,
    /// Condition, count, return value or call arguments (bracketed values).
    pub args: Vec<Expr>,
    /// 1-based column of the `O`.
    pub col: usize,
}

/// One line of a program in syntax form: words (values not yet evaluated), parameter
/// settings, an O-word statement, messages.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Line {
    /// 1-based physical line in the source text.
    pub line: usize,
    /// The `N` number if one was written (informational only).
    pub line_number: Option<f64>,
    /// True if the line starts with the block-delete `/`.
    pub block_delete: bool,
    /// Words in source order (N excluded).
    pub words: Vec<ExprWord>,
    /// Parameter settings in source order.
    pub assigns: Vec<Assign>,
    /// The O-word statement (then there are no words).
    pub oword: Option<OWord>,
    /// Texts of `(MSG, …)` comments.
    pub messages: Vec<String>,
    /// Column of the first word or setting (1 if none).
    pub first_col: usize,
}

impl Line {
    /// True if the line does nothing (only comments other than messages, or an N word).
    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
            && self.assigns.is_empty()
            && self.oword.is_none()
            && self.messages.is_empty()
    }
}
