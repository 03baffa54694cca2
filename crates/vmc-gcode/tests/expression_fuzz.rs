//! Property tests of the expression parser and evaluator, from a fixed seed: (1) token soup —
//! numbers (ordinary and extreme), parameters, every binary operator and function, brackets
//! balanced or not — never panics, and every refusal is located on its line and column; (2)
//! well-formed arithmetic trees evaluate to what an independent evaluator (written here, in
//! Rust's own `f64` arithmetic) gives, or are refused, never a different number.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use vmc_gcode::interp::{run_program, CanonKind, InterpConfig};

/// Cases of each property.
const SOUP_CASES: u32 = 3000;
const TREE_CASES: u32 = 1500;

fn runner(cases: u32, seed: u8) -> TestRunner {
    TestRunner::new_with_rng(
        Config {
            cases,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[seed; 32]),
    )
}

/// The X of the first traverse of `src`, or the interpreter's error; a panic fails the test
/// (the thread's join reports it).
fn x_of(src: String) -> Result<Option<f64>, String> {
    std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || {
            run_program(&src, &InterpConfig::default())
                .map(|moves| {
                    moves.iter().find_map(|m| match m.kind {
                        CanonKind::Traverse { end_mm, .. } => Some(end_mm[0]),
                        _ => None,
                    })
                })
                .map_err(|e| e.to_string())
        })
        .unwrap()
        .join()
        .expect("the interpreter panicked")
}

fn token() -> impl Strategy<Value = String> {
    let fixed = prop::sample::select(vec![
        "[",
        "[",
        "]",
        "]",
        "+",
        "-",
        "*",
        "/",
        "**",
        " MOD ",
        " AND ",
        " OR ",
        " XOR ",
        " EQ ",
        " NE ",
        " GT ",
        " GE ",
        " LT ",
        " LE ",
        "SIN",
        "COS",
        "TAN",
        "ASIN",
        "ACOS",
        "ATAN",
        "SQRT",
        "EXP",
        "LN",
        "ABS",
        "FIX",
        "FUP",
        "ROUND",
        "EXISTS",
        "#1",
        "#2",
        "#5400",
        "#<_x>",
        "#<y>",
        "#",
        "1e999",
        "0",
        "-0",
        "1e308",
        "0.0000001",
        "99999",
        ".",
        "/[2]",
    ]);
    prop_oneof![
        3 => fixed.prop_map(str::to_string),
        2 => (-1000.0f64..1000.0).prop_map(|v| format!("{v:.3}")),
    ]
}

#[test]
fn token_soup_never_panics_and_every_refusal_has_line_and_column() {
    let refused = std::cell::Cell::new(0u32);
    runner(SOUP_CASES, 11)
        .run(&prop::collection::vec(token(), 1..25), |tokens| {
            let expr = tokens.concat();
            let src = format!("G21\n#1=2\n#2=[{expr}]\nG0 X#2\nM2\n");
            match x_of(src) {
                Ok(Some(x)) => prop_assert!(x.is_finite(), "{expr} moved to {x}"),
                Ok(None) => {}
                Err(msg) => {
                    prop_assert!(!msg.contains('\n'), "{msg}");
                    prop_assert!(
                        msg.contains("line 3, column") || msg.contains("line 4"),
                        "{expr}: {msg}"
                    );
                    refused.set(refused.get() + 1);
                }
            }
            Ok(())
        })
        .unwrap();
    let refused = refused.get();
    println!("{SOUP_CASES} token soups, none panicked, {refused} refused");
    assert!(refused > 0 && refused < SOUP_CASES, "{refused} refused");
}

/// A well-formed arithmetic expression and its value by Rust's `f64` arithmetic.
#[derive(Debug, Clone)]
enum Tree {
    Num(i32),
    Bin(Box<Tree>, char, Box<Tree>),
    Neg(Box<Tree>),
}

impl Tree {
    fn text(&self) -> String {
        match self {
            Tree::Num(n) => n.to_string(),
            Tree::Bin(a, op, b) => format!("[{}{op}{}]", a.text(), b.text()),
            Tree::Neg(a) => format!("-{}", a.text()),
        }
    }

    fn value(&self) -> f64 {
        match self {
            Tree::Num(n) => f64::from(*n),
            Tree::Bin(a, op, b) => {
                let (a, b) = (a.value(), b.value());
                match op {
                    '+' => a + b,
                    '-' => a - b,
                    '*' => a * b,
                    _ => a / b,
                }
            }
            Tree::Neg(a) => -a.value(),
        }
    }
}

fn tree() -> impl Strategy<Value = Tree> {
    (-50i32..50)
        .prop_map(Tree::Num)
        .prop_recursive(6, 64, 2, |inner| {
            prop_oneof![
                (
                    inner.clone(),
                    prop::sample::select(vec!['+', '-', '*', '/']),
                    inner.clone()
                )
                    .prop_map(|(a, op, b)| Tree::Bin(Box::new(a), op, Box::new(b))),
                inner.prop_map(|a| Tree::Neg(Box::new(a))),
            ]
        })
}

#[test]
fn arithmetic_trees_evaluate_as_an_independent_evaluator_or_are_refused() {
    let agreed = std::cell::Cell::new(0u32);
    runner(TREE_CASES, 12)
        .run(&tree(), |t| {
            let want = t.value();
            let src = format!("G21\n#1={}\nG0 X#1\nM2\n", t.text());
            match x_of(src) {
                Ok(Some(x)) => {
                    prop_assert!(want.is_finite(), "{} = {want} accepted as {x}", t.text());
                    let tol = 1e-9 * want.abs().max(1.0);
                    prop_assert!((x - want).abs() <= tol, "{}: {x} vs {want}", t.text());
                    agreed.set(agreed.get() + 1);
                }
                Ok(None) => prop_assert!(false, "no move for {}", t.text()),
                Err(msg) => {
                    // Only a division by zero (or what it leads to) is refused.
                    prop_assert!(!want.is_finite(), "{} = {want} refused: {msg}", t.text());
                    prop_assert!(msg.contains("line 2"), "{msg}");
                }
            }
            Ok(())
        })
        .unwrap();
    let agreed = agreed.get();
    println!("{TREE_CASES} arithmetic trees, none panicked, {agreed} evaluated to the reference");
    assert!(agreed > TREE_CASES / 2, "{agreed}");
}
