//! The commands behind the command line: each subcommand's arguments to the library's calls, the
//! exit code, and errors printed on one line.

use super::{
    Cli, Command, CompareArgs, DatasetsAction, DriftArgs, FitArgs, ReproduceArgs, RunArgs,
};
use crate::experiment::{self, log::Shard, spec::CliOverrides, RunContext};
use crate::families::{Loaded, Section};
use clap::Parser;
use std::process::ExitCode;

/// The program: parse the command line, run the command, print an error chain on one line and
/// exit 2 on error (1 for drift found, 0 otherwise).
pub fn main() -> ExitCode {
    // Output piped into a reader that stops early (`somnurbs drift ... | head`) ends the program
    // quietly, as for other Unix tools, instead of a panic in println!.
    #[cfg(unix)]
    // SAFETY: restoring the default action of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("somnurbs: error: {}", crate::io::one_line(&format!("{e:#}")));
            ExitCode::from(2)
        }
    }
}

/// Worker threads: the flag, else every core; at most a few per core (a note says when the flag
/// was cut down).
fn jobs(flag: Option<usize>) -> anyhow::Result<usize> {
    let cpus = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let (jobs, note) = experiment::limits::jobs(flag, cpus)?;
    if let Some(note) = note {
        eprintln!("somnurbs: note: {note}");
    }
    Ok(jobs)
}

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    crate::simd::simd()?;
    match cli.command {
        Command::Run(args) => run_spec(&args),
        Command::Drift(args) => drift(&args),
        Command::Export(args) => {
            let data = experiment::data_dir(args.data_dir.as_deref());
            let request = crate::families::optimise::export::Request {
                results: args.results,
                cell: args.cell,
                variant: args.variant,
                start: args.start,
                out: args.out,
                frame: args.frame,
                units: args.units,
                samples: args.samples,
                allow_excursion: args.allow_excursion,
            };
            Ok(exit_code(crate::families::optimise::export::export(&request, data)?))
        }
        Command::Report(args) => {
            let data = experiment::data_dir(args.data_dir.as_deref());
            let out = experiment::report::<Section>(&args.results, data, jobs(args.jobs)?)?;
            eprintln!(
                "somnurbs: {} is whole: every file its records give is in place",
                out.display()
            );
            Ok(ExitCode::SUCCESS)
        }
        Command::Merge(args) => {
            let ctx = RunContext {
                page: true,
                ..RunContext::new(
                    args.out.clone(),
                    jobs(args.jobs)?,
                    experiment::data_dir(args.data_dir.as_deref()),
                )
            };
            crate::io::outdir::require_folder_outside_results(&args.out, "--out")?;
            let out = experiment::merge::<Section>(&args.shards, &ctx)?;
            eprintln!(
                "somnurbs: merged {} shards into {} and {}",
                args.shards.len(),
                out.join("REPORT.md").display(),
                out.join(crate::report::html::FILE).display()
            );
            Ok(ExitCode::SUCCESS)
        }
        Command::Reproduce(args) => reproduce(&args),
        Command::Compare(args) => {
            crate::families::optimise::compare::compare(&args.into())?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Fit(args) => Ok(exit_code(crate::families::fit::command::fit(&args.into())?)),
        Command::Datasets(args) => {
            let dir = experiment::data_dir(args.data_dir.as_deref());
            let action = args.action.unwrap_or(DatasetsAction::List);
            experiment::datasets::datasets(action.into(), &dir)?;
            Ok(ExitCode::SUCCESS)
        }
    }
}

// The command line's arguments as the families and the engine take them (clap stays in `cli`).

impl From<CompareArgs> for crate::families::optimise::compare::Request {
    fn from(a: CompareArgs) -> Self {
        Self {
            results: a.results,
            alpha: a.alpha,
            rope: a.rope,
            bayes_samples: a.bayes_samples,
            out: a.out,
            external: a.external,
        }
    }
}

impl From<FitArgs> for crate::families::fit::command::Request {
    fn from(a: FitArgs) -> Self {
        Self {
            grid: a.grid,
            cn: a.cn,
            param: a.param,
            approach: a.approach,
            out: a.out,
            samples: a.samples,
            knots: a.knots,
            error_a: a.error_a,
            fairness: a.fairness,
            frame: a.frame,
            units: a.units,
            allow_excursion: a.allow_excursion,
        }
    }
}

/// A command that writes surfaces: 0 when it wrote them, 2 when it refused (its message printed).
fn exit_code(outcome: crate::families::fit::command::Outcome) -> ExitCode {
    match outcome {
        crate::families::fit::command::Outcome::Written => ExitCode::SUCCESS,
        crate::families::fit::command::Outcome::Refused => ExitCode::from(2),
    }
}

impl From<DatasetsAction> for experiment::datasets::Action {
    fn from(a: DatasetsAction) -> Self {
        match a {
            DatasetsAction::List => Self::List,
            DatasetsAction::Show { name } => Self::Show { name },
            DatasetsAction::Export { name, file } => Self::Export { name, file },
        }
    }
}

/// `somnurbs run`: one spec (or its variants) into one folder, or one shard of it.
fn run_spec(args: &RunArgs) -> anyhow::Result<ExitCode> {
    let cli = CliOverrides { set: args.set.clone(), sweep: args.sweep.clone() };
    let variants = Loaded::load_variants(&args.spec, args.profile.as_deref(), &cli)?;
    let spec = &variants[0].spec;
    let data_dir = experiment::data_dir(args.data_dir.as_deref());
    if args.dry_run {
        let out = spec.output_dir(args.out.as_deref());
        experiment::preflight(&variants[0], &RunContext::new(out, 1, data_dir))?;
        for (key, seed) in variants.iter().flat_map(experiment::dry_run_listing) {
            println!("{key}\tseed {seed}");
        }
        return Ok(ExitCode::SUCCESS);
    }
    let shard = args.shard.as_deref().map(Shard::parse).transpose()?;
    let out = spec.output_dir(args.out.as_deref());
    crate::io::outdir::require_folder_outside_results(&out, "output folder")?;
    let ctx = RunContext {
        resume: args.resume,
        shard,
        page: true,
        reuse: reuse_folders(&args.reuse)?,
        ..RunContext::new(out, jobs(args.jobs)?, data_dir)
    };
    super::interrupt::on_sigint(&run_resume_command(args, &ctx.out));
    let out = experiment::run_variants(&variants, &ctx)?;
    match shard {
        Some(s) => eprintln!(
            "somnurbs: wrote shard {s} to {} (combine the shards with `somnurbs merge`)",
            out.display()
        ),
        None => eprintln!(
            "somnurbs: {} and {} are in place",
            out.join("REPORT.md").display(),
            out.join(crate::report::html::FILE).display()
        ),
    }
    Ok(ExitCode::SUCCESS)
}

/// The command that continues an interrupted `somnurbs run` (the SIGINT line).
fn run_resume_command(args: &RunArgs, out: &std::path::Path) -> String {
    use super::interrupt::quote;
    let mut words = vec!["somnurbs".to_string(), "run".into(), quote(&args.spec.to_string_lossy())];
    let mut flag = |name: &str, value: &str| words.push(format!("--{name} {}", quote(value)));
    if let Some(p) = &args.profile {
        flag("profile", p);
    }
    for s in &args.set {
        flag("set", s);
    }
    for s in &args.sweep {
        flag("sweep", s);
    }
    if let Some(s) = &args.shard {
        flag("shard", s);
    }
    if let Some(d) = &args.data_dir {
        flag("data-dir", &d.to_string_lossy());
    }
    flag("out", &out.to_string_lossy());
    words.push("--resume".into());
    words.join(" ")
}

/// `somnurbs drift`: compare two result folders (exit 1 on drift), or accept the current one.
fn drift(args: &DriftArgs) -> anyhow::Result<ExitCode> {
    use crate::report::drift;
    if args.accept {
        let said = drift::accept(&args.baseline, &args.current)?;
        for l in &said {
            println!("{l}");
        }
        println!(
            "baseline {} now holds the tables of {} ({} files changed)",
            args.baseline.display(),
            args.current.display(),
            said.len()
        );
        return Ok(ExitCode::SUCCESS);
    }
    let mut columns =
        args.tol.iter().map(|t| drift::parse_tol(t)).collect::<anyhow::Result<Vec<_>>>()?;
    let config = drift::read_config(&args.baseline)?;
    columns.extend(
        config
            .tolerance
            .iter()
            .map(|c| (c.column.clone(), drift::Tolerance { abs: c.abs, rel: c.rel })),
    );
    let opts = drift::DriftOptions { columns, config, ..Default::default() };
    let report = drift::compare_dirs(&args.baseline, &args.current, &opts, args.allow_spec_change)?;
    let out = args.out.clone().unwrap_or_else(|| "drift.csv".into());
    crate::io::outdir::require_outside_results(&out, "--out FILE")?;
    crate::io::write_atomic(&out, report.csv()?.as_bytes())?;
    println!("{}\nper-cell differences: {}", report.summary(10), out.display());
    Ok(if report.drifted() { ExitCode::from(1) } else { ExitCode::SUCCESS })
}

/// `somnurbs reproduce`: a plan's specs in order into one folder, then the combined report.
fn reproduce(args: &ReproduceArgs) -> anyhow::Result<ExitCode> {
    use experiment::reproduce::{default_out, specs_dir};
    let out = args.out.clone().unwrap_or_else(|| default_out(&args.plan, &args.profile));
    crate::io::outdir::require_folder_outside_results(&out, "output folder")?;
    let jobs = jobs(args.jobs)?;
    let specs = specs_dir(args.specs.as_deref(), &args.plan)?;
    let ctx = RunContext {
        resume: args.resume,
        reuse: reuse_folders(&args.reuse)?,
        ..RunContext::new(out, jobs, experiment::data_dir(args.data_dir.as_deref()))
    };
    super::interrupt::on_sigint(&reproduce_resume_command(args, &specs, &ctx.out));
    let report =
        experiment::reproduce::reproduce::<Section>(&specs, &args.plan, &args.profile, &ctx)?;
    if let Some(report) = report {
        eprintln!("somnurbs: wrote {}", report.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// The folders of `--reuse`, each checked to be a folder holding a cell log (read only).
fn reuse_folders(dirs: &[std::path::PathBuf]) -> anyhow::Result<Vec<std::path::PathBuf>> {
    use crate::io::outdir::{LOG_FILE, LOG_GZ};
    for d in dirs {
        if !d.is_dir() {
            anyhow::bail!("--reuse {}: not a folder", d.display());
        }
        if !experiment::log::has_log(d) {
            anyhow::bail!(
                "--reuse {}: holds no cell log ({LOG_GZ} or {LOG_FILE}): name a result folder of `somnurbs run`",
                d.display()
            );
        }
    }
    Ok(dirs.to_vec())
}

/// The command that continues an interrupted `somnurbs reproduce` (the SIGINT line).
fn reproduce_resume_command(
    args: &ReproduceArgs,
    specs: &std::path::Path,
    out: &std::path::Path,
) -> String {
    use super::interrupt::quote;
    let mut words = vec!["somnurbs reproduce".to_string()];
    let mut flag = |name: &str, value: &str| words.push(format!("--{name} {}", quote(value)));
    flag("plan", &args.plan);
    flag("profile", &args.profile);
    if args.specs.is_some() {
        flag("specs", &specs.to_string_lossy());
    }
    if let Some(d) = &args.data_dir {
        flag("data-dir", &d.to_string_lossy());
    }
    flag("out", &out.to_string_lossy());
    words.push("--resume".into());
    words.join(" ")
}
