//! `host-sim`: scenario generator, log replay, reports and plots. `host-sim --help` lists the commands.

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use host_sim::cmd;
use host_sim::exit_status::HELP as EXIT_HELP;

#[derive(Parser, Debug)]
#[command(
    name = "host-sim",
    version,
    about = "RINS installation-error estimator: scenarios, log replay, reports and plots"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Generate an attitude log and its truth file (FILE.truth.json beside it).
    #[command(after_help = EXIT_HELP)]
    Generate(cmd::generate::GenerateArgs),
    /// Replay an attitude log through the estimator, write the estimates CSV, print the final
    /// estimates, the rejected rows and (with FILE.truth.json beside the log) the accuracy table.
    /// Formats: docs/log-format.md.
    #[command(after_help = EXIT_HELP)]
    Estimate(cmd::estimate::EstimateArgs),
    /// Generate + estimate with every method + report + plots, in one go.
    #[command(after_help = EXIT_HELP)]
    Run(cmd::run::RunArgs),
    /// Many independent runs in parallel: error statistics at 2000 ... 86400 s.
    #[command(after_help = EXIT_HELP)]
    MonteCarlo(cmd::monte_carlo::MonteCarloArgs),
    /// Every method on every scenario over several seeds: a markdown table for docs/results.md.
    #[command(after_help = EXIT_HELP)]
    Compare(cmd::compare::CompareArgs),
    /// Stream a log through the firmware over its link.
    #[command(after_help = EXIT_HELP)]
    Stream(cmd::stream::StreamArgs),
    /// How long a board's checkpoint flash lasts: N days of a sea log through the firmware's own
    /// checkpoint store on a model of the board's flash; prints the erases of each sector, the
    /// stalls a save causes and the flash life.
    #[command(after_help = EXIT_HELP)]
    FlashLife(cmd::flash_life::FlashLifeArgs),
    /// Whether a log's conventions fit the model of eq (2): fits the log as it is and under each
    /// variant of its conventions (rotation, platform, roll or pitch negated, roll and pitch
    /// exchanged, rotation in radians) and tells which fits best, with the residual power of each.
    /// docs/interface.md.
    #[command(after_help = cmd::commission::HELP)]
    Commission(cmd::commission::CommissionArgs),
}

/// Whether an error is a closed pipe on the way out (`host-sim estimate ... | head`).
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            || c.downcast_ref::<host_sim::replay::ReplayError>()
                .is_some_and(|r| matches!(r, host_sim::replay::ReplayError::Write(io) if io.kind() == std::io::ErrorKind::BrokenPipe))
    })
}

fn main() {
    let matches = cmd::args::accept_negative_numbers(Cli::command()).get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    let result = match &cli.command {
        Command::Generate(a) => cmd::generate::run(a),
        Command::Estimate(a) => cmd::estimate::run(a),
        Command::Run(a) => cmd::run::run(a),
        Command::MonteCarlo(a) => cmd::monte_carlo::run(a),
        Command::Compare(a) => cmd::compare::run(a),
        Command::Stream(a) => cmd::stream::run(a),
        Command::FlashLife(a) => cmd::flash_life::run(a),
        Command::Commission(a) => cmd::commission::run(a),
    };
    if let Err(e) = result {
        // The reader went away: stop quietly, as command-line tools do.
        if is_broken_pipe(&e) {
            std::process::exit(0);
        }
        let (message, status) = host_sim::exit_status::report(&e);
        eprintln!("{message}");
        std::process::exit(status);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every option that takes a value, of every command, takes a negative number too (the
    /// option's own check then names what is wrong with it).
    #[test]
    fn every_option_takes_a_negative_number() {
        fn walk(cmd: &clap::Command, missing: &mut Vec<String>) {
            for arg in cmd.get_arguments() {
                if arg.get_action().takes_values()
                    && !arg.is_positional()
                    && !arg.is_allow_negative_numbers_set()
                {
                    missing.push(format!("{} --{}", cmd.get_name(), arg.get_id()));
                }
            }
            cmd.get_subcommands().for_each(|c| walk(c, missing));
        }
        let mut missing = Vec::new();
        let mut cmd = cmd::args::accept_negative_numbers(Cli::command());
        cmd.build();
        walk(&cmd, &mut missing);
        assert!(missing.is_empty(), "{missing:?}");
        assert!(cmd.get_subcommands().count() >= 6);
    }
}
