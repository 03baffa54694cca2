//! Long and deep expressions: the parser bounds the operations on a line
//! ([`vmc_gcode::syntax::MAX_OPERATIONS`]), so no program can build an expression tree deep
//! enough to overflow the stack when it is evaluated or dropped. Every case runs on a thread
//! with a 2 MB stack (the default of test threads, and smaller than a program's main thread),
//! and a property test draws random chains and nestings of every operator around the bound.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use vmc_gcode::interp::{run_program, CanonKind, InterpConfig};
use vmc_gcode::syntax::MAX_OPERATIONS;

/// Runs `src` through the interpreter on a 2 MB thread; `Ok` holds the number of moves.
fn run_on_small_stack(src: String) -> Result<usize, String> {
    std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || {
            run_program(&src, &InterpConfig::default())
                .map(|m| m.len())
                .map_err(|e| e.to_string())
        })
        .unwrap()
        .join()
        .expect("the interpreter panicked")
}

fn chain(op: &str, terms: usize) -> String {
    vec!["1"; terms].join(op)
}

#[test]
fn a_sum_of_a_hundred_thousand_terms_is_refused_with_its_line_and_column() {
    let src = format!("G21\n#1=[{}]\nM2\n", chain("+", 100_000));
    let err = run_on_small_stack(src).unwrap_err();
    assert!(err.contains("line 2"), "{err}");
    assert!(err.contains("column"), "{err}");
    assert!(
        err.contains(&format!("more than {MAX_OPERATIONS} operations")),
        "{err}"
    );
}

#[test]
fn a_long_chain_of_powers_is_refused_not_a_stack_overflow() {
    let src = format!("G21\nG0 X[{}]\nM2\n", chain("**", 200_000));
    let err = run_on_small_stack(src).unwrap_err();
    assert!(err.contains("line 2"), "{err}");
}

#[test]
fn the_longest_accepted_chain_evaluates_to_its_sum() {
    let src = format!(
        "G21\n#1=[{}]\nG0 X[#1/100]\nM2\n",
        chain("+", MAX_OPERATIONS + 1)
    );
    // MAX_OPERATIONS additions of 1 starting from 1: X = (MAX_OPERATIONS + 1) / 100.
    let x_mm = std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || {
            let moves = run_program(&src, &InterpConfig::default()).expect("accepted");
            moves.iter().find_map(|m| match m.kind {
                CanonKind::Traverse { end_mm, .. } => Some(end_mm[0]),
                _ => None,
            })
        })
        .unwrap()
        .join()
        .unwrap()
        .expect("one traverse");
    assert!(
        (x_mm - (MAX_OPERATIONS + 1) as f64 / 100.0).abs() < 1e-9,
        "{x_mm}"
    );
    let over = format!("G21\n#1=[{}]\nM2\n", chain("+", MAX_OPERATIONS + 2));
    assert!(run_on_small_stack(over).is_err());
}

#[test]
fn operations_are_counted_per_line_not_per_program() {
    let line = format!("#1=[{}]\n", chain("*", MAX_OPERATIONS / 2));
    let src = format!("G21\n{}M2\n", line.repeat(5));
    assert!(run_on_small_stack(src).is_ok());
}

/// One random expression: chains of random operators, brackets, functions and unary minus.
fn expression() -> impl Strategy<Value = String> {
    let ops = prop::sample::select(vec![
        "+", "-", "*", "/", "**", " MOD ", " EQ ", " LT ", " AND ", " XOR ",
    ]);
    let atom = prop_oneof![
        Just("1".to_string()),
        Just("2.5".to_string()),
        Just("#1".to_string()),
        Just("-[3]".to_string()),
        Just("SIN[30]".to_string()),
    ];
    (prop::collection::vec((ops, atom), 1..2_500), 0usize..80).prop_map(|(terms, nest)| {
        let mut body = String::from("1");
        for (op, a) in terms {
            body.push_str(op);
            body.push_str(&a);
        }
        format!("{}{}{}", "[".repeat(nest + 1), body, "]".repeat(nest + 1))
    })
}

/// Cases of the property below (each up to a few thousand operations).
const CASES: u32 = 200;

#[test]
fn random_chains_and_nestings_never_overflow_the_stack() {
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: CASES,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[39; 32]),
    );
    let refused = std::cell::Cell::new(0u32);
    runner
        .run(&expression(), |e| {
            let res = run_on_small_stack(format!("G21\n#1=0.5\n#2={e}\nM2\n"));
            if let Err(msg) = &res {
                prop_assert!(msg.contains("line 3"), "{msg}");
                refused.set(refused.get() + 1);
            }
            Ok(())
        })
        .unwrap();
    // Both sides of the bound are drawn.
    let refused = refused.get();
    println!("{CASES} random expressions, none panicked, {refused} refused");
    assert!(
        refused > 0 && refused < CASES,
        "{refused} of {CASES} refused"
    );
}
