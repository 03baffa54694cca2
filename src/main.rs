//! `vmc-twin`: the command line over the library. It parses the arguments ([`vmc_twin::cli`]),
//! builds the validated config of the command, runs the use case ([`vmc_twin::commands`]) with
//! stdout as its output, and turns every failure into one line on stderr and a non-zero exit
//! code.

use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

use vmc_twin::cli::{Cli, Command, ControlAction};
use vmc_twin::commands;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of the output went away (`| head`): nothing left to say.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("vmc-twin: error: {}", error_text(&e));
            ExitCode::FAILURE
        }
    }
}

/// Builds the command's config and runs it, printing to stdout.
fn run(command: Command) -> Result<()> {
    let stdout = std::io::stdout();
    let out = &mut stdout.lock();
    match command {
        Command::Run(args) => commands::run::run_target(&args.config()?, out),
        Command::Calibrate(args) => commands::calibrate::calibrate(&args.config()?, out),
        Command::Campaign(args) => commands::campaign::campaign(&args.config()?, out),
        Command::Merge(args) => commands::merge::merge(&args.config(), out),
        Command::Train(args) => commands::train::train(&args.config()?, out),
        Command::FitThermal(args) => commands::thermal::fit_thermal(&args.config()?, out),
        Command::PredictThermal(args) => commands::thermal::predict_thermal(&args.config(), out),
        Command::IdentifyThermal(args) => {
            commands::identify_thermal::identify_thermal(&args.config()?, out)
        }
        Command::SelectSensors(args) => {
            commands::select_sensors_whole_or_shard(&args.config()?, out)
        }
        Command::Check(args) => commands::check::check(&args.config()?, out),
        Command::Lobes(args) => match args.controller_config()? {
            Some(cfg) => commands::control_lobes_whole_or_shard(&cfg, out),
            None => commands::lobes_whole_or_shard(&args.config()?, out),
        },
        Command::Cut(args) => match args.controller_config()? {
            Some(cfg) => commands::control::cut(&cfg, out),
            None => commands::cut::cut(&args.config()?, out),
        },
        Command::ModalFit(args) => commands::modal_fit::modal_fit(&args.config()?, out),
        Command::Control(args) => match args.action {
            ControlAction::Design(d) => commands::control::design(&d.config()?, out),
        },
        Command::Chatter(args) => commands::chatter::chatter(&args.config()?, out),
        Command::Export(args) => commands::export::export(&args.config()?, out),
        Command::Replay(args) => commands::replay::replay(&args.config()?, out),
        Command::Interpret(args) => commands::interpret::interpret(&args.config()?, out),
        Command::ProbeCampaign(args) => {
            commands::probe_campaign::probe_campaign(&args.config()?, out)
        }
        Command::Identify(args) => commands::identify::identify(&args.config()?, out),
        Command::Bench(args) => commands::bench::bench(&args.config()?, out),
    }
}

/// Whether the error comes from writing to a pipe whose reader has closed it.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// The error and its causes, `: `-joined (each error type prints its cause once: either in
/// its message or as its source, not both).
fn error_text(e: &anyhow::Error) -> String {
    format!("{e:#}")
}

#[cfg(test)]
mod tests {
    use super::error_text;
    use vmc_twin::predict::nn::{DataError, NnError};
    use vmc_twin::predict::predictor::PredictError;

    #[test]
    fn a_cause_that_its_parent_already_prints_is_not_repeated() {
        // `PredictError::Net` prints its cause in its message (and does not expose it again).
        let e = anyhow::Error::new(PredictError::Net {
            net: "spindle",
            cause: NnError::Data(DataError::TooLarge {
                what: "targets",
                column: 0,
            }),
        });
        let text = error_text(&e);
        assert!(
            text.starts_with("network `spindle`: targets, column 0: "),
            "{text}"
        );
        assert_eq!(text.matches("targets, column 0").count(), 1, "{text}");
        // Contexts still chain.
        let e = e.context("cal.csv");
        assert!(error_text(&e).starts_with("cal.csv: network `spindle`: "));
    }
}
