//! Problem-agnostic optimisers over one problem trait (thesis Chapter 6 and seed 003): GA, DE,
//! PSO, CSA and ICSA, and the thesis' control-net problem with a fast sparse fitness. Pure: no
//! file I/O.

pub mod control_net;
pub mod cuckoo;
pub mod de;
pub mod exact;
pub mod ga;
pub mod problem;
pub mod pso;

pub use problem::{Budget, Optimiser, Problem, RunResult};
