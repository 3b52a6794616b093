//! somnurbs: reproduce, from seeds, SOM + cubic B-spline surface reconstruction experiments.
//!
//! Pure algorithms (`data`, `som`, `spline`, `optim`, `stats`) know nothing of files or the CLI;
//! `experiment` (spec, runner, seeds) and `report` (CSV, PNG, Markdown) wire them together.
pub mod cli;
pub mod data;
pub mod double_net;
pub mod experiment;
pub mod geom;
pub mod optim;
pub mod outdir;
pub mod report;
pub mod som;
pub mod spline;
pub mod stats;
