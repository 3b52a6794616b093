//! somnurbs: parse the command line, run, print an error chain on one line, exit non-zero on error.

use clap::Parser;
use somnurbs::cli::{Cli, Command, DatasetsAction};
use somnurbs::experiment::{self, spec::Spec, RunContext};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            let msg = format!("{e:#}").replace('\n', " ");
            eprintln!("somnurbs: error: {msg}");
            ExitCode::from(2)
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Run(args) => {
            let spec = Spec::load(&args.spec, args.profile.as_deref())?;
            if args.dry_run {
                for (key, seed) in experiment::dry_run_listing(&spec) {
                    println!("{key}\tseed {seed}");
                }
                return Ok(ExitCode::SUCCESS);
            }
            let jobs = args.jobs.unwrap_or_else(|| std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1));
            if jobs == 0 {
                anyhow::bail!("--jobs must be at least 1");
            }
            let ctx = RunContext {
                out: spec.output_dir(args.out.as_deref()),
                jobs,
                data_dir: experiment::data_dir(args.data_dir.as_deref()),
            };
            let out = experiment::run_spec(&spec, &ctx)?;
            eprintln!("somnurbs: wrote {}", out.join("REPORT.md").display());
            Ok(ExitCode::SUCCESS)
        }
        Command::Compare(args) => {
            experiment::compare::compare(&args)?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Fit(args) => {
            experiment::fit_cmd::fit(&args)?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Datasets(args) => {
            let dir = experiment::data_dir(args.data_dir.as_deref());
            somnurbs::experiment::datasets::datasets(args.action.unwrap_or(DatasetsAction::List), &dir)?;
            Ok(ExitCode::SUCCESS)
        }
    }
}
