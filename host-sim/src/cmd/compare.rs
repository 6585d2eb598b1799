//! `host-sim compare`: every method on every scenario over several seeds, one markdown table per
//! rotation scheme.

use crate::cmd::args::generated_log::SpreadArgs;
use crate::cmd::args::{MethodArg, ScenarioArg, TuningArgs};
use crate::sim::rotation_scheme::RotationScheme;
use crate::sim::scenario::ScenarioKind;
use estimator_core::Method;

/// A comma-separated list of schemes, or `all`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SchemeList(pub Vec<RotationScheme>);

/// Parses `--schemes`: scheme names separated by commas, or `all`.
pub fn parse_schemes(text: &str) -> Result<SchemeList, String> {
    if text.trim() == "all" {
        return Ok(SchemeList(RotationScheme::ALL.to_vec()));
    }
    let names: Vec<&str> = RotationScheme::ALL.iter().map(|s| s.name()).collect();
    text.split(',')
        .map(|n| {
            RotationScheme::parse(n.trim()).ok_or_else(|| {
                format!(
                    "unknown scheme {:?}: expected `all` or some of {}",
                    n.trim(),
                    names.join(", ")
                )
            })
        })
        .collect::<Result<Vec<_>, _>>()
        .map(SchemeList)
}

/// `host-sim compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
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
    #[arg(long, visible_alias = "scheme", value_name = "LIST", value_parser = parse_schemes)]
    schemes: Option<SchemeList>,
    #[command(flatten)]
    tuning: TuningArgs,
    #[command(flatten)]
    spread: SpreadArgs,
}

/// `host-sim compare`: one table per rotation scheme, a line per scenario and method.
pub fn run(a: &CompareArgs) -> anyhow::Result<()> {
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
            heading = crate::study::compare::describe(&draw);
            for &method in &methods {
                rows.push(crate::study::compare::compare_one(
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
        print!("{}", crate::study::compare::format_table(&rows));
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

    #[test]
    fn schemes_parse_as_list_or_all() {
        assert_eq!(
            parse_schemes("all").unwrap().0,
            RotationScheme::ALL.to_vec()
        );
        assert_eq!(
            parse_schemes("reversed, eight-position").unwrap().0,
            vec![RotationScheme::Reversed, RotationScheme::EightPosition]
        );
        assert!(parse_schemes("continuous,spiral")
            .unwrap_err()
            .contains("spiral"));
    }
}
