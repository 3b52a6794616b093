//! The bounds of the `[cuckoo_bezier]` section. Its settings, defaults and checks are `CuckooBezierSpec` in
//! the family's `mod.rs`.

use super::CuckooBezierSpec;
use crate::experiment::limits::{self, Check};
use crate::experiment::spec::SpecError;

/// The bounds of the `[cuckoo_bezier]` section's sizes and counts (docs/specs.md, "Spec limits").
pub(crate) fn limits(c: &Check, s: &CuckooBezierSpec) -> Result<(), SpecError> {
    c.list("cuckoo_bezier.examples", &s.examples)?;
    c.list("cuckoo_bezier.methods", &s.methods)?;
    c.int("cuckoo_bezier.runs", s.runs, limits::MAX_REPEATS)?;
    c.int("cuckoo_bezier.nests", s.nests, limits::MAX_POPULATION)?;
    c.int("cuckoo_bezier.trace_every", s.trace_every, limits::MAX_TRACE_EVERY)?;
    for name in super::EXAMPLES {
        if let Some(e) = s.example(name) {
            c.int(&format!("cuckoo_bezier.{name}.size"), e.size, limits::MAX_SAMPLES)?;
            c.int(&format!("cuckoo_bezier.{name}.degree"), e.degree, 30)?;
            c.int(&format!("cuckoo_bezier.{name}.generations"), e.generations, limits::MAX_GENERATIONS)?;
        }
    }
    c.cells("cuckoo_bezier", &[s.examples.len(), s.methods.len(), s.runs])?;
    Ok(())
}
