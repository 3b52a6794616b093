//! Experiment families: one per kind of spec section (Chapter 4's `[som]`, Chapter 5's `[fit]`,
//! Chapter 6's `[optim]`, and one per other seed). `run_spec`, `--dry-run`, the fingerprint and
//! `merge` see a family only through [`Family`], so a new experiment (another seed's problem)
//! plugs in as one file implementing it plus one line in [`FAMILIES`]; nothing in the runner
//! changes for it.

use super::spec::Spec;
use super::RunContext;
use anyhow::Result;

/// What a family's run hands back to `run_spec`.
pub struct Outcome {
    /// The family's REPORT.md section (None when no tables were written: a shard).
    pub section: Option<String>,
    /// Sum of the cells' CPU seconds (the manifest's `cpu_seconds_cells`).
    pub cpu_s: f64,
    /// How many results the run produced (the manifest's `cells`).
    pub cells: usize,
}

/// One experiment family: which spec section selects it, its cells' keys, and how it runs.
pub trait Family: Sync {
    /// The spec section (`som`, `fit`, `optim`, `seed002`, ...), for messages.
    fn section(&self) -> &'static str;
    /// Whether the spec has this family's section.
    fn present(&self, spec: &Spec) -> bool;
    /// The keys of every cell that goes through the cell log, in cell order (what `--resume`
    /// and `merge` must find; cell k goes to shard k mod N + 1).
    fn logged_keys(&self, spec: &Spec) -> Vec<String>;
    /// Keys of cells that run (on their own streams) but are not logged: a resumed run or a merge
    /// runs them again. Listed by `--dry-run` only.
    fn unlogged_keys(&self, _spec: &Spec) -> Vec<String> {
        Vec::new()
    }
    /// Run the cells of `ctx`'s slice; with `tables`, write the tables and pictures into
    /// `ctx.out` and return the REPORT.md section.
    fn run(&self, spec: &Spec, ctx: &RunContext, tables: bool) -> Result<Outcome>;
    /// Run the variants of a spec (`--sweep`) into one folder, their tables together. A family
    /// whose tables cannot tell variants apart runs one variant only.
    fn run_variants(&self, variants: &[Spec], ctx: &RunContext, tables: bool) -> Result<Outcome> {
        match variants {
            [one] => self.run(one, ctx, tables),
            _ => anyhow::bail!("--sweep: [{}] specs run one variant at a time (sweeps work on [optim] specs)", self.section()),
        }
    }
}

/// Every family the harness knows, in the order their sections are named in messages.
pub static FAMILIES: &[&dyn Family] = &[&super::ch4::Som, &super::ch5::Fit, &super::ch6::Optim, &super::seed001::Seed001, &super::seed002::Seed002, &super::seed003::Seed003, &super::seed004::Seed004];

/// The families whose sections the spec has (validation requires exactly one).
pub fn present(spec: &Spec) -> Vec<&'static dyn Family> {
    FAMILIES.iter().copied().filter(|f| f.present(spec)).collect()
}

/// The section names, as `[som], [fit], ...`, for messages.
pub fn section_list() -> String {
    FAMILIES.iter().map(|f| format!("[{}]", f.section())).collect::<Vec<_>>().join(", ")
}
