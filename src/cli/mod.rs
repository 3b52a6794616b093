//! Command-line definitions (clap). Help text and parsing come from the same definitions.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

mod commands;
mod interrupt;
pub use commands::main;

const EXAMPLES: &str = "\
Examples:
  somnurbs run experiments/ch4_models.toml                 # Appendix B/C, Tables 4.9/4.13/4.14
  somnurbs run experiments/ch4_models.toml --profile quick # the same, T = 3000 (seconds)
  somnurbs run experiments/ch4_bunny.toml --data-dir ~/scans   # bun_zipper.ply lives in ~/scans
  somnurbs run experiments/ch4_grids.toml --dry-run        # list cells and their seeds
  somnurbs run experiments/ch6_same.toml --profile quick --sweep optimise.de.f=0.3,0.5,0.8 --out f_sweep
  somnurbs datasets list
  somnurbs datasets export sphere sphere.xyz

Data directory (bunny, talus): --data-dir, else $SOMNURBS_DATA, else ./data, else the clone's data/";

#[derive(Debug, Parser)]
#[command(name = "somnurbs", version, about = "Reproduce SOM + cubic B-spline surface reconstruction experiments from seeds", after_help = EXAMPLES)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Run an experiment spec (TOML): every cell on its own seeded stream, then tables, pictures,
    /// REPORT.md and manifest.toml in the output folder.
    #[command(after_help = EXAMPLES)]
    Run(RunArgs),
    /// List, describe or export the data sets (generated primitives and data files).
    Datasets(DatasetsArgs),
    /// Fit cubic B-spline surfaces to a structured two-view grid (the CSV Chapter 4 saves in
    /// maps/) and write the control nets (CSV), an IGES file and an OBJ mesh.
    #[command(
        after_help = "Examples (after `somnurbs reproduce`):\n  somnurbs fit --grid results/thesis/ch4_models/maps/dnsom_spindle_20x20.csv --cn 18x18 --out fit_spindle\n  somnurbs fit --grid results/thesis/ch4_models/maps/dnsom_cube_20x20.csv --cn 18x18 --knots nurbs_book --fairness 1e-4 --out fit_cube\n  somnurbs fit --grid my_scan_20x20.csv --cn 18x18 --allow-excursion --out fit_scan   # write even if the surfaces leave the data\n\nThe surfaces are also evaluated between the data points. When they leave the map's bounding box\nby more than 10% of its diagonal, fit measures on the same map the options that keep them within\n(more --fairness, another --param, --knots or --approach, the largest smaller square --cn),\nprints them, and exits 2 writing nothing; --allow-excursion writes the surfaces anyway, with a\nwarning."
    )]
    Fit(FitArgs),
    /// Compare the optimisers of a Chapter 6 results folder: per cell Wilcoxon signed-rank
    /// (repeats paired by index) and rank-sum tests with A12, and overall Friedman with
    /// Holm-corrected pairwise tests and a critical-difference diagram; the Bayesian signed-rank
    /// test; runtime ECDFs, ERT, fixed-budget curves and AOCC from the IOHprofiler traces.
    #[command(
        after_help = "Examples (after `somnurbs reproduce`):\n  somnurbs compare results/thesis/ch6_same\n  somnurbs compare results/thesis/ch6_diff --alpha 0.01 --rope 1e-5\n  somnurbs compare results/ch6_exact --external ioh_data   # optimisers logged from Python (docs/python.md)"
    )]
    Compare(CompareArgs),
    /// Regenerate the thesis: Chapters 4, 5 and 6 in order (each chapter's maps feed the next),
    /// then one REPORT.md with every table and picture, the thesis' figures beside ours, Tables
    /// 6.8/6.9 and the table of the thesis' claims with verdicts.
    #[command(
        after_help = "Examples:\n  somnurbs reproduce --profile quick   # under a minute\n  somnurbs reproduce                   # the full protocol\n  somnurbs reproduce --plan seeds      # the other seeds' experiments (001-004)"
    )]
    Reproduce(ReproduceArgs),
    /// Compare every table of a results folder with a baseline folder: numbers to per-column
    /// tolerances, timing columns reported but not judged. Exit 0: no drift; 1: drift (the moved
    /// cells are named, and all differences written to drift.csv, or --out); 2: bad input.
    #[command(
        after_help = "Examples:\n  somnurbs drift results/baselines/quick results/thesis_quick\n  somnurbs drift results/baselines/quick results/thesis_quick --tol 'de_*=1e-6'\n  somnurbs drift --accept results/baselines/quick results/thesis_quick   # update the baseline on purpose"
    )]
    Drift(DriftArgs),
    /// Combine the shard folders of one spec (`run --shard I/N`) into one folder with its tables,
    /// identical to a one-machine run apart from timing.
    #[command(
        after_help = "Example:\n  somnurbs run experiments/ch6_same.toml --shard 1/2 --out s1   # on one machine\n  somnurbs run experiments/ch6_same.toml --shard 2/2 --out s2   # on another\n  somnurbs merge s1 s2 --out results/ch6_same"
    )]
    Merge(MergeArgs),
    /// Make a finished results folder's tables, pictures, REPORT.md and report.html again from
    /// its cell records alone (no cell runs): a missing file is written, and every file that is
    /// there must already hold exactly what the records give (a finished folder is never
    /// rewritten). Exit 0: the folder is whole; 2: a file differs, a record is missing, bad input.
    #[command(
        after_help = "Examples:\n  somnurbs report results/ch6_same          # restores a deleted table, checks the rest\n  somnurbs report results/ch4_models --data-dir data"
    )]
    Report(ReportArgs),
    /// Export the control net an optimiser found in a finished Chapter 6 folder (from the cell's
    /// record; `--start` exports approach B's net, its start) as control_nets.csv, surfaces.igs
    /// and surfaces.obj in the data's own frame, with export.csv; the record's surface error must
    /// come out again from the exported net.
    #[command(
        after_help = "Examples:\n  somnurbs export results/ch6_same --cell optim/talus/20x20/18x18/chord_length/de/r0 --out talus_de\n  somnurbs export results/ch6_same --cell optim/talus/20x20/18x18/chord_length/de/r0 --start --out talus_b\n  somnurbs export results/ch6_same --cell optim/talus/20x20/18x18/chord_length/de/r0 --allow-excursion --out talus_de\n\nThe `cell` column of runs.csv names the cells; in a sweep, --variant names one of a cell's variants.\nA net whose surfaces leave the map's bounding box between the data points by more than 10% of its\ndiagonal is refused (exit 2, nothing written; the start's excursion is measured and printed)\nunless --allow-excursion is given."
    )]
    Export(ExportArgs),
}

#[derive(Debug, Args)]
pub(crate) struct ExportArgs {
    /// A finished folder of `somnurbs run` (or `merge`) with an [optimise] section.
    pub(crate) results: PathBuf,
    /// The cell, as runs.csv's `cell` column writes it (e.g.
    /// optim/talus/20x20/18x18/chord_length/de/r0).
    #[arg(long)]
    pub(crate) cell: String,
    /// In a sweep's folder: the variant (runs.csv's `variant` column) of the cell.
    #[arg(long)]
    pub(crate) variant: Option<String>,
    /// Export approach B's net (the cell's start) instead of the optimiser's best.
    #[arg(long)]
    pub(crate) start: bool,
    /// Output folder (must not exist or be empty).
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// `data` (the data set's own coordinates, the normalisation undone with the map's frame) or
    /// `normalised` (the map's).
    #[arg(long, default_value = "data")]
    pub(crate) frame: String,
    /// Length unit of the data's coordinates, for the IGES unit flag: unknown, mm, cm, m, um, in
    /// or ft.
    #[arg(long, default_value = "unknown")]
    pub(crate) units: String,
    /// Evaluation samples per direction in the OBJ mesh, in [2, 1000].
    #[arg(long, default_value_t = 40)]
    pub(crate) samples: usize,
    /// The data folder (as for `run`); the problem is rebuilt from the folder's own maps/.
    #[arg(long)]
    pub(crate) data_dir: Option<PathBuf>,
    /// Write the net even when its surfaces leave the map's bounding box between the data points
    /// by more than 10% of its diagonal (a warning instead of a refusal).
    #[arg(long)]
    pub(crate) allow_excursion: bool,
}

#[derive(Debug, Args)]
pub(crate) struct ReportArgs {
    /// A finished folder of `somnurbs run` or `somnurbs merge`.
    pub(crate) results: PathBuf,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, short = 'j')]
    pub(crate) jobs: Option<usize>,
    /// The data folder the run read (default: $SOMNURBS_DATA, else ./data, else the data/ of the
    /// clone somnurbs was built from); the records hold every cell's result, the data the
    /// pictures draw.
    #[arg(long)]
    pub(crate) data_dir: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub(crate) struct CompareArgs {
    /// A results folder written by a spec with an [optimise] section (reads its runs.csv).
    pub(crate) results: PathBuf,
    /// Significance level for the h columns, in (0, 1).
    #[arg(long, default_value_t = 0.05)]
    pub(crate) alpha: f64,
    /// Region of practical equivalence of the Bayesian signed-rank test: half-width on the
    /// difference of the mean errors per cell, each divided by the cell's approach-B error
    /// (finite, >= 0).
    #[arg(long, default_value_t = 1e-6)]
    pub(crate) rope: f64,
    /// Monte Carlo samples of the Bayesian signed-rank test, in [1000, 10^7].
    #[arg(long, default_value_t = 50_000)]
    pub(crate) bayes_samples: usize,
    /// Folder for the tables and charts (default RESULTS/compare). It must be missing, empty or
    /// an earlier compare's, which is replaced whole, and not inside a result folder
    /// (RESULTS/compare aside); the run's own files are never changed.
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// An IOHprofiler folder of optimisers from outside somnurbs (written by the Python
    /// package's `somnurbs.ioh_adapter.Logger`), compared beside the folder's own (repeatable);
    /// refused unless its problems are the folder's (spec, profile, reading, box, B's error) and
    /// its traces agree with its records and with the folder's certified lower bounds.
    #[arg(long, value_name = "DIR")]
    pub(crate) external: Vec<PathBuf>,
}

#[derive(Debug, Args)]
pub(crate) struct FitArgs {
    /// Two-view grid CSV with columns i,j,view,class,x,y,z (both views, 2 nx ny rows), or its
    /// gzip-compressed copy (`.csv.gz`, as Chapter 5 and 6 folders keep their maps).
    #[arg(long)]
    pub(crate) grid: PathBuf,
    /// Control-net size CNXxCNY (each side at least 4, at most the grid's).
    #[arg(long)]
    pub(crate) cn: String,
    /// uniform, chord_length, centripetal or exponential.
    #[arg(long, default_value = "chord_length")]
    pub(crate) param: String,
    /// conventional (A) or improved (B).
    #[arg(long, default_value = "improved")]
    pub(crate) approach: String,
    /// Output folder for control_nets.csv, surfaces.igs, surfaces.obj and fit.csv.
    #[arg(long, default_value = "fit")]
    pub(crate) out: PathBuf,
    /// Evaluation samples per direction in the OBJ mesh, in [2, 1000].
    #[arg(long, default_value_t = 40)]
    pub(crate) samples: usize,
    /// Knot reading for nets smaller than the grid: eq2_10 (the thesis' Eq. 2.10 literally) or
    /// nurbs_book (The NURBS Book eq. 9.68-9.69). See docs/readings.md.
    #[arg(long, default_value = "eq2_10")]
    pub(crate) knots: String,
    /// Reading of approach A's surface error: per_surface or nov_bottom.
    #[arg(long, default_value = "per_surface")]
    pub(crate) error_a: String,
    /// Penalised least squares weight (0: plain least squares, as the thesis); a small value such
    /// as 1e-4 keeps near-square nets bounded between the data points.
    #[arg(long, default_value_t = 0.0)]
    pub(crate) fairness: f64,
    /// Coordinates of control_nets.csv, surfaces.igs and surfaces.obj: `data` (the data set's
    /// own, the normalisation undone with the frame Chapter 4 saved beside the map,
    /// MAP.frame.toml) or `normalised` (the map's). A map without a frame is exported as it is.
    #[arg(long, default_value = "data")]
    pub(crate) frame: String,
    /// Length unit of the data's coordinates, for the IGES unit flag: unknown (flag 2, MM,
    /// marked nominal in the start section), mm, cm, m, um, in or ft.
    #[arg(long, default_value = "unknown")]
    pub(crate) units: String,
    /// Write the surfaces even when they leave the map's bounding box between the data points by
    /// more than 10% of its diagonal (a warning instead of a refusal; without it such a fit exits
    /// 2, writes nothing and prints the options measured to stay within), e.g.
    /// `somnurbs fit --grid scan.csv --cn 18x18 --allow-excursion`.
    #[arg(long)]
    pub(crate) allow_excursion: bool,
}

#[derive(Debug, Args)]
pub(crate) struct RunArgs {
    /// The experiment spec, e.g. experiments/ch4_models.toml.
    pub(crate) spec: PathBuf,
    /// A profile defined in the spec ([profiles.NAME]), e.g. quick.
    #[arg(long)]
    pub(crate) profile: Option<String>,
    /// Output folder (default: the spec's `output`, else results/<spec name>).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Worker threads (default: all cores; at least 1, at most 4 x the cores: more is cut down
    /// with a note). Results do not depend on it.
    #[arg(long, short = 'j')]
    pub(crate) jobs: Option<usize>,
    /// Folder holding bun_zipper.ply and talus_r.stl (default: $SOMNURBS_DATA, else ./data, else
    /// the data/ of the clone somnurbs was built from).
    #[arg(long)]
    pub(crate) data_dir: Option<PathBuf>,
    /// List the cells and their seeds without running them.
    #[arg(long)]
    pub(crate) dry_run: bool,
    /// Keep the cells an earlier, interrupted run of the same spec, profile and seed finished in
    /// the output folder (its cells.jsonl) and run only the rest; refused if the folder holds
    /// another run.
    #[arg(long)]
    pub(crate) resume: bool,
    /// Run only the I-th of N deterministic slices of the cells (1-based, e.g. 3/8) and write no
    /// tables; `somnurbs merge` combines the N shard folders into one.
    #[arg(long, value_name = "I/N")]
    pub(crate) shard: Option<String>,
    /// Change one key of the spec's [optimise] section, validated as if written in the file, e.g.
    /// `--set optimise.de.f=0.5` (repeatable). The change is recorded in the manifest; a cell it
    /// reaches is another cell (its identity), drawing the same random numbers as the unchanged
    /// spec's cell of the same place.
    #[arg(long, value_name = "KEY=VALUE")]
    pub(crate) set: Vec<String>,
    /// Run the spec once per value of an optimiser setting into one folder, e.g.
    /// `--sweep optimise.de.f=0.3,0.5,0.8` (repeatable: every combination). A cell the setting
    /// does not reach (GA's and PSO's in that example) is computed once and listed once; runs.csv
    /// gets a `variant` column and `somnurbs compare` ranks each de@variant like an optimiser.
    /// At most 1000 variants and 10^5 cells over all of them; a value given twice (compared as
    /// TOML values: 0.3 and 0.30 are one) is refused.
    #[arg(long, value_name = "KEY=V1,V2,...")]
    pub(crate) sweep: Vec<String>,
    /// Another result folder whose cell log may hold cells of this run (repeatable): a cell
    /// that computes the same there (same problem content, optimiser table, budget, place and
    /// master seed; never matched by name alone) is taken from its record, not computed.
    #[arg(long, value_name = "DIR")]
    pub(crate) reuse: Vec<PathBuf>,
}

#[derive(Debug, Args)]
pub(crate) struct DriftArgs {
    /// The baseline folder (e.g. results/baselines/quick); its drift.toml, if any, names
    /// timing-dependent tables and rows and per-column tolerances.
    pub(crate) baseline: PathBuf,
    /// The folder of the run to check.
    pub(crate) current: PathBuf,
    /// Tolerance of the columns matching COLUMN (a glob): |a - b| <= ABS + REL max(|a|, |b|).
    /// Repeatable. Default 1e-9 absolute and 1e-9 relative.
    #[arg(long, value_name = "COLUMN=ABS[,REL]")]
    pub(crate) tol: Vec<String>,
    /// Where to write the per-cell diff CSV (default drift.csv in the working folder; never
    /// inside a result folder).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Compare even when the two folders were made by different specs, seeds or profiles.
    #[arg(long)]
    pub(crate) allow_spec_change: bool,
    /// Make the baseline hold the current tables (on purpose, after a change that moves results).
    #[arg(long)]
    pub(crate) accept: bool,
}

#[derive(Debug, Args)]
pub(crate) struct MergeArgs {
    /// The shard folders (each written by `somnurbs run SPEC --shard I/N`), all N of them.
    #[arg(required = true)]
    pub(crate) shards: Vec<PathBuf>,
    /// The folder to write the combined run to (must not hold a run yet, nor be a shard folder).
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Worker threads (default: all cores; at least 1, at most 4 x the cores: more is cut down
    /// with a note). Results do not depend on it.
    #[arg(long, short = 'j')]
    pub(crate) jobs: Option<usize>,
    /// Folder holding bun_zipper.ply and talus_r.stl (default: $SOMNURBS_DATA, else ./data, else
    /// the data/ of the clone somnurbs was built from).
    #[arg(long)]
    pub(crate) data_dir: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub(crate) struct ReproduceArgs {
    /// quick (every spec's quick profile: under a minute on 2 cores; what CI runs) or full (the
    /// thesis' protocol: about half an hour on 2 cores, nearly all of it Chapter 6).
    #[arg(long, default_value = "full", value_parser = ["quick", "full"])]
    pub(crate) profile: String,
    /// Which plan: `<specs>/<PLAN>.toml` lists the specs to run in order (thesis: Chapters 4-6;
    /// seeds: the other seeds' experiments; all: both).
    #[arg(long, default_value = "thesis")]
    pub(crate) plan: String,
    /// Output folder (default results/<PLAN>, or results/<PLAN>_quick).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Folder of the plans and experiment specs (default: experiments, or, run from a folder
    /// without one, the experiments folder of the clone somnurbs was built from).
    #[arg(long)]
    pub(crate) specs: Option<PathBuf>,
    /// Worker threads (default: all cores; at least 1, at most 4 x the cores: more is cut down
    /// with a note). Results do not depend on it.
    #[arg(long, short = 'j')]
    pub(crate) jobs: Option<usize>,
    /// Folder holding bun_zipper.ply and talus_r.stl (default: $SOMNURBS_DATA, else ./data, else
    /// the data/ of the clone somnurbs was built from).
    #[arg(long)]
    pub(crate) data_dir: Option<PathBuf>,
    /// Keep what an interrupted reproduction finished (per chapter, as `run --resume`).
    #[arg(long)]
    pub(crate) resume: bool,
    /// Another result folder (a spec's) whose cell log may hold cells of the plan (repeatable;
    /// as `run --reuse`). A reading set always reuses the plan's own folder of its spec.
    #[arg(long, value_name = "DIR")]
    pub(crate) reuse: Vec<PathBuf>,
}

#[derive(Debug, Args)]
pub(crate) struct DatasetsArgs {
    #[command(subcommand)]
    pub(crate) action: Option<DatasetsAction>,
    /// Folder holding the data files (default: $SOMNURBS_DATA, else ./data, else the clone's data/).
    #[arg(long, global = true)]
    pub(crate) data_dir: Option<PathBuf>,
}

#[derive(Debug, Subcommand)]
pub(crate) enum DatasetsAction {
    /// List the built-in data sets (default).
    List,
    /// Load one data set and print its size and bounds.
    Show {
        /// A name from `somnurbs datasets list`, e.g. sphere or bunny.
        name: String,
    },
    /// Write a data set's normalised points to FILE (.csv: comma-separated with header; else XYZ).
    Export {
        /// A name from `somnurbs datasets list`, e.g. sphere or bunny.
        name: String,
        /// The file to write (.csv, or .xyz: one "x y z" line per point).
        file: PathBuf,
    },
}
