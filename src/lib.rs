//! somnurbs: reproduce, from seeds, SOM + cubic B-spline surface reconstruction experiments.
//!
//! Pure algorithms (`data`, `som`, `spline`, `optim`, `stats`, and `simd`, the home of every fast
//! path) know nothing of files or the CLI;
//! `experiment` (the engine: spec, runner, seeds), `report` (the toolkit: tables, PNG, Markdown)
//! and `io` serve the experiment `families`, one folder each, listed once in `families/mod.rs`.
// Loops over coordinates (0..3), SIMD lanes and table columns index several arrays at once and
// read closer to the equations than zipped iterators.
#![allow(clippy::needless_range_loop)]

pub mod cli;
pub mod data;
pub mod double_net;
pub mod experiment;
pub mod families;
pub mod geom;
pub mod io;
pub mod optim;
pub mod report;
pub mod simd;
pub mod som;
pub mod spline;
pub mod stats;
