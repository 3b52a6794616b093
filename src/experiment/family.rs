//! The family contract: one family per kind of spec section (Chapter 4's `[som]`, Chapter 5's
//! `[fit]`, Chapter 6's `[optim]`, and one per other seed). `run_spec`, `--dry-run`, the
//! fingerprint and `merge` see a family only through [`Family`], so a new experiment (another
//! seed's problem) plugs in as one folder under `src/families/` implementing it plus one line in
//! the registry (`families/mod.rs`), which `install()` hands to the engine as a [`Registry`];
//! nothing in the engine changes for it, and the engine imports no family.

use super::spec::{Spec, SpecError, SpecFile};
use super::RunContext;
use crate::report::claims::Claim;
use anyhow::Result;
use std::path::{Path, PathBuf};

/// What a family's run hands back to `run_spec`.
pub struct Outcome {
    /// The family's REPORT.md section (None when no tables were written: a shard).
    pub section: Option<String>,
    /// Sum of the cells' CPU seconds (the manifest's `cpu_seconds_cells`).
    pub cpu_s: f64,
    /// How many results the run produced (the manifest's `cells`).
    pub cells: usize,
}

/// One experiment family as the engine sees it: which spec section selects it, its cells' keys,
/// and how it runs. Implemented for every [`Experiment`] by the blanket impl below.
pub trait Family: Sync {
    /// The spec section (`som`, `fit`, `optim`, `seed002`, ...), for messages.
    fn section(&self) -> &'static str;
    /// Whether the spec has this family's section.
    fn present(&self, spec: &Spec) -> bool;
    /// Check the bounds of the section's sizes and counts (before anything is allocated from them).
    fn check_limits(&self, c: &super::limits::Check) -> Result<(), SpecError>;
    /// The data-set entries of the section, as written (names or paths).
    fn datasets<'a>(&self, spec: &'a Spec) -> Vec<&'a String>;
    /// Read the SOM maps from the folder `maps` (a plan whose earlier spec saved them); families
    /// that read no maps ignore it.
    fn use_maps(&self, spec: &mut Spec, maps: &str);
    /// Check that the files the section names besides its data sets (Chapter 4's maps) are
    /// there, before the output folder is touched.
    fn require_inputs(&self, spec: &Spec) -> Result<()>;
    /// Check every value of the family's section (called once the limits have passed and the
    /// spec has been found to hold this family's section only).
    fn validate(&self, spec: &Spec) -> Result<(), SpecError>;
    /// The keys of every cell that goes through the cell log, in cell order (what `--resume`
    /// and `merge` must find; cell k goes to shard k mod N + 1).
    fn logged_keys(&self, spec: &Spec) -> Vec<String>;
    /// Keys of cells that run (on their own streams) but are not logged: a resumed run or a merge
    /// runs them again. Listed by `--dry-run` only.
    fn unlogged_keys(&self, spec: &Spec) -> Vec<String>;
    /// Run the cells of `ctx`'s slice; with `tables`, write the tables and pictures into
    /// `ctx.out` and return the REPORT.md section.
    fn run(&self, spec: &Spec, ctx: &RunContext, tables: bool) -> Result<Outcome>;
    /// Run the variants of a spec (`--sweep`) into one folder, their tables together. A family
    /// whose tables cannot tell variants apart runs one variant only.
    fn run_variants(&self, variants: &[Spec], ctx: &RunContext, tables: bool) -> Result<Outcome>;
    /// Which keys `--set` and `--sweep` may change in the section (None: none).
    fn overrides(&self) -> Option<Overrides>;
    /// The family's part of a plan's combined report, from its specs' finished folders.
    fn combine(&self, view: &PlanView) -> Result<Combined>;
    /// The exact definitions of the metrics the family reports (the manifest's `[definitions]`).
    fn definitions(&self) -> super::Definitions;
}

/// A finished plan as one family sees it, for the parts of the combined report that need more
/// than one of its specs (the thesis' Tables 6.8 and 6.9 sum two specs' tables).
pub struct PlanView<'a> {
    /// The plan's output folder; spec `s` ran into `out/s`.
    pub out: &'a Path,
    /// The plan's specs of this family, in plan order.
    pub specs: Vec<&'a Spec>,
    /// The plan's own reading (`eq2_10`).
    pub reading: &'a str,
    /// The reading sets that ran some specs again.
    pub readings: Vec<ReadingRun>,
}

/// One reading set of a plan: its name, the specs it ran again and the folder holding them
/// (spec `s` ran into `root/s`).
#[derive(Debug, Clone)]
pub struct ReadingRun {
    pub name: String,
    pub specs: Vec<String>,
    pub root: PathBuf,
}

/// What a family adds to a plan's combined report.
#[derive(Default)]
pub struct Combined {
    /// Specs of the family that go beyond the source's protocol: their claims are labelled with
    /// the spec's name (`6 (ch6_exact)`), so they are not read as the source's own.
    pub beyond: Vec<String>,
    /// Claims over several specs, added to the plan's claims table.
    pub claims: Vec<Claim>,
    /// Markdown sections after the claims table.
    pub sections: Vec<String>,
    /// Markdown appended to the readings matrix.
    pub readings: Vec<String>,
}

/// Which keys of a section `--set` and `--sweep` may change (see [`Section::OVERRIDES`]).
#[derive(Debug, Clone, Copy)]
pub struct Overrides {
    /// What `--sweep` may vary: settings that leave every variant the same problems, so the
    /// variants can be ranked like optimisers. Full dotted keys (`optim.generations`), or
    /// prefixes ending in a dot (`optim.de.`: every key of that table).
    pub sweepable: fn() -> Vec<String>,
}

impl Overrides {
    /// Whether `--sweep` may vary `key` (a full dotted key, `optim.de.f`).
    pub fn sweepable(&self, key: &str) -> bool {
        (self.sweepable)().iter().any(|p| {
            if p.ends_with('.') {
                key.starts_with(p.as_str())
            } else {
                key == p
            }
        })
    }

    /// The sweepable keys, for messages (`optim.de.*, optim.generations`).
    pub fn describe(&self) -> String {
        let shown: Vec<String> = (self.sweepable)()
            .iter()
            .map(|p| if p.ends_with('.') { format!("{p}*") } else { p.to_string() })
            .collect();
        shown.join(", ")
    }
}

/// Where a section type sits in the spec file: its name, written for every family by the
/// `families!` macro of the registry from the section's field name.
pub trait Placed: Sized + Clone + std::fmt::Debug + Send + Sync + 'static {
    /// The section's name in the spec file (also used in messages).
    const NAME: &'static str;
    /// The section in a spec file, if the file has it.
    fn of(file: &SpecFile) -> Option<&Self> {
        file.sections.get(Self::NAME)?.as_any().downcast_ref()
    }
    /// The same, to change (see [`Section::use_maps`]).
    fn of_mut(file: &mut SpecFile) -> Option<&mut Self> {
        file.sections.get_mut(Self::NAME)?.as_any_mut().downcast_mut()
    }
}

/// A family's section as the engine holds it, whatever its type.
pub trait AnySection: std::fmt::Debug + Send + Sync {
    fn as_any(&self) -> &dyn std::any::Any;
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any;
    fn clone_box(&self) -> Box<dyn AnySection>;
}

impl<T: Placed> AnySection for T {
    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
    fn clone_box(&self) -> Box<dyn AnySection> {
        Box::new(self.clone())
    }
}

/// The family sections of a spec file, by section name, in the file's order of the registry.
#[derive(Debug, Default)]
pub struct Sections(Vec<(&'static str, Box<dyn AnySection>)>);

impl Clone for Sections {
    fn clone(&self) -> Sections {
        Sections(self.0.iter().map(|(n, s)| (*n, s.as_ref().clone_box())).collect())
    }
}

impl Sections {
    pub fn insert(&mut self, name: &'static str, section: Box<dyn AnySection>) {
        self.0.push((name, section));
    }
    pub fn get(&self, name: &str) -> Option<&dyn AnySection> {
        self.0.iter().find(|(n, _)| *n == name).map(|(_, s)| s.as_ref())
    }
    pub fn get_mut(&mut self, name: &str) -> Option<&mut dyn AnySection> {
        match self.0.iter_mut().find(|(n, _)| *n == name) {
            Some((_, s)) => Some(s.as_mut()),
            None => None,
        }
    }
}

/// The families as the engine reaches them: written by the `families!` macro in
/// `families/mod.rs` and handed over by its `install()`, so the engine imports no family.
pub struct Registry {
    /// Every family, in the order their sections are named in messages.
    pub families: &'static [&'static dyn Family],
    /// Parse a spec file's text (the header and every family's optional section).
    pub parse: fn(&str) -> Result<SpecFile, toml::de::Error>,
}

static INSTALLED: std::sync::OnceLock<&'static Registry> = std::sync::OnceLock::new();

/// Hand the engine its families (the first call wins; `main` makes it before anything else).
pub fn install(registry: &'static Registry) {
    let _ = INSTALLED.set(registry);
}

/// The installed families. Unit tests install the crate's own on first use.
pub fn registry() -> &'static Registry {
    #[cfg(test)]
    crate::families::install();
    INSTALLED.get().expect("somnurbs::families::install() must run before a spec is read")
}

/// A family's spec section (`[som]`, `[optim]`, `[seed004]`, ...): how it is checked. The
/// section type lives in its family's folder.
pub trait Section: Placed {
    /// Check the bounds of the section's sizes and counts (before anything is allocated from
    /// them).
    fn limits(&self, c: &super::limits::Check) -> Result<(), SpecError>;
    /// Check every value of the section (once the limits have passed).
    fn validate(&self, spec: &Spec) -> Result<(), SpecError>;
    /// The data-set entries of the section, as written (names or paths).
    fn datasets(&self) -> &[String] {
        &[]
    }
    /// Read the SOM maps from the folder `maps` (a plan whose earlier spec saved them).
    fn use_maps(&mut self, _maps: &str) {}
    /// See [`Family::require_inputs`]; by default nothing to check.
    fn require_inputs(&self, _spec: &Spec) -> Result<()> {
        Ok(())
    }
    /// Whether the section takes `--set`/`--sweep` (None: it does not), and which keys a sweep
    /// may vary.
    const OVERRIDES: Option<Overrides> = None;
}

/// A family as it is written: its section type, its cells and its run. Every `Experiment` is a
/// [`Family`] (the engine's object-safe view) through the blanket impl below, so a family writes
/// none of the section plumbing itself.
pub trait Experiment: Sync {
    type Section: Section;
    /// See [`Family::logged_keys`].
    fn logged_keys(&self, spec: &Spec) -> Vec<String>;
    /// See [`Family::unlogged_keys`].
    fn unlogged_keys(&self, _spec: &Spec) -> Vec<String> {
        Vec::new()
    }
    /// See [`Family::run`].
    fn run(&self, spec: &Spec, ctx: &RunContext, tables: bool) -> Result<Outcome>;
    /// See [`Family::run_variants`]; by default a sweep is refused.
    fn run_variants(&self, variants: &[Spec], ctx: &RunContext, tables: bool) -> Result<Outcome> {
        match variants {
            [one] => self.run(one, ctx, tables),
            _ => anyhow::bail!(
                "--sweep: [{}] specs run one variant at a time (sweeps work on [optim] specs)",
                Self::Section::NAME
            ),
        }
    }
    /// See [`Family::combine`]; by default nothing.
    fn combine(&self, _view: &PlanView) -> Result<Combined> {
        Ok(Combined::default())
    }
    /// See [`Family::definitions`]; by default none.
    fn definitions(&self) -> super::Definitions {
        super::Definitions::default()
    }
}

impl<E: Experiment> Family for E {
    fn section(&self) -> &'static str {
        E::Section::NAME
    }
    fn present(&self, spec: &Spec) -> bool {
        E::Section::of(&spec.file).is_some()
    }
    fn check_limits(&self, c: &super::limits::Check) -> Result<(), SpecError> {
        E::Section::of(&c.spec.file).map_or(Ok(()), |s| s.limits(c))
    }
    fn datasets<'a>(&self, spec: &'a Spec) -> Vec<&'a String> {
        E::Section::of(&spec.file).map(|s| s.datasets().iter().collect()).unwrap_or_default()
    }
    fn use_maps(&self, spec: &mut Spec, maps: &str) {
        if let Some(s) = E::Section::of_mut(&mut spec.file) {
            s.use_maps(maps);
        }
    }
    fn require_inputs(&self, spec: &Spec) -> Result<()> {
        E::Section::of(&spec.file).map_or(Ok(()), |s| s.require_inputs(spec))
    }
    fn validate(&self, spec: &Spec) -> Result<(), SpecError> {
        E::Section::of(&spec.file).map_or(Ok(()), |s| s.validate(spec))
    }
    fn logged_keys(&self, spec: &Spec) -> Vec<String> {
        Experiment::logged_keys(self, spec)
    }
    fn unlogged_keys(&self, spec: &Spec) -> Vec<String> {
        Experiment::unlogged_keys(self, spec)
    }
    fn run(&self, spec: &Spec, ctx: &RunContext, tables: bool) -> Result<Outcome> {
        Experiment::run(self, spec, ctx, tables)
    }
    fn run_variants(&self, variants: &[Spec], ctx: &RunContext, tables: bool) -> Result<Outcome> {
        Experiment::run_variants(self, variants, ctx, tables)
    }
    fn overrides(&self) -> Option<Overrides> {
        E::Section::OVERRIDES
    }
    fn combine(&self, view: &PlanView) -> Result<Combined> {
        Experiment::combine(self, view)
    }
    fn definitions(&self) -> super::Definitions {
        Experiment::definitions(self)
    }
}

/// The families whose sections the spec has (validation requires exactly one). The engine reaches
/// the families only through the installed [`Registry`].
pub fn present(spec: &Spec) -> Vec<&'static dyn Family> {
    registry().families.iter().copied().filter(|f| f.present(spec)).collect()
}

/// The section names, as `[som], [fit], ...`, for messages.
pub fn section_list() -> String {
    registry().families.iter().map(|f| format!("[{}]", f.section())).collect::<Vec<_>>().join(", ")
}
