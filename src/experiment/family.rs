//! The family contract: one family per kind of spec section (Chapter 4's `[som]`, Chapter 5's
//! `[fit]`, Chapter 6's `[optimise]`, and one per other seed). A family is written as an
//! [`Experiment`]: its section type (parsed and checked once), its cells' keys and its run, each
//! method given the section as that type. The `families!` macro of `families/mod.rs` (the only
//! list of families) makes the enum of their sections, which implements [`Families`]; the engine
//! is generic over it, reaches each family through [`Family`] (implemented for every
//! `Experiment` below) and names no family. No section is ever held as `Any`: a family gets its
//! own from the enum by [`Holds`], a `match` the macro writes.

use super::limits::Check;
use super::spec::{Loaded, Spec, SpecError, SpecFile};
use super::RunContext;
use crate::report::claims::Claim;
use crate::report::reference::{Published, RefTable};
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

/// The set of families a harness knows: the enum of their sections that the `families!` macro
/// writes, one variant per family. The engine is generic over it.
pub trait Families: Clone + std::fmt::Debug + Send + Sync + Sized + 'static {
    /// Every family, in the order their sections are named in messages.
    fn all() -> &'static [&'static dyn Family<Self>];
    /// The (former, present) names of renamed sections: a spec, `--set` key or reading set may
    /// still use the former (docs/specs.md, "Former section names").
    fn renamed() -> &'static [(&'static str, &'static str)];
    /// Parse a spec file's text: its header, and each family section it holds (in registry
    /// order; validation requires exactly one). Unknown keys are refused, so serde names the
    /// line and column of a bad one.
    fn parse(text: &str) -> Result<(SpecFile, Vec<Self>), toml::de::Error>;
    /// The family this section belongs to.
    fn family(&self) -> &'static dyn Family<Self>;
}

/// A family's section inside the enum `Self` (written by the `families!` macro: a `match`).
pub trait Holds<S>: Families {
    /// The section, when it is this family's.
    fn get(&self) -> Option<&S>;
    /// The same, to change (see [`Section::use_maps`]).
    fn get_mut(&mut self) -> Option<&mut S>;
}

/// One experiment family as the engine sees it: which spec section selects it, its cells' keys,
/// and how it runs. Implemented for every [`Experiment`] by the blanket impl below; every method
/// takes the spec's section as the enum `F` and hands the family its own type.
pub trait Family<F>: Sync {
    /// The spec section (`som`, `fit`, `optimise`, `rational_bezier`, ...), for messages.
    fn section(&self) -> &'static str;
    /// Check the bounds of the section's sizes and counts (before anything is allocated from them).
    fn check_limits(&self, c: &Check, s: &F) -> Result<(), SpecError>;
    /// The data-set entries of the section, as written (names or paths).
    fn datasets<'a>(&self, s: &'a F) -> Vec<&'a String>;
    /// Read the SOM maps from the folder `maps` (a plan whose earlier spec saved them); families
    /// that read no maps ignore it.
    fn use_maps(&self, s: &mut F, maps: &str);
    /// Check what the run checks before its first cell besides its data files loading: the
    /// files the section names (Chapter 4's maps) are there, and the data sets are large enough
    /// for the maps trained on them. Called before the output folder is touched, and by
    /// `--dry-run`.
    fn require_inputs(&self, spec: &Spec, s: &F, ctx: &RunContext) -> Result<()>;
    /// Check every value of the family's section (called once the limits have passed and the
    /// spec has been found to hold this family's section only).
    fn validate(&self, spec: &Spec, s: &F) -> Result<(), SpecError>;
    /// The keys of every cell that goes through the cell log, in cell order (what `--resume`
    /// and `merge` must find, and what `--dry-run` lists; cell k of each list of cells a family
    /// runs goes to shard k mod N + 1, but a cell every other cell needs, seed 001's map of a
    /// data set, runs in every shard).
    fn logged_keys(&self, spec: &Spec, s: &F) -> Vec<String>;
    /// Run the variants of a spec (one for a plain run; `--sweep` makes more) into one folder;
    /// with `tables`, write the tables and pictures into `ctx.out` and return the REPORT.md
    /// section. A family whose tables cannot tell variants apart runs one variant only.
    fn run_variants(
        &self,
        variants: &[Loaded<F>],
        ctx: &RunContext,
        tables: bool,
    ) -> Result<Outcome>;
    /// Which keys `--set` and `--sweep` may change in the section (None: none).
    fn overrides(&self) -> Option<Overrides>;
    /// The family's part of a plan's combined report, from its specs' finished folders (the
    /// view's specs of other families are left out).
    fn combine(&self, view: &PlanView<F>) -> Result<Combined>;
    /// The exact definitions of the metrics the family reports (the manifest's `[definitions]`).
    fn definitions(&self) -> super::Definitions;
    /// The published tables the family reproduces (the readings score compares every CSV of its
    /// folders named like one).
    fn published(&self) -> Published;
    /// The part of the sources the family reproduces (`Chapter 6`, `Seed 003`), for the readings
    /// score's totals.
    fn title(&self) -> &'static str;
}

/// A finished plan as one family sees it, for the parts of the combined report that need more
/// than one of its specs (the thesis' Tables 6.8 and 6.9 sum two specs' tables). `S` is the
/// family's section type (the engine's view holds the sections' enum).
pub struct PlanView<'a, S> {
    /// The plan's output folder; spec `s` ran into `out/s`.
    pub out: &'a Path,
    /// The plan's specs of this family, in plan order, each with its section.
    pub specs: Vec<(&'a Spec, &'a S)>,
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
    /// variants can be ranked like optimisers. Full dotted keys (`optimise.generations`), or
    /// prefixes ending in a dot (`optimise.de.`: every key of that table).
    pub sweepable: fn() -> Vec<String>,
}

impl Overrides {
    /// Whether `--sweep` may vary `key` (a full dotted key, `optimise.de.f`).
    pub fn sweepable(&self, key: &str) -> bool {
        (self.sweepable)().iter().any(|p| {
            if p.ends_with('.') {
                key.starts_with(p.as_str())
            } else {
                key == p
            }
        })
    }

    /// The sweepable keys, for messages (`optimise.de.*, optimise.generations`).
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
}

/// A family's spec section (`[som]`, `[optimise]`, `[closed_cylinder]`, ...): how it is checked. The
/// section type lives in its family's folder.
pub trait Section: Placed {
    /// Check the bounds of the section's sizes and counts (before anything is allocated from
    /// them).
    fn limits(&self, c: &Check) -> Result<(), SpecError>;
    /// Check every value of the section (once the limits have passed).
    fn validate(&self, spec: &Spec) -> Result<(), SpecError>;
    /// The data-set entries of the section, as written (names or paths).
    fn datasets(&self) -> &[String] {
        &[]
    }
    /// Read the SOM maps from the folder `maps` (a plan whose earlier spec saved them).
    fn use_maps(&mut self, _maps: &str) {}
    /// See [`Family::require_inputs`]; by default nothing to check.
    fn require_inputs(&self, _spec: &Spec, _ctx: &RunContext) -> Result<()> {
        Ok(())
    }
    /// Whether the section takes `--set`/`--sweep` (None: it does not), and which keys a sweep
    /// may vary.
    const OVERRIDES: Option<Overrides> = None;
}

/// A family as it is written: its section type, its cells and its run, each given the spec and
/// the family's own section. Every `Experiment` is a [`Family`] (the engine's object-safe view)
/// through the blanket impl below, so a family writes none of the section plumbing itself.
pub trait Experiment: Sync + 'static {
    type Section: Section;
    /// See [`Family::logged_keys`].
    fn logged_keys(&self, spec: &Spec, s: &Self::Section) -> Vec<String>;
    /// Run the spec's cells of `ctx`'s slice; with `tables`, write the tables and pictures into
    /// `ctx.out` and return the REPORT.md section.
    fn run(
        &self,
        spec: &Spec,
        s: &Self::Section,
        ctx: &RunContext,
        tables: bool,
    ) -> Result<Outcome>;
    /// See [`Family::run_variants`]; by default a sweep is refused.
    fn run_variants(
        &self,
        variants: &[(&Spec, &Self::Section)],
        ctx: &RunContext,
        tables: bool,
    ) -> Result<Outcome> {
        match variants {
            [(spec, s)] => self.run(spec, s, ctx, tables),
            _ => anyhow::bail!(
                "--sweep: [{}] specs run one variant at a time (sweeps work on [optimise] specs)",
                Self::Section::NAME
            ),
        }
    }
    /// See [`Family::combine`]; by default nothing.
    fn combine(&self, _view: &PlanView<Self::Section>) -> Result<Combined> {
        Ok(Combined::default())
    }
    /// See [`Family::definitions`]; by default none.
    fn definitions(&self) -> super::Definitions {
        super::Definitions::default()
    }
    /// See [`Family::published`]; by default none.
    fn published(&self) -> Published {
        &[]
    }
    /// See [`Family::title`].
    fn title(&self) -> &'static str;
}

/// The message for a section handed to a family it does not belong to (the engine asks each
/// section's own family, so this is never seen).
fn foreign(name: &str) -> SpecError {
    SpecError::new(format!(
        "internal: a section that is not [{name}] was handed to the [{name}] family"
    ))
}

impl<F: Holds<E::Section>, E: Experiment> Family<F> for E {
    fn section(&self) -> &'static str {
        E::Section::NAME
    }
    fn check_limits(&self, c: &Check, s: &F) -> Result<(), SpecError> {
        s.get().ok_or_else(|| foreign(E::Section::NAME))?.limits(c)
    }
    fn datasets<'a>(&self, s: &'a F) -> Vec<&'a String> {
        s.get().map(|s| s.datasets().iter().collect()).unwrap_or_default()
    }
    fn use_maps(&self, s: &mut F, maps: &str) {
        if let Some(s) = s.get_mut() {
            s.use_maps(maps);
        }
    }
    fn require_inputs(&self, spec: &Spec, s: &F, ctx: &RunContext) -> Result<()> {
        s.get().ok_or_else(|| foreign(E::Section::NAME))?.require_inputs(spec, ctx)
    }
    fn validate(&self, spec: &Spec, s: &F) -> Result<(), SpecError> {
        s.get().ok_or_else(|| foreign(E::Section::NAME))?.validate(spec)
    }
    fn logged_keys(&self, spec: &Spec, s: &F) -> Vec<String> {
        s.get().map(|s| Experiment::logged_keys(self, spec, s)).unwrap_or_default()
    }
    fn run_variants(
        &self,
        variants: &[Loaded<F>],
        ctx: &RunContext,
        tables: bool,
    ) -> Result<Outcome> {
        let typed: Vec<(&Spec, &E::Section)> = variants
            .iter()
            .map(|v| Ok((&v.spec, v.section.get().ok_or_else(|| foreign(E::Section::NAME))?)))
            .collect::<Result<_, SpecError>>()?;
        Experiment::run_variants(self, &typed, ctx, tables)
    }
    fn overrides(&self) -> Option<Overrides> {
        E::Section::OVERRIDES
    }
    fn combine(&self, view: &PlanView<F>) -> Result<Combined> {
        let own = PlanView {
            out: view.out,
            specs: view.specs.iter().filter_map(|(spec, s)| Some((*spec, s.get()?))).collect(),
            reading: view.reading,
            readings: view.readings.clone(),
        };
        Experiment::combine(self, &own)
    }
    fn definitions(&self) -> super::Definitions {
        Experiment::definitions(self)
    }
    fn published(&self) -> Published {
        Experiment::published(self)
    }
    fn title(&self) -> &'static str {
        Experiment::title(self)
    }
}

/// The published table `name`, from whichever family of `F` compiles it in.
pub(crate) fn published<F: Families>(name: &str) -> Option<RefTable> {
    F::all().iter().find_map(|f| crate::report::reference::lookup(f.published(), name))
}

/// The section names, as `[som], [fit], ...`, for messages.
pub(crate) fn section_list<F: Families>() -> String {
    F::all().iter().map(|f| format!("[{}]", f.section())).collect::<Vec<_>>().join(", ")
}
