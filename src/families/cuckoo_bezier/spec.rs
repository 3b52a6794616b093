//! The `[cuckoo_bezier]` section as the engine sees it: its bounds and checks. Its settings,
//! defaults and own value checks are `CuckooBezierSpec` in the family's `mod.rs`.

use super::CuckooBezierSpec;
use crate::experiment::limits::{self, Check};
use crate::experiment::spec::{Spec, SpecError};

impl crate::experiment::family::Section for CuckooBezierSpec {
    /// The bounds of the `[cuckoo_bezier]` section's sizes and counts (docs/specs.md, "Spec limits").
    fn limits(&self, c: &Check) -> Result<(), SpecError> {
        c.list("cuckoo_bezier.examples", &self.examples)?;
        c.list("cuckoo_bezier.methods", &self.methods)?;
        c.int("cuckoo_bezier.runs", self.runs, limits::MAX_REPEATS)?;
        c.int("cuckoo_bezier.nests", self.nests, limits::MAX_POPULATION)?;
        c.int("cuckoo_bezier.trace_every", self.trace_every, limits::MAX_TRACE_EVERY)?;
        for name in super::EXAMPLES {
            if let Some(e) = self.example(name) {
                c.int(&format!("cuckoo_bezier.{name}.size"), e.size, limits::MAX_SAMPLES)?;
                c.int(&format!("cuckoo_bezier.{name}.degree"), e.degree, 30)?;
                c.int(&format!("cuckoo_bezier.{name}.generations"), e.generations, limits::MAX_GENERATIONS)?;
            }
        }
        c.cells("cuckoo_bezier", &[self.examples.len(), self.methods.len(), self.runs])?;
        Ok(())
    }
    fn validate(&self, spec: &Spec) -> Result<(), SpecError> {
        self.validate().map_err(|(key, msg)| spec.err(&key, msg))?;
        spec.validate_optimiser_params("cuckoo_bezier", &self.offered())
    }
}
