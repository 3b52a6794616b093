//! somnurbs: reproduce, from seeds, SOM + cubic B-spline surface reconstruction experiments.
//!
//! Pure algorithms (`data`, `som`, `spline`, `optim`, `stats`, and `simd`, the home of every fast
//! path) know nothing of files or the CLI;
//! `experiment` (the engine: spec, runner, seeds), `report` (the toolkit: tables, PNG, Markdown)
//! and `io` serve the experiment `families`, one folder each, listed once in `families/mod.rs`.
//!
//! # The public surface
//!
//! `pub` only for the binary, the integration tests, the benches and the Python package; the rest
//! is `pub(crate)` (`unreachable_pub` fails the build otherwise):
//!
//! - the program: [`cli::main`];
//! - specs and runs: [`families::Loaded`] (a spec and its one typed section),
//!   [`families::Section`], [`experiment::RunContext`], [`experiment::Override`],
//!   [`experiment::dry_run_listing`], [`experiment::data_dir`], [`experiment::log_text`], the
//!   seeds ([`experiment::cell_rng`], [`experiment::seed_hex`]), [`experiment::run_cells`],
//!   [`experiment::thread_cpu_seconds`], [`experiment::GridSize`];
//! - the families' entry points the benches and tests drive: [`families::som::run_cell`] and its
//!   cells, [`families::optimise::problems`], [`families::optimise::exact_optima`],
//!   [`families::suite`] (the Chapter 6 problems as a benchmark suite, for Python), and
//!   [`notice`] (where notes and progress lines go: stderr, or the Python package's `logging`);
//! - the algorithms the benches time: [`som::train`], [`spline::fit_two_view`],
//!   [`spline::ControlNetProblem`], the seed 003 Bezier problems, [`optim::De`], [`optim::Pso`],
//!   [`optim::Csa`], [`optim::default_optimiser`], [`optim::certify_dual`], [`simd::Isa`] and the
//!   fast paths' timing reports;
//! - the file readers the fuzz tests feed ([`data::ply`], [`data::stl`], [`data::off`],
//!   [`data::obj`], [`data::xyz`]), [`data::load_dataset`], [`spline::parse_iges_128`], and
//!   the vendored plotly.js ([`report::PLOTLY_JS`]).
// Loops over coordinates (0..3), SIMD lanes and table columns index several arrays at once and
// read closer to the equations than zipped iterators.
#![allow(clippy::needless_range_loop)]
#![warn(unreachable_pub)]

pub mod cli;
pub mod data;
pub mod double_net;
pub mod experiment;
pub mod families;
pub mod geom;
pub(crate) mod io;
pub mod notice;
pub mod optim;
pub mod report;
pub mod simd;
pub mod som;
pub mod spline;
pub(crate) mod stats;
