//! The spec defaults several families share (serde `default = "..."` functions), in one place so
//! that no family borrows another's: the optimisation budget of the thesis' Table 6.1 (which the
//! seeds' families reuse), the SOM settings of Chapter 4 (`SomParams::default()`), and `true`.

/// Repeats per cell, and other counts that default to ten (Table 6.1: 10 runs).
pub(crate) fn ten() -> usize {
    10
}

/// Generations of one optimiser run (Table 6.1).
pub(crate) fn generations() -> usize {
    2000
}

/// Individuals of one optimiser run (Table 6.1).
pub(crate) fn population() -> usize {
    40
}

/// Half-width of the start around the least-squares net (Table 6.1's range, +-5e-6).
pub(crate) fn init_range() -> f64 {
    5e-6
}

/// Evaluations between two points of a convergence trace.
pub(crate) fn trace_every() -> u64 {
    400
}

/// SOM training iterations T (Chapter 4; `SomParams::default()`).
pub(crate) fn som_iterations() -> usize {
    crate::som::SomParams::default().iterations
}

/// SOM initial learning rate alpha0 (Chapter 4; `SomParams::default()`).
pub(crate) fn som_alpha0() -> f64 {
    crate::som::SomParams::default().alpha0
}

/// A switch that is on unless the spec turns it off.
pub(crate) fn yes() -> bool {
    true
}
