//! Parameters and the evaluation of values (LinuxCNC semantics).
//!
//! - Numbered parameters `#1…#5601` start at 0 and always exist; other numbers are refused.
//!   Those that mirror the modal state (stored G28/G30 positions, G92 offset, G54…G59 work
//!   offsets, in mm) are kept in step with it.
//!   `#1…#30` are saved on a subroutine call, set from the call's arguments (0 when missing)
//!   and restored on return.
//! - Named parameters: `#<_name>` is global, `#<name>` local to the subroutine call (or the
//!   main program) that set it. Reading one that was never set is an error.
//! - Trigonometry in degrees; `EQ`/`NE` compare within 1e-4; `MOD` is never negative;
//!   `ROUND` rounds halves away from zero; comparisons and logic give 1 or 0. Every result
//!   must be finite (division by zero, `SQRT` of a negative number, `LN` of a non-positive
//!   number, `ASIN`/`ACOS` outside [−1, 1] are errors).

use std::collections::HashMap;

use crate::syntax::{BinOp, Expr, Func, GcodeError, Param};

/// Number of numbered parameters (`#0…#5601`, LinuxCNC's; `#0` reads 0 and cannot be set).
pub const NUM_PARAMS: usize = 5602;
/// Numbered parameters local to a subroutine call (`#1…#30`).
pub(super) const CALL_PARAMS: usize = 30;
/// Tolerance of `EQ` and `NE`.
const EQ_TOLERANCE: f64 = 1e-4;

/// All parameters of a running program.
#[derive(Debug, Clone)]
pub(super) struct Params {
    numbered: Vec<f64>,
    globals: HashMap<String, f64>,
    /// Local named parameters, one scope per active call (the first is the main program's).
    locals: Vec<HashMap<String, f64>>,
}

impl Params {
    /// All numbered parameters 0, no named parameter set.
    pub fn new() -> Self {
        Self {
            numbered: vec![0.0; NUM_PARAMS],
            globals: HashMap::from([
                ("_value".to_string(), 0.0),
                ("_value_returned".to_string(), 0.0),
            ]),
            locals: vec![HashMap::new()],
        }
    }

    /// Opens a call scope: saves `#1…#30`, sets them from `args` (0 when missing).
    pub fn enter_call(&mut self, args: &[f64]) -> [f64; CALL_PARAMS] {
        let mut saved = [0.0; CALL_PARAMS];
        saved.copy_from_slice(&self.numbered[1..=CALL_PARAMS]);
        for i in 0..CALL_PARAMS {
            self.numbered[i + 1] = args.get(i).copied().unwrap_or(0.0);
        }
        self.locals.push(HashMap::new());
        saved
    }

    /// Closes a call scope, restoring `#1…#30`.
    pub fn leave_call(&mut self, saved: &[f64; CALL_PARAMS]) {
        self.numbered[1..=CALL_PARAMS].copy_from_slice(saved);
        if self.locals.len() > 1 {
            self.locals.pop();
        }
    }

    /// Numbered parameter `n` (range already checked).
    pub fn get(&self, n: usize) -> f64 {
        self.numbered[n]
    }

    /// Sets numbered parameter `n` (range already checked).
    pub fn set(&mut self, n: usize, v: f64) {
        self.numbered[n] = v;
    }

    /// Sets a global named parameter (name without `#<>`, starting with `_`).
    pub fn set_global(&mut self, name: &str, v: f64) {
        self.globals.insert(name.to_string(), v);
    }

    fn named(&self, name: &str) -> Option<f64> {
        if name.starts_with('_') {
            self.globals.get(name).copied()
        } else {
            self.locals.last().and_then(|l| l.get(name)).copied()
        }
    }

    /// Evaluates a value; errors name `line` and `col` (the word's column).
    pub fn eval(&self, e: &Expr, line: usize, col: usize) -> Result<f64, GcodeError> {
        let v = match e {
            Expr::Num(v) => *v,
            Expr::Param(p) => self.read(p, line, col)?,
            Expr::Neg(x) => -self.eval(x, line, col)?,
            Expr::Func(f, x) => func(*f, self.eval(x, line, col)?)
                .map_err(|why| GcodeError::invalid(line, col, why))?,
            Expr::Atan(y, x) => {
                let (y, x) = (self.eval(y, line, col)?, self.eval(x, line, col)?);
                y.atan2(x).to_degrees()
            }
            Expr::Exists(p) => match p {
                Param::Named(name) => f64::from(u8::from(self.named(name).is_some())),
                Param::Numbered(n) => {
                    let n = self.eval(n, line, col)?;
                    f64::from(u8::from(param_index(n).is_some()))
                }
            },
            Expr::Bin(op, a, b) => {
                let (a, b) = (self.eval(a, line, col)?, self.eval(b, line, col)?);
                binary(*op, a, b).map_err(|why| GcodeError::invalid(line, col, why))?
            }
        };
        if !v.is_finite() {
            return Err(GcodeError::invalid(
                line,
                col,
                "expression result is not a finite number",
            ));
        }
        Ok(v)
    }

    /// The value of a parameter.
    fn read(&self, p: &Param, line: usize, col: usize) -> Result<f64, GcodeError> {
        match p {
            Param::Numbered(n) => {
                let n = self.eval(n, line, col)?;
                let i = param_index(n).ok_or_else(|| out_of_range(n, line, col))?;
                Ok(self.numbered[i])
            }
            Param::Named(name) if name.starts_with("_ini[") || name.starts_with("_hal[") => {
                Err(GcodeError::unsupported(
                    line,
                    col,
                    format!("INI/HAL parameter #<{name}> is not supported"),
                ))
            }
            Param::Named(name) => self.named(name).ok_or_else(|| {
                GcodeError::invalid(line, col, format!("named parameter #<{name}> not defined"))
            }),
        }
    }

    /// Which parameter a setting targets (evaluated now, with the line's old values).
    pub fn target(&self, p: &Param, line: usize, col: usize) -> Result<Target, GcodeError> {
        match p {
            Param::Numbered(n) => {
                let n = self.eval(n, line, col)?;
                match param_index(n) {
                    Some(i) if i > 0 => Ok(Target::Numbered(i)),
                    _ => Err(out_of_range(n, line, col)),
                }
            }
            Param::Named(name) => Ok(Target::Named(name.clone())),
        }
    }

    /// Makes a named target exist (value 0) if it does not yet; numbered ones always exist.
    pub fn define(&mut self, t: &Target) {
        if let Target::Named(name) = t {
            if self.named(name).is_none() {
                self.assign(t.clone(), 0.0);
            }
        }
    }

    /// Applies a setting.
    pub fn assign(&mut self, t: Target, v: f64) {
        match t {
            Target::Numbered(i) => self.numbered[i] = v,
            Target::Named(name) if name.starts_with('_') => {
                self.globals.insert(name, v);
            }
            Target::Named(name) => {
                if let Some(scope) = self.locals.last_mut() {
                    scope.insert(name, v);
                }
            }
        }
    }
}

/// A parameter to be set.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Target {
    /// `#n`.
    Numbered(usize),
    /// `#<name>`.
    Named(String),
}

/// The index of numbered parameter `n` if it is a whole number in range.
fn param_index(n: f64) -> Option<usize> {
    let r = n.round();
    ((n - r).abs() < 1e-4 && r >= 0.0 && r < NUM_PARAMS as f64).then_some(r as usize)
}

fn out_of_range(n: f64, line: usize, col: usize) -> GcodeError {
    GcodeError::invalid(
        line,
        col,
        format!(
            "parameter number {n} out of range (1 to {})",
            NUM_PARAMS - 1
        ),
    )
}

fn truth(v: bool) -> f64 {
    f64::from(u8::from(v))
}

fn binary(op: BinOp, a: f64, b: f64) -> Result<f64, String> {
    Ok(match op {
        BinOp::Pow => {
            if a < 0.0 && b.fract() != 0.0 {
                return Err(format!(
                    "{a} ** {b}: negative base with a fractional exponent"
                ));
            }
            a.powf(b)
        }
        BinOp::Mul => a * b,
        BinOp::Div => {
            if b == 0.0 {
                return Err("division by zero".to_string());
            }
            a / b
        }
        BinOp::Mod => {
            if b == 0.0 {
                return Err("MOD by zero".to_string());
            }
            let r = a % b;
            if r < 0.0 {
                r + b.abs()
            } else {
                r
            }
        }
        BinOp::Add => a + b,
        BinOp::Sub => a - b,
        BinOp::Eq => truth((a - b).abs() < EQ_TOLERANCE),
        BinOp::Ne => truth((a - b).abs() >= EQ_TOLERANCE),
        BinOp::Gt => truth(a > b),
        BinOp::Ge => truth(a >= b),
        BinOp::Lt => truth(a < b),
        BinOp::Le => truth(a <= b),
        BinOp::And => truth(a != 0.0 && b != 0.0),
        BinOp::Or => truth(a != 0.0 || b != 0.0),
        BinOp::Xor => truth((a != 0.0) != (b != 0.0)),
    })
}

fn func(f: Func, x: f64) -> Result<f64, String> {
    Ok(match f {
        Func::Abs => x.abs(),
        Func::Acos | Func::Asin if !(-1.0..=1.0).contains(&x) => {
            return Err(format!("ACOS/ASIN argument {x} outside [-1, 1]"))
        }
        Func::Acos => x.acos().to_degrees(),
        Func::Asin => x.asin().to_degrees(),
        Func::Cos => x.to_radians().cos(),
        Func::Sin => x.to_radians().sin(),
        Func::Tan => x.to_radians().tan(),
        Func::Exp => x.exp(),
        Func::Fix => x.floor(),
        Func::Fup => x.ceil(),
        Func::Ln if x <= 0.0 => return Err(format!("LN of non-positive number {x}")),
        Func::Ln => x.ln(),
        Func::Round => x.round(),
        Func::Sqrt if x < 0.0 => return Err(format!("SQRT of negative number {x}")),
        Func::Sqrt => x.sqrt(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::syntax::parse_line;

    fn val(text: &str) -> f64 {
        let line = parse_line(1, &format!("X{text}")).unwrap().unwrap();
        Params::new().eval(&line.words[0].value, 1, 1).unwrap()
    }

    #[test]
    fn operators_and_functions_follow_linuxcnc() {
        for (text, want) in [
            ("[-7 MOD 3]", 2.0),
            ("[7 MOD -3]", 1.0),
            ("[1 EQ 1.00001]", 1.0),
            ("[1 EQ 1.001]", 0.0),
            ("ROUND[-2.5]", -3.0),
            ("FIX[-2.5]", -3.0),
            ("FUP[2.1]", 3.0),
            ("[2**3**2]", 64.0),
            ("[1 - 2 - 3]", -4.0),
            ("[3 AND 0.5]", 1.0),
            ("[5 XOR 0]", 1.0),
            ("[1+2*3]", 7.0),
            ("-[2]", -2.0),
            ("ATAN[1]/[1]", 45.0),
            ("SQRT[16]", 4.0),
            ("EXISTS[#<nope>]", 0.0),
            ("EXISTS[#1]", 1.0),
        ] {
            assert!((val(text) - want).abs() < 1e-12, "{text}: {}", val(text));
        }
        assert!((val("SIN[30]") - 0.5).abs() < 1e-12);
    }

    #[test]
    fn bad_arithmetic_and_unset_names_are_invalid() {
        for text in [
            "[1/0]",
            "SQRT[-1]",
            "LN[0]",
            "ACOS[2]",
            "#<x>",
            "#6000",
            "[10**400]",
        ] {
            let line = parse_line(1, &format!("X{text}")).unwrap().unwrap();
            assert!(
                Params::new().eval(&line.words[0].value, 1, 1).is_err(),
                "{text}"
            );
        }
    }
}
