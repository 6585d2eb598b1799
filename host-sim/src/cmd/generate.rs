//! `host-sim generate`: an attitude log of a scenario and its truth file.

use crate::cmd::args::generated_log::{LogShapeArgs, ScenarioOverrides, ShipMotionArgs};
use crate::cmd::args::ScenarioArg;
use crate::formats::log_csv;
use crate::formats::truth_file::{truth_path, write_truth, Truth};
use crate::sim::recorder::Recorder;
use crate::sim::samples::Samples;
use std::path::{Path, PathBuf};

/// `host-sim generate`.
#[derive(clap::Args, Debug)]
pub struct GenerateArgs {
    /// Which scenario.
    #[arg(long, value_enum)]
    scenario: ScenarioArg,
    /// Seed of the random phases, sway spectrum and noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    overrides: ScenarioOverrides,
    #[command(flatten)]
    shape: LogShapeArgs,
    #[command(flatten)]
    motion: ShipMotionArgs,
    /// Output attitude log (CSV), and its truth file beside it (`FILE.truth.json`); `-` writes
    /// the log to standard output and no truth file.
    #[arg(long, value_name = "FILE.csv")]
    out: PathBuf,
}

/// `host-sim generate`: the log row by row from the generator through the recorder into the file,
/// then its truth file beside it.
pub fn run(a: &GenerateArgs) -> anyhow::Result<()> {
    let mut params = a.overrides.params(a.scenario.into(), a.seed)?;
    a.shape.apply_generated(&mut params)?;
    a.motion.apply(&mut params)?;
    // Row by row from the generator through the recorder into the file: nothing held in memory.
    let mut recorder = Recorder::new(&params.recording, params.seed, params.sample_interval_s);
    let mut written = 0usize;
    let rows = Samples::new(&params)
        .filter_map(|(row, _)| recorder.record(&row))
        .inspect(|_| written += 1);
    log_csv::write_log(&a.out, rows)?;
    if a.out == Path::new(crate::formats::output_file::STDOUT) {
        // The log is on standard output: the summary goes to standard error, and there is no
        // file for the truth to sit beside.
        eprintln!("wrote {written} rows to standard output (no truth file)");
        return Ok(());
    }
    let truth_path = truth_path(&a.out);
    write_truth(&truth_path, &Truth::new(&params))?;
    println!(
        "wrote {} ({written} rows) and {}",
        a.out.display(),
        truth_path.display()
    );
    Ok(())
}
