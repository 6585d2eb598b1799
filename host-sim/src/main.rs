//! `host-sim`: scenario generator, log replay, reports and plots. `host-sim --help` lists the commands.

use anyhow::Context;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Method, RejectReason};
use host_sim::cli_args::{
    method_label, LogShapeArgs, MethodArg, RecorderArgs, ScenarioArg, ScenarioOverrides,
    SchemeList, ShipMotionArgs, TimingArgs, TuningArgs,
};
use host_sim::exit_status::{RunEnd, HELP as EXIT_HELP};
use host_sim::formats::log_csv::{self, LogError, Truth};
use host_sim::pipeline::{
    default_estimates_path, estimate_log, inputs_of, load_truth, log_name, truth_rows,
    EstimateOptions,
};
use host_sim::replay::{Replay, Step};
use host_sim::report::{format_accuracy, format_honesty, format_rms, Report, TruthRows};
use host_sim::sim::recorder::{recorded_rows, Recorder};
use host_sim::sim::rotation_scheme::RotationScheme;
use host_sim::sim::scenario::{generate, Mismatch, Samples, ScenarioKind};
use host_sim::study::monte_carlo::{format_summary, run_all, summarize, Draw, MC_TIMES_S};
use std::io::Write;
use std::path::{Path, PathBuf};

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
    Generate(GenerateArgs),
    /// Replay an attitude log through the estimator, write the estimates CSV, print the final
    /// estimates, the rejected rows and (with FILE.truth.json beside the log) the accuracy table.
    /// Formats: docs/log-format.md.
    #[command(after_help = EXIT_HELP)]
    Estimate(EstimateArgs),
    /// Generate + estimate with every method + report + plots, in one go.
    #[command(after_help = EXIT_HELP)]
    Run(RunArgs),
    /// Many independent runs in parallel: error statistics at 2000 ... 86400 s.
    #[command(after_help = EXIT_HELP)]
    MonteCarlo(MonteCarloArgs),
    /// Every method on every scenario over several seeds: a markdown table for docs/results.md.
    #[command(after_help = EXIT_HELP)]
    Compare(CompareArgs),
    /// Stream a log through the firmware over its link.
    #[command(after_help = EXIT_HELP)]
    Stream(host_sim::stream::StreamArgs),
    /// How long a board's checkpoint flash lasts: N days of a sea log through the firmware's own
    /// checkpoint store on a model of the board's flash; prints the erases of each sector, the
    /// stalls a save causes and the flash life.
    #[command(after_help = EXIT_HELP)]
    FlashLife(host_sim::flash_life::FlashLifeArgs),
    /// Whether a log's conventions fit the model of eq (2): fits the log as it is and under each
    /// variant of its conventions (rotation, platform, roll or pitch negated, roll and pitch
    /// exchanged, rotation in radians) and tells which fits best, with the residual power of each.
    /// docs/interface.md.
    #[command(after_help = host_sim::commission::HELP)]
    Commission(CommissionArgs),
}

#[derive(clap::Args, Debug)]
struct CommissionArgs {
    /// Attitude log (CSV, plain or gzip, `-` for standard input; format: docs/log-format.md).
    log: PathBuf,
    /// Refuse the log at its first unreadable row (default: skip it, count it, report its line).
    #[arg(long)]
    strict: bool,
    #[command(flatten)]
    tuning: TuningArgs,
    #[command(flatten)]
    timing: TimingArgs,
}

#[derive(clap::Args, Debug)]
struct GenerateArgs {
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

#[derive(clap::Args, Debug)]
struct EstimateArgs {
    /// Attitude log (CSV, plain or gzip, `-` for standard input; format: docs/log-format.md).
    log: PathBuf,
    /// Estimates CSV to write (default: LOG.estimates.csv beside the log; `-`: standard output,
    /// the summary then goes to standard error). Never the log itself.
    #[arg(long, value_name = "EST.csv", allow_hyphen_values = true)]
    out: Option<PathBuf>,
    /// Refuse the log at its first unreadable row (default: skip it, count it, report its line).
    #[arg(long)]
    strict: bool,
    /// Identification method.
    #[arg(long, value_enum, default_value_t = MethodArg::Windowed)]
    method: MethodArg,
    #[command(flatten)]
    tuning: TuningArgs,
    #[command(flatten)]
    timing: TimingArgs,
    /// Average the log's rows (any rate up to 200 Hz: a navigation computer's attitude) into bins
    /// of S s (0.1-10) aligned to multiples of S, and step the estimator once a bin with the
    /// average, stamped at the bin's centre: the estimator's interval is S, and the estimates CSV
    /// has one row per bin (docs/interface.md, "Attitude at the navigation rate").
    #[arg(long, value_name = "S")]
    bin_interval_s: Option<f64>,
    /// Checkpoint the estimator after the rows at these times, drop it and restore a fresh one
    /// from the bytes, as after a power cut right after a save: the estimates go on from the
    /// checkpoint's while the window refills (docs/reliability.md).
    #[arg(long, value_name = "T1,T2,...", value_delimiter = ',')]
    restart_at: Vec<f64>,
    /// Write plots (estimates with 1-sigma, error against the truth, status timeline, attitude
    /// before and after compensation, residuals) and a self-contained report.html into DIR
    /// (created if missing).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
}

#[derive(clap::Args, Debug)]
struct RunArgs {
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
    #[command(flatten)]
    tuning: TuningArgs,
    /// Output directory (default: out/SCENARIO-SEED).
    #[arg(long, value_name = "DIR")]
    out_dir: Option<PathBuf>,
    /// Skip the plots.
    #[arg(long)]
    no_plots: bool,
    /// Write the report of our method's run (its plots and the paper's figures) and a
    /// self-contained report.html into DIR (created if missing).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
}

#[derive(clap::Args, Debug)]
struct MonteCarloArgs {
    /// Which scenario.
    #[arg(long, value_enum)]
    scenario: ScenarioArg,
    /// Number of runs.
    #[arg(long)]
    runs: usize,
    /// Master seed (run i uses a seed derived from it).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Identification method.
    #[arg(long, value_enum, default_value_t = MethodArg::Windowed)]
    method: MethodArg,
    /// Rotation scheme of the RINS.
    #[arg(long, value_enum, default_value_t)]
    scheme: RotationScheme,
    #[command(flatten)]
    tuning: TuningArgs,
    #[command(flatten)]
    spread: SpreadArgs,
    /// Write the summary as JSON (with the scenario, method, seeds and command).
    #[arg(long, value_name = "summary.json")]
    out: Option<PathBuf>,
    /// Write the error percentiles and 2-sigma coverage over time (PNG) and a self-contained
    /// report.html into DIR (created if missing).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

/// How Monte Carlo and compare runs are drawn beyond the scenario's defaults.
#[derive(clap::Args, Debug, Clone)]
struct SpreadArgs {
    /// Log length, s (default: the scenario's).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    /// Latitudes spread uniformly in MIN,MAX deg (default: the scenario's).
    #[arg(long, value_name = "MIN,MAX", allow_hyphen_values = true, value_parser = host_sim::cli_args::parse_list::<2>)]
    lat_range: Option<[f64; 2]>,
    /// Roll sway amplitude uniform between the scenario's and this, deg (rougher sea).
    #[arg(long, value_name = "DEG")]
    max_roll_deg: Option<f64>,
    /// Model mismatch: relative error of the true rotation period (0.005 = 0.5 % slower).
    #[arg(
        long,
        value_name = "FRACTION",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    period_error: f64,
    /// Model mismatch: white jitter on the rotation angle, 1-sigma deg.
    #[arg(long, value_name = "DEG", default_value_t = 0.0)]
    rotation_jitter_deg: f64,
    /// Model mismatch: linear drift of every installation error, arcsec per day.
    #[arg(
        long,
        value_name = "ARCSEC",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    error_drift_arcsec_per_day: f64,
    /// Model mismatch: frequency error of the low-frequency errors relative to the Earth rate (0.2 = 20 % faster).
    #[arg(
        long,
        value_name = "FRACTION",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    lowfreq_rate_error: f64,
    /// Model mismatch: coloured (Gauss-Markov, 60 s) attitude noise, 1-sigma arcsec.
    #[arg(long, value_name = "ARCSEC", default_value_t = 0.0)]
    coloured_noise_arcsec: f64,
    #[command(flatten)]
    motion: ShipMotionArgs,
    #[command(flatten)]
    timing: TimingArgs,
    #[command(flatten)]
    recorder: RecorderArgs,
}

impl SpreadArgs {
    fn draw(&self, kind: ScenarioKind, scheme: RotationScheme, seed: u64) -> anyhow::Result<Draw> {
        self.timing.check()?;
        let mut d = Draw::new(kind, seed);
        d.scheme = scheme;
        d.rotation_period_s = self.timing.rotation_period;
        d.sample_interval_s = self.timing.sample_interval;
        d.recorder = self.recorder.settings();
        if let Some(v) = self.lat_range {
            anyhow::ensure!(
                v[0] <= v[1] && v[0] > -90.0 && v[1] < 90.0,
                "--lat-range needs MIN,MAX inside (-90, 90) with MIN <= MAX"
            );
            d.lat_range_deg = Some((v[0], v[1]));
        }
        if let Some(m) = self.max_roll_deg {
            anyhow::ensure!(
                m.is_finite() && m > 0.0 && m < 90.0,
                "--max-roll-deg must be inside (0, 90)"
            );
            d.max_roll_deg = Some(m);
        }
        if let Some(t) = self.duration {
            d.duration_s = Some(host_sim::cli_args::check_duration(t)?);
        }
        let finite = [
            self.period_error,
            self.rotation_jitter_deg,
            self.error_drift_arcsec_per_day,
            self.lowfreq_rate_error,
            self.coloured_noise_arcsec,
        ];
        anyhow::ensure!(
            finite.iter().all(|v| v.is_finite()),
            "mismatch switches must be finite"
        );
        anyhow::ensure!(self.period_error > -1.0, "--period-error must be above -1");
        anyhow::ensure!(
            self.rotation_jitter_deg >= 0.0 && self.coloured_noise_arcsec >= 0.0,
            "noise levels must be >= 0"
        );
        d.mismatch = Mismatch {
            rotation_period_error: self.period_error,
            rotation_jitter_deg: self.rotation_jitter_deg,
            error_drift_arcsec_per_day: self.error_drift_arcsec_per_day,
            low_frequency_rate_error: self.lowfreq_rate_error,
            coloured_noise_arcsec: self.coloured_noise_arcsec,
            heel_in_turns_deg: self.motion.heel_in_turns_deg()?,
            ..Mismatch::default()
        };
        self.motion.interface.apply(&mut d.mismatch)?;
        d.ship_motion = self.motion.settings()?;
        d.check()?;
        Ok(d)
    }
}

#[derive(clap::Args, Debug)]
struct CompareArgs {
    /// Seeds (runs) per scenario and method.
    #[arg(long, default_value_t = 5)]
    seeds: usize,
    /// Master seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Scenarios (default: all).
    #[arg(long, value_enum, value_delimiter = ',')]
    scenarios: Vec<ScenarioArg>,
    /// Methods (default: all).
    #[arg(long, value_enum, value_delimiter = ',')]
    methods: Vec<MethodArg>,
    /// Rotation schemes, one table each: comma-separated names (continuous, reversed,
    /// reciprocating, four-position, eight-position) or `all` (default: continuous).
    #[arg(long, visible_alias = "scheme", value_name = "LIST", value_parser = host_sim::cli_args::parse_schemes)]
    schemes: Option<SchemeList>,
    #[command(flatten)]
    tuning: TuningArgs,
    #[command(flatten)]
    spread: SpreadArgs,
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
    let matches = host_sim::cli_args::accept_negative_numbers(Cli::command()).get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    let result = match &cli.command {
        Command::Generate(a) => cmd_generate(a),
        Command::Estimate(a) => cmd_estimate(a),
        Command::Run(a) => cmd_run(a),
        Command::MonteCarlo(a) => cmd_monte_carlo(a),
        Command::Compare(a) => cmd_compare(a),
        Command::Stream(a) => host_sim::stream::run(a),
        Command::FlashLife(a) => host_sim::flash_life::run(a),
        Command::Commission(a) => cmd_commission(a),
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

fn cmd_generate(a: &GenerateArgs) -> anyhow::Result<()> {
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
    if a.out == Path::new(host_sim::formats::output_file::STDOUT) {
        // The log is on standard output: the summary goes to standard error, and there is no
        // file for the truth to sit beside.
        eprintln!("wrote {written} rows to standard output (no truth file)");
        return Ok(());
    }
    let truth_path = log_csv::truth_path(&a.out);
    log_csv::write_truth(&truth_path, &Truth::new(&params))?;
    println!(
        "wrote {} ({written} rows) and {}",
        a.out.display(),
        truth_path.display()
    );
    Ok(())
}

/// Tells each unreadable row skipped (the first few) on standard error.
fn warn_row(e: &LogError) {
    eprintln!("warning: {e} (row skipped)");
}

fn cmd_commission(a: &CommissionArgs) -> anyhow::Result<()> {
    use host_sim::commission::{fit_variants, format_report, run_end, verdict, Variant};
    a.timing.check()?;
    let config = a.timing.pin(a.tuning.checked_config(Method::Windowed)?);
    let fits = fit_variants(&a.log, config, a.strict, &Variant::ALL)?;
    if let Some(as_is) = fits.first() {
        for e in &as_is.replay.unreadable.first {
            warn_row(e);
        }
    }
    let verdict = verdict(&fits);
    let mut out = std::io::stdout().lock();
    write!(out, "{}", format_report(&log_name(&a.log), &fits, &verdict))?;
    out.flush()?;
    run_end(&fits, &verdict)?;
    Ok(())
}

fn cmd_estimate(a: &EstimateArgs) -> anyhow::Result<()> {
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| default_estimates_path(&a.log));
    let method: Method = a.method.into();
    let mut restart_at = a.restart_at.clone();
    anyhow::ensure!(
        restart_at.iter().all(|t| t.is_finite()),
        "--restart-at needs finite times"
    );
    restart_at.sort_by(f64::total_cmp);
    a.timing.check()?;
    if let Some(bin_s) = a.bin_interval_s {
        let (lo, hi) = estimator_core::binning::BIN_INTERVAL_RANGE_S;
        anyhow::ensure!(
            bin_s.is_finite() && (lo..=hi).contains(&bin_s),
            "--bin-interval-s must be between {lo} and {hi} s, got {bin_s}"
        );
        if let Some(d) = a.timing.sample_interval {
            anyhow::ensure!(
                d == bin_s,
                "--sample-interval {d} contradicts --bin-interval-s {bin_s}: the estimator's interval is the bins'; leave --sample-interval out"
            );
        }
    }
    if let Some(dir) = &a.report {
        host_sim::report::pages::check_dir(dir, &inputs_of(&a.log))?;
    }
    let options = EstimateOptions {
        config: a.timing.pin(a.tuning.checked_config(method)?),
        restart_at_s: restart_at.clone(),
        strict: a.strict,
        timeline: a.report.is_some(),
        bin_interval_s: a.bin_interval_s,
    };
    let truth = load_truth(&a.log, &mut |w| eprintln!("warning: {w}"));
    let rows = truth
        .as_ref()
        .map(|t| truth_rows(&t.file, t.generated.as_ref()));
    let est = estimate_log(&a.log, &out, &options, rows, &mut warn_row, &mut |_| {})?;
    // The summary goes where the estimates do not.
    let mut info: Box<dyn Write> = if log_csv::is_stdio(&out) {
        Box::new(std::io::stderr())
    } else {
        Box::new(std::io::stdout().lock())
    };
    if !restart_at.is_empty() {
        writeln!(
            info,
            "restarted from a checkpoint after the rows at {restart_at:?} s"
        )?;
    }
    let out_name = if log_csv::is_stdio(&out) {
        "standard output".to_string()
    } else {
        out.display().to_string()
    };
    print_summary(&mut info, &a.log, method, &est.replay, &out_name)?;
    if let Some(rep) = &est.report {
        print_report(&mut info, method, rep)?;
    }
    if let (Some(dir), Some(tl)) = (&a.report, &est.timeline) {
        let page = host_sim::report::pages::write_replay_report(
            dir,
            &log_name(&a.log),
            method_label(method),
            &est.replay,
            est.report.as_ref(),
            tl,
            vec![],
        )?;
        writeln!(info, "report in {}", page.display())?;
    }
    info.flush()?;
    no_estimate_end(&est.replay)
}

/// The end of a replay without an estimate (exit status 4, the reason on standard error).
fn no_estimate_end(r: &Replay) -> anyhow::Result<()> {
    if r.final_estimate.is_some() {
        return Ok(());
    }
    let reason = match (r.holdup, r.binning) {
        (Some(h), _) => format!("{h} at the end of the log"),
        (None, Some(b)) => format!(
            "no bin accepted ({} rejected; {} rows refused by the binning)",
            r.rejected.total(),
            b.refused.total()
        ),
        (None, None) => format!("no row accepted ({} rejected)", r.rejected.total()),
    };
    Err(RunEnd::NoEstimate { reason }.into())
}

fn print_summary(
    w: &mut dyn Write,
    log: &Path,
    method: Method,
    r: &Replay,
    out: &str,
) -> std::io::Result<()> {
    let log = if log_csv::is_stdio(log) {
        "standard input".to_string()
    } else {
        log.display().to_string()
    };
    let c = &r.counters;
    // With binning the estimator stepped once a bin (the rows are counted on the next line).
    let rows = if r.binning.is_some() { "bins" } else { "rows" };
    writeln!(
        w,
        "{log}: method {}: {} {rows}, {} accepted, {} filled (lost samples interpolated), {} window restarts, {} clock steps; estimates in {out}",
        method.name(),
        r.rows,
        c.accepted,
        c.filled,
        c.window_restarts,
        c.clock_steps
    )?;
    if let Some(b) = &r.binning {
        writeln!(w, "  binned: {}", b.describe())?;
    }
    writeln!(w, "  {}", host_sim::replay::pattern_summary(r))?;
    for change in &r.error_changes {
        writeln!(w, "  {}", host_sim::replay::describe_error_change(change))?;
    }
    writeln!(
        w,
        "  final status: {}",
        r.final_status
            .map_or("none (no row accepted)", |s| s.name())
    )?;
    writeln!(w, "  {}", host_sim::replay::describe_health(&r.health))?;
    if let Some(limit) = host_sim::replay::describe_limit(&r.health) {
        writeln!(w, "  {limit}")?;
    }
    match (r.final_estimate, r.holdup) {
        (Some(e), holdup) => {
            for i in 0..4 {
                writeln!(
                    w,
                    "  x{} = {:+.3} arcsec (1-sigma {:.3})",
                    i + 1,
                    rad_to_arcsec(e.x_rad[i] as f64),
                    rad_to_arcsec(e.sigma_rad[i] as f64)
                )?;
            }
            if let Some(h) = holdup {
                writeln!(w, "  estimates frozen: {h}")?;
            }
        }
        (None, Some(h)) => writeln!(w, "  no estimate: {h}")?,
        (None, None) => writeln!(w, "  no estimate: no row accepted")?,
    }
    let reasons: Vec<String> = RejectReason::ALL
        .iter()
        .map(|&reason| format!("{} {}", reason.name(), r.rejected.of(reason)))
        .collect();
    writeln!(
        w,
        "  rejected {rows}: {} ({})",
        r.rejected.total(),
        reasons.join(", ")
    )?;
    if r.unreadable.skipped > 0 {
        let lines: Vec<String> = r
            .unreadable
            .first
            .iter()
            .map(|e| e.line.to_string())
            .collect();
        let more = if r.unreadable.skipped as usize > lines.len() {
            ", ..."
        } else {
            ""
        };
        writeln!(
            w,
            "  unreadable rows skipped: {} (lines {}{more}; --strict refuses such a log)",
            r.unreadable.skipped,
            lines.join(", ")
        )?;
    }
    Ok(())
}

fn print_report(w: &mut dyn Write, method: Method, rep: &Report) -> std::io::Result<()> {
    writeln!(w, "\naccuracy against the truth, {}:", method_label(method))?;
    write!(w, "{}", format_accuracy(&rep.accuracy))?;
    write!(w, "{}", format_honesty(&rep.accuracy.honesty))?;
    if let Some(r) = &rep.rms_from_first_estimate {
        write!(w, "{}", format_rms("from the first estimate", r))?;
    }
    if let Some(r) = &rep.rms_last_quarter {
        write!(w, "{}", format_rms("last quarter of the run", r))?;
    }
    Ok(())
}

fn cmd_run(a: &RunArgs) -> anyhow::Result<()> {
    let mut params = a.overrides.params(a.scenario.into(), a.seed)?;
    a.shape.apply(&mut params)?;
    a.motion.apply(&mut params)?;
    let dir = a.out_dir.clone().unwrap_or_else(|| {
        PathBuf::from(format!("out/{}-{}", params.scenario.name(), params.seed))
    });
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("{}:0: cannot create directory", dir.display()))?;
    let log = dir.join(format!("{}.csv", params.scenario.name()));
    if let Some(report_dir) = &a.report {
        host_sim::report::pages::check_dir(report_dir, &inputs_of(&log))?;
    }
    let generated = generate(&params);
    let logged = recorded_rows(
        &params.recording,
        params.seed,
        params.sample_interval_s,
        &generated.rows,
    );
    log_csv::write_log(&log, &logged)?;
    let truth = Truth::new(&params);
    log_csv::write_truth(&log_csv::truth_path(&log), &truth)?;
    println!(
        "wrote {} ({} rows) and its truth file",
        log.display(),
        logged.len()
    );
    let mut runs: Vec<(Method, Vec<Step>)> = Vec::new();
    let mut reports: Vec<(Method, Report)> = Vec::new();
    let mut ours = None;
    let mut stdout = std::io::stdout().lock();
    for method in [Method::Windowed, Method::Paper, Method::Traditional] {
        let out = dir.join(format!(
            "{}.estimates.{}.csv",
            params.scenario.name(),
            method.name()
        ));
        let timeline = a.report.is_some() && method == Method::Windowed;
        let options = EstimateOptions {
            config: a.tuning.config(method),
            restart_at_s: vec![],
            strict: true,
            timeline,
            bin_interval_s: None,
        };
        let mut steps = Vec::with_capacity(generated.rows.len());
        let rows = TruthRows::Generated {
            rows: &generated.rows,
            truth: &generated.truth,
            time_offset_s: params.recording.time_offset_s,
            errors_step_at_s: params.errors_step.map(|step| step.at_s),
        };
        let est = estimate_log(
            &log,
            &out,
            &options,
            Some(rows),
            &mut warn_row,
            &mut |view| {
                steps.push(Step {
                    time_s: view.line.row.time_s,
                    result: *view.result,
                })
            },
        )?;
        print_summary(
            &mut stdout,
            &log,
            method,
            &est.replay,
            &out.display().to_string(),
        )?;
        let rep = est
            .report
            .clone()
            .context("a report against the generated truth")?;
        print_report(&mut stdout, method, &rep)?;
        writeln!(stdout)?;
        runs.push((method, steps));
        reports.push((method, rep));
        if timeline {
            ours = Some(est);
        }
    }
    drop(stdout);
    println!(
        "side by side ({} scenario, seed {}):",
        params.scenario.name(),
        params.seed
    );
    let side: Vec<(&str, &Report)> = reports.iter().map(|(m, r)| (method_label(*m), r)).collect();
    let side_by_side = host_sim::report::format_side_by_side(&side);
    print!("{side_by_side}");
    // The figures index the truth by sample instant: stamps moved back onto it.
    let grid = |t: f64| {
        params
            .recording
            .sample_time_s(t, params.sample_interval_s)
            .unwrap_or(f64::NAN)
    };
    let on_grid: Vec<(Method, Vec<Step>)> = runs
        .iter()
        .map(|(m, steps)| {
            let moved = steps
                .iter()
                .map(|s| {
                    let mut s = *s;
                    s.time_s = grid(s.time_s);
                    if let Ok(o) = &mut s.result {
                        o.time_s = grid(o.time_s);
                    }
                    s
                })
                .collect();
            (*m, moved)
        })
        .collect();
    let steps: Vec<(&str, &[Step])> = on_grid
        .iter()
        .map(|(m, s)| (m.name(), s.as_slice()))
        .collect();
    let window = (params.rotation_period_s / params.sample_interval_s).round() as usize;
    let grid_rows: Vec<_> = logged
        .iter()
        .map(|r| host_sim::sim::scenario::Row {
            time_s: grid(r.time_s),
            ..*r
        })
        .collect();
    let paper_figures = |into: &Path| {
        host_sim::report::figures::write_figures(
            into,
            &grid_rows,
            &generated.truth,
            &params.errors_arcsec,
            params.sample_interval_s,
            window,
            &steps,
        )
    };
    if !a.no_plots {
        println!("plots:");
        for f in paper_figures(&dir)? {
            println!("  {}", f.display());
        }
    }
    if let (Some(report_dir), Some(est)) = (&a.report, &ours) {
        use host_sim::report::html::{Block, Figure, Section};
        host_sim::report::pages::create_dir(report_dir)?;
        let figures = paper_figures(report_dir)?;
        let mut paper = Section::new("The paper's figures, from this run");
        for path in figures {
            let caption = host_sim::report::figures::caption_of(&path);
            paper = paper.with(Block::Figure(Figure { path, caption }));
        }
        let extra = vec![
            Section::new("The three methods side by side").with(Block::Code(side_by_side)),
            paper,
        ];
        let tl = est.timeline.as_ref().context("our method's timeline")?;
        let page = host_sim::report::pages::write_replay_report(
            report_dir,
            &log.display().to_string(),
            method_label(Method::Windowed),
            &est.replay,
            est.report.as_ref(),
            tl,
            extra,
        )?;
        println!("report in {}", page.display());
    }
    Ok(())
}

fn thread_pool(threads: Option<usize>) -> anyhow::Result<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        anyhow::ensure!(n >= 1, "--threads must be at least 1");
        b = b.num_threads(n);
    }
    Ok(b.build()?)
}

/// A progress bar of `len` steps on standard error when it is a terminal (hidden otherwise).
fn progress_bar(len: u64, unit: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template(&format!(
        "{{elapsed_precise}} [{{bar:30}}] {{pos}}/{{len}} {unit}, {{eta}} left"
    )) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

fn cmd_monte_carlo(a: &MonteCarloArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.runs >= 1, "--runs must be at least 1");
    let draw = a.spread.draw(a.scenario.into(), a.scheme, a.seed)?;
    draw.check_duration()?;
    let method: Method = a.method.into();
    let config = a.tuning.config(method);
    if let Some(dir) = &a.report {
        host_sim::report::pages::create_dir(dir)?;
    }
    let duration_s = draw.params(0).duration_s;
    let times = host_sim::study::monte_carlo::tracked_times_s(duration_s);
    let bar = progress_bar(a.runs as u64, "runs");
    let start = std::time::Instant::now();
    let pool = thread_pool(a.threads)?;
    let results = pool.install(|| run_all(&draw, config, a.runs, &times, &|| bar.inc(1)))?;
    bar.finish_and_clear();
    let elapsed = start.elapsed().as_secs_f64();
    let over_time = summarize(&results);
    let summary = over_time.at_times(&MC_TIMES_S);
    let description = host_sim::study::compare::describe(&draw);
    println!(
        "monte carlo: scenario {} ({description}), method {}, {} runs of {duration_s:.0} s in {elapsed:.1} s ({} threads)",
        draw.kind.name(),
        method.name(),
        a.runs,
        pool.current_num_threads()
    );
    println!("absolute error |x_hat - x| over runs, arcsec:");
    let honesty = host_sim::study::monte_carlo::pool_honesty(&results);
    let table = format_summary(&summary)
        + &host_sim::study::monte_carlo::format_honesty_over_runs(&honesty, results.len());
    print!("{table}");
    let command = host_sim::report::html::command_line();
    if let Some(out) = &a.out {
        let json = host_sim::study::monte_carlo::StudyJson {
            scenario: draw.kind.name().to_string(),
            method: method.name().to_string(),
            scheme: draw.scheme.name().to_string(),
            description: description.clone(),
            duration_s,
            master_seed: draw.seed,
            run_seeds: (0..a.runs).map(|i| draw.run_seed(i)).collect(),
            command: command.clone(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            summary: summary.clone(),
            over_time: over_time.clone(),
            honesty,
        };
        let text = serde_json::to_string_pretty(&json)?;
        host_sim::formats::output_file::write_bytes(out, (text + "\n").as_bytes())?;
        println!("summary in {}", out.display());
    }
    if let Some(dir) = &a.report {
        let facts = vec![
            ("scenario".to_string(), draw.kind.name().to_string()),
            ("draw".into(), description.clone()),
            ("method".into(), method_label(method).to_string()),
            ("rotation scheme".into(), draw.scheme.name().to_string()),
            ("runs".into(), format!("{} of {duration_s:.0} s", a.runs)),
            ("master seed".into(), draw.seed.to_string()),
            (
                "wall time".into(),
                format!("{elapsed:.1} s on {} threads", pool.current_num_threads()),
            ),
        ];
        let study = host_sim::report::pages::MonteCarloStudy {
            description,
            facts,
            summary: &over_time,
            table,
        };
        let page = host_sim::report::pages::write_monte_carlo_report(dir, &study)?;
        println!("report in {}", page.display());
    }
    if summary.no_estimate() {
        return Err(RunEnd::NoEstimate {
            reason: format!(
                "no run reached an estimate by the table's times ({} s and after)",
                MC_TIMES_S[0]
            ),
        }
        .into());
    }
    Ok(())
}

fn cmd_compare(a: &CompareArgs) -> anyhow::Result<()> {
    anyhow::ensure!(a.seeds >= 1, "--seeds must be at least 1");
    let scenarios: Vec<ScenarioKind> = if a.scenarios.is_empty() {
        vec![
            ScenarioKind::Paper,
            ScenarioKind::Turntable,
            ScenarioKind::Sea,
        ]
    } else {
        a.scenarios.iter().map(|s| (*s).into()).collect()
    };
    let methods: Vec<Method> = if a.methods.is_empty() {
        vec![Method::Paper, Method::Windowed, Method::Traditional]
    } else {
        a.methods.iter().map(|m| (*m).into()).collect()
    };
    let schemes = a
        .schemes
        .as_ref()
        .map_or(vec![RotationScheme::Continuous], |l| l.0.clone());
    let start = std::time::Instant::now();
    for (i, &scheme) in schemes.iter().enumerate() {
        let mut rows = Vec::new();
        let mut heading = String::new();
        for &kind in &scenarios {
            let draw = a.spread.draw(kind, scheme, a.seed)?;
            heading = host_sim::study::compare::describe(&draw);
            for &method in &methods {
                rows.push(host_sim::study::compare::compare_one(
                    &draw,
                    a.tuning.config(method),
                    a.seeds,
                )?);
            }
        }
        if i > 0 {
            println!();
        }
        println!("{heading}\n");
        print!("{}", host_sim::study::compare::format_table(&rows));
    }
    let command: Vec<String> = std::env::args().skip(1).collect();
    println!(
        "\n{} seeds per line; errors of a few hundred arcsec drawn per seed; `host-sim {}` ({:.0} s)",
        a.seeds,
        command.join(" "),
        start.elapsed().as_secs_f64()
    );
    Ok(())
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
        let mut cmd = host_sim::cli_args::accept_negative_numbers(Cli::command());
        cmd.build();
        walk(&cmd, &mut missing);
        assert!(missing.is_empty(), "{missing:?}");
        assert!(cmd.get_subcommands().count() >= 6);
    }
}
