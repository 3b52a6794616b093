//! The bounds of the `[seed003]` section. Its settings, defaults and checks are `CuckooBezierSpec` in
//! the family's `mod.rs`.

use super::CuckooBezierSpec;
use crate::experiment::limits::{self, Check};
use crate::experiment::spec::SpecError;

/// The bounds of the `[seed003]` section's sizes and counts (docs/specs.md, "Spec limits").
pub(crate) fn limits(c: &Check, s: &CuckooBezierSpec) -> Result<(), SpecError> {
    c.list("seed003.examples", &s.examples)?;
    c.list("seed003.methods", &s.methods)?;
    c.int("seed003.runs", s.runs, limits::MAX_REPEATS)?;
    c.int("seed003.nests", s.nests, limits::MAX_POPULATION)?;
    c.int("seed003.trace_every", s.trace_every, limits::MAX_TRACE_EVERY)?;
    for name in super::EXAMPLES {
        if let Some(e) = s.example(name) {
            c.int(&format!("seed003.{name}.size"), e.size, limits::MAX_SAMPLES)?;
            c.int(&format!("seed003.{name}.degree"), e.degree, 30)?;
            c.int(&format!("seed003.{name}.generations"), e.generations, limits::MAX_GENERATIONS)?;
        }
    }
    c.cells("seed003", &[s.examples.len(), s.methods.len(), s.runs])?;
    Ok(())
}
