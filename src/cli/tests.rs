use clap::{CommandFactory, Parser};

use super::*;

/// The arguments after `cargo run --release --` of every such line of `text` (a trailing
/// `# comment` removed), with the line number.
fn run_lines(text: &str) -> Vec<(usize, Vec<String>)> {
    text.lines()
        .enumerate()
        .filter_map(|(i, line)| {
            let rest = line.trim().strip_prefix("cargo run --release -- ")?;
            let rest = rest.split(" #").next().unwrap_or(rest);
            Some((i + 1, rest.split_whitespace().map(String::from).collect()))
        })
        .collect()
}

#[test]
fn the_command_line_definition_is_consistent() {
    Cli::command().debug_assert();
}

#[test]
fn every_command_of_the_readme_is_accepted_by_the_parser() {
    let readme = include_str!("../../README.md");
    let lines = run_lines(readme);
    assert!(
        lines.len() >= 5,
        "the README shows the main commands: found {} `cargo run --release --` lines",
        lines.len()
    );
    for (line, args) in lines {
        let argv = std::iter::once("vmc-twin".to_string()).chain(args.iter().cloned());
        if let Err(e) = Cli::try_parse_from(argv) {
            panic!(
                "README.md line {line}: `{}` is refused: {e}",
                args.join(" ")
            );
        }
    }
}

#[test]
fn a_readme_line_with_an_unknown_flag_would_be_caught() {
    let lines = run_lines("cargo run --release -- campaign --no-such-flag # comment\n");
    assert_eq!(lines.len(), 1);
    let argv = std::iter::once("vmc-twin".to_string()).chain(lines[0].1.iter().cloned());
    assert!(Cli::try_parse_from(argv).is_err());
}

#[test]
fn train_kind_is_one_of_the_model_classes() {
    let cli =
        Cli::try_parse_from(["vmc-twin", "train", "--data", "c.csv", "--kind", "linear"]).unwrap();
    let Command::Train(args) = cli.command else {
        panic!("not train");
    };
    assert_eq!(ModelKind::from(args.kind), ModelKind::Linear);
    let e = Cli::try_parse_from(["vmc-twin", "train", "--data", "c.csv", "--kind", "mlp"])
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("possible values: hybrid, volumetric, linear"),
        "{e}"
    );
}
