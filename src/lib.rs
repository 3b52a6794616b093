//! somnurbs: reproduce, from seeds, SOM + cubic B-spline surface reconstruction experiments.
//!
//! Pure algorithms (`data`, `som`, `spline`, `optim`, `stats`) know nothing of files or the CLI;
//! `experiment` (the engine: spec, runner, seeds), `report` (the toolkit: tables, PNG, Markdown)
//! and `io` serve the experiment `families`, one folder each, listed once in `families/mod.rs`.
pub mod cli;
pub mod data;
pub mod double_net;
pub mod experiment;
pub mod families;
pub mod geom;
pub mod io;
pub mod optim;
pub mod report;
pub mod som;
pub mod spline;
pub mod stats;
