//! Experiment specs: TOML text -> raw serde structs (unknown keys rejected) -> a validated plan.
//!
//! A spec may carry named profiles (`[profiles.quick]`): tables deep-merged over the spec before it
//! is read, so a profile can change any key (e.g. `som.iterations = 3000`) and nothing else.
//! Errors are one line and name the file, the line and column, and the key at fault.

use super::family::{Families, Family, Holds};
pub(crate) use super::grid_size::GridSize;
use super::overrides::apply_override;
pub(crate) use super::overrides::{CliOverrides, Override, Variant};
use std::fmt;
use std::path::Path;

/// A spec error: one line, naming the file and (where known) line:column and key.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecError {
    message: String,
    /// Set when the error is a profile the spec does not define: (the profile asked for, the
    /// profiles it defines), for a caller that answers it in its own terms (the Python suite).
    pub(crate) unknown_profile: Option<(String, Vec<String>)>,
}

impl SpecError {
    pub(crate) fn new(message: impl Into<String>) -> SpecError {
        SpecError { message: message.into(), unknown_profile: None }
    }
}

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for SpecError {}

/// Declares the experiment families, once (invoked in `families/mod.rs`, the only list of
/// families): each family's module (the first part of its section's path: `som::spec::SomSpec`
/// is in folder `som/`), where each section type sits in the spec file
/// ([`Placed`](super::family::Placed)), and `Section`, the enum of the families' sections (one
/// variant per family, named after its [`Experiment`](super::family::Experiment) type) that the
/// engine is generic over ([`Families`](super::family::Families)): the families in the order
/// their sections are named in messages, the parser of the whole file (the header plus one
/// optional section per family, `deny_unknown_fields`, so serde names the file, line and column
/// of a bad key), and each family's typed view of the enum ([`Holds`](super::family::Holds)).
/// A family is one folder plus one line here.
macro_rules! families {
    ($($(#[$doc:meta])* $field:ident $(($old:ident))?: $module:ident :: $($section:ident)::+ => $fmod:ident :: $family:ident),* $(,)?) => {
        $(pub mod $module;)*

        /// The section of a spec: one variant per family, holding its checked section type.
        #[derive(Debug, Clone)]
        pub enum Section {
            $($(#[$doc])* $family($module::$($section)::+),)*
        }

        /// A spec as the engine holds it, with the families of this harness.
        pub type Loaded = $crate::experiment::spec::Loaded<Section>;

        /// The whole spec file as written: the header and one optional section per family.
        #[derive(serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Whole {
            name: String,
            #[serde(default)]
            description: String,
            master_seed: u64,
            #[serde(default)]
            output: Option<String>,
            #[serde(default)]
            normalise: $crate::data::Normalise,
            $($(#[$doc])* #[serde(default)] $field: Option<$module::$($section)::+>,)*
            #[serde(default)]
            profiles: std::collections::BTreeMap<String, toml::Table>,
        }

        impl $crate::experiment::family::Families for Section {
            fn all() -> &'static [&'static dyn $crate::experiment::family::Family<Section>] {
                &[$(&$fmod::$family),*]
            }

            fn renamed() -> &'static [(&'static str, &'static str)] {
                &[$($((stringify!($old), stringify!($field)),)?)*]
            }

            fn parse(
                text: &str,
            ) -> Result<($crate::experiment::spec::SpecFile, Vec<Section>), toml::de::Error> {
                let w: Whole = toml::from_str(text)?;
                let mut sections = Vec::new();
                $(if let Some(s) = w.$field {
                    sections.push(Section::$family(s));
                })*
                let file = $crate::experiment::spec::SpecFile {
                    name: w.name,
                    description: w.description,
                    master_seed: w.master_seed,
                    output: w.output,
                    normalise: w.normalise,
                    profiles: w.profiles,
                };
                Ok((file, sections))
            }

            fn family(&self) -> &'static dyn $crate::experiment::family::Family<Section> {
                match self {
                    $(Section::$family(_) => &$fmod::$family,)*
                }
            }
        }

        $(impl $crate::experiment::family::Holds<$module::$($section)::+> for Section {
            fn get(&self) -> Option<&$module::$($section)::+> {
                #[allow(irrefutable_let_patterns)]
                if let Section::$family(s) = self { Some(s) } else { None }
            }
            fn get_mut(&mut self) -> Option<&mut $module::$($section)::+> {
                #[allow(irrefutable_let_patterns)]
                if let Section::$family(s) = self { Some(s) } else { None }
            }
        }

        impl $crate::experiment::family::Placed for $module::$($section)::+ {
            const NAME: &'static str = stringify!($field);
        })*
    };
}
pub(crate) use families;

/// A spec file's header, as read (the family section beside it is in [`Loaded`]).
#[derive(Debug, Clone)]
pub struct SpecFile {
    /// Experiment name; the default output folder is `results/<name>`.
    pub name: String,
    pub description: String,
    /// Master seed every (cell, repeat) stream is derived from.
    pub master_seed: u64,
    /// Output folder (overridden by `--out`).
    pub output: Option<String>,
    /// How the data sets are scaled: per_axis (the thesis), uniform (aspect ratios kept) or none.
    pub normalise: crate::data::Normalise,
    /// Named overrides, merged over the spec by `--profile NAME`.
    pub profiles: std::collections::BTreeMap<String, toml::Table>,
}

/// A spec read from a file, with the profile applied: what every family's method is given beside
/// its own section (the engine holds both in a [`Loaded`]).
#[derive(Debug, Clone)]
pub struct Spec {
    pub file: SpecFile,
    /// The spec's text as read (kept in the manifest).
    pub text: String,
    pub path: String,
    pub profile: Option<String>,
    /// The command line's `--set`/`--sweep` as written (empty for a plain run).
    pub cli: CliOverrides,
    /// Which variant of the spec this is: its `key=value` changes (empty for a plain run).
    pub variant: Variant,
    /// A plan's reading set's keys that reached this spec, with their values (empty outside a
    /// reading set): kept in the fingerprint, so `report` and `--resume` apply them again.
    pub readings: std::collections::BTreeMap<String, toml::Value>,
}

/// A spec file's text (UTF-8; a UTF-16 or binary file is named as such).
pub(crate) fn read_spec(path: &Path) -> Result<String, SpecError> {
    let shown = path.display().to_string();
    let bytes =
        crate::io::input::read(path, crate::io::input::Kind::Toml).map_err(|e| match e {
            crate::io::input::InputError::NotFound { .. } => {
                SpecError::new(format!("{shown}: cannot read spec: no such file"))
            }
            e => SpecError::new(format!("cannot read spec: {e}")),
        })?;
    crate::io::utf8_text(&shown, bytes).map_err(SpecError::new)
}

fn toml_error(path: &str, text: &str, e: &toml::de::Error) -> SpecError {
    SpecError::new(crate::io::toml_message(path, text, e))
}

/// Deep-merge `over` into `base` (tables merge, everything else replaces).
fn merge(base: &mut toml::Table, over: &toml::Table) {
    for (k, v) in over {
        match (base.get_mut(k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) => merge(b, o),
            _ => {
                base.insert(k.clone(), v.clone());
            }
        }
    }
}

/// A spec as the engine holds it: the spec (header, text, profile, variant) and its one family
/// section, parsed into its own type and checked once, by [`Loaded::parse`] and its kin. `F` is
/// the enum of the harness' families' sections (`families::Section`).
#[derive(Debug, Clone)]
pub struct Loaded<F> {
    pub spec: Spec,
    pub section: F,
}

impl<F: Families> Loaded<F> {
    /// The family of the spec's section.
    pub fn family(&self) -> &'static dyn Family<F> {
        self.section.family()
    }

    /// The section as the family type `S`, if the spec's section is one.
    pub fn section_as<S>(&self) -> Option<&S>
    where
        F: Holds<S>,
    {
        self.section.get()
    }

    /// Parse spec text with a reading set's overrides applied after the profile (each validated
    /// as if written in the file); `path` is used in messages only.
    pub fn parse_with(
        path: &str,
        text: &str,
        profile: Option<&str>,
        overrides: &[Override],
    ) -> Result<Loaded<F>, SpecError> {
        Loaded::parse_reaching(path, text, profile, overrides).map(|(spec, _)| spec)
    }

    /// [`Loaded::parse_with`], and for each override whether it reached the spec (`false`: the
    /// spec has no section of its key, so it was skipped).
    pub(crate) fn parse_reaching(
        path: &str,
        text: &str,
        profile: Option<&str>,
        overrides: &[Override],
    ) -> Result<(Loaded<F>, Vec<bool>), SpecError> {
        let (canonical, made) = super::renamed::canonical_text::<F>(text);
        super::renamed::note(path, &made);
        let spec = Loaded::parse_canonical(path, text, &canonical, profile)?;
        if overrides.is_empty() {
            return Ok((spec, Vec::new()));
        }
        let text = canonical.as_ref();
        let mut table: toml::Table =
            toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        if let Some(over) = profile.and_then(|p| spec.spec.file.profiles.get(p)) {
            merge(&mut table, &over.clone());
        }
        let mut reached = Vec::with_capacity(overrides.len());
        for o in overrides {
            let key = super::renamed::canonical_key::<F>(&o.key).into_owned();
            let o = Override { key, value: o.value.clone() };
            reached.push(
                apply_override(&mut table, &o)
                    .map_err(|e| SpecError::new(format!("{path}: {e}")))?,
            );
        }
        let merged = toml::to_string(&table).map_err(|e| SpecError::new(format!("{path}: {e}")))?;
        let (file, sections) = F::parse(&merged).map_err(|e| {
            SpecError::new(format!(
                "{path}: with {}: {}",
                overrides.iter().map(|o| o.to_string()).collect::<Vec<_>>().join(", "),
                e.message().replace('\n', " ")
            ))
        })?;
        let readings = overrides
            .iter()
            .zip(&reached)
            .filter(|(_, r)| **r)
            .map(|(o, _)| (o.key.clone(), o.value.clone()))
            .collect();
        Ok((Loaded::checked(Spec { file, readings, ..spec.spec }, sections)?, reached))
    }

    /// Parse spec text; `path` is used in messages only.
    pub fn parse(path: &str, text: &str, profile: Option<&str>) -> Result<Loaded<F>, SpecError> {
        let (canonical, made) = super::renamed::canonical_text::<F>(text);
        super::renamed::note(path, &made);
        Loaded::parse_canonical(path, text, &canonical, profile)
    }

    /// [`Loaded::parse`] of a spec as `written`, whose former section names are already replaced
    /// in `text` ([`super::renamed::canonical_text`]).
    fn parse_canonical(
        path: &str,
        written: &str,
        text: &str,
        profile: Option<&str>,
    ) -> Result<Loaded<F>, SpecError> {
        let (file, sections) = F::parse(text).map_err(|e| toml_error(path, text, &e))?;
        let (file, sections) = match profile {
            None => (file, sections),
            Some(name) => {
                let over = file.profiles.get(name).ok_or_else(|| {
                    let known: Vec<String> = file.profiles.keys().cloned().collect();
                    SpecError {
                        unknown_profile: Some((name.to_string(), known.clone())),
                        ..SpecError::new(format!(
                            "{path}: no profile `{name}` (the spec defines: {})",
                            if known.is_empty() { "none".to_string() } else { known.join(", ") }
                        ))
                    }
                })?;
                let mut table: toml::Table =
                    toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
                merge(&mut table, over);
                let merged =
                    toml::to_string(&table).map_err(|e| SpecError::new(format!("{path}: {e}")))?;
                F::parse(&merged).map_err(|e| {
                    SpecError::new(format!(
                        "{path}: [profiles.{name}]: {}",
                        e.message().replace('\n', " ")
                    ))
                })?
            }
        };
        let spec = Spec {
            file,
            text: written.to_string(),
            path: path.to_string(),
            profile: profile.map(String::from),
            cli: CliOverrides::default(),
            variant: Variant::default(),
            readings: Default::default(),
        };
        Loaded::checked(spec, sections)
    }

    /// Read and parse a spec file.
    pub fn load(path: &Path, profile: Option<&str>) -> Result<Loaded<F>, SpecError> {
        let shown = path.display().to_string();
        let text = read_spec(path)?;
        Loaded::parse(&shown, &text, profile)
    }

    /// Read a spec file and make its variants ([`CliOverrides::variants`]).
    pub fn load_variants(
        path: &Path,
        profile: Option<&str>,
        cli: &CliOverrides,
    ) -> Result<Vec<Loaded<F>>, SpecError> {
        let shown = path.display().to_string();
        let text = read_spec(path)?;
        cli.variants(&shown, &text, profile)
    }

    /// Checks every value once, so that a run never starts on a spec it would fail on later: the
    /// name, the spec's one family section, its bounds (before anything is allocated from a
    /// size) and then every value.
    fn checked(spec: Spec, sections: Vec<F>) -> Result<Loaded<F>, SpecError> {
        let f = &spec.file;
        if f.name.trim().is_empty() || f.name.contains(['/', '\\']) {
            return Err(spec.err("name", "must be a non-empty name without slashes"));
        }
        if sections.len() != 1 {
            return Err(section_count_error(&spec, &sections));
        }
        let Some(section) = sections.into_iter().next() else {
            return Err(section_count_error::<F>(&spec, &[]));
        };
        super::limits::check(&spec, &section)?;
        section.family().validate(&spec, &section)?;
        Ok(Loaded { spec, section })
    }
}

/// The error for a spec with no family section, or more than one.
fn section_count_error<F: Families>(spec: &Spec, sections: &[F]) -> SpecError {
    if sections.is_empty() {
        return SpecError::new(format!(
            "{}: the spec has no experiment section (add one of {})",
            spec.path,
            super::family::section_list::<F>()
        ));
    }
    let names: Vec<String> =
        sections.iter().map(|s| format!("[{}]", s.family().section())).collect();
    SpecError::new(format!(
        "{}: one experiment section per spec, this one has {} (they write the same files: split the spec)",
        spec.path,
        names.join(" and ")
    ))
}

impl Spec {
    /// What the profile changes from the spec as written: each leaf key it sets, its value,
    /// and whether that reduces the run (a smaller number, or a shorter list, than the spec's).
    pub fn profile_changes(&self) -> Vec<ProfileChange> {
        let Some(over) = self.profile.as_deref().and_then(|p| self.file.profiles.get(p)) else {
            return Vec::new();
        };
        let base: toml::Table = toml::from_str(&self.text).unwrap_or_default();
        let mut out = Vec::new();
        profile_leaves(&base, over, "", &mut out);
        out
    }

    /// Whether the profile reduces the run in any key (see [`Spec::profile_changes`]).
    pub fn reduced(&self) -> bool {
        self.profile_changes().iter().any(|c| c.reduces)
    }

    /// An error naming the spec file and the key at fault.
    pub(crate) fn err(&self, key: &str, msg: impl fmt::Display) -> SpecError {
        SpecError::new(format!("{}: {key}: {msg}", self.path))
    }

    /// The checks every optimisation section shares: its optimisers (names checked when read),
    /// repeats, generations, a population each optimiser the section runs can work with, and every
    /// parameter table ([`Spec::validate_optimiser_params`]), each error naming `<section>.<key>`
    /// (the optimiser's own key where one sets the minimum).
    pub(crate) fn validate_runs(
        &self,
        section: &str,
        optimisers: &[crate::optim::Name],
        tables: &crate::optim::Tables,
        repeats: usize,
        generations: u64,
        population: usize,
    ) -> Result<(), SpecError> {
        let key = |k: &str| format!("{section}.{k}");
        if optimisers.is_empty() {
            return Err(self.err(&key("optimisers"), "is empty"));
        }
        if repeats == 0 {
            return Err(self.err(&key("repeats"), "must be at least 1"));
        }
        if generations == 0 {
            return Err(self.err(&key("generations"), "must be at least 1"));
        }
        for &name in optimisers {
            let need = tables.get(name).min_population();
            if population >= need.n {
                continue;
            }
            return Err(match need.key {
                Some(k) => self.err(
                    &key(&format!("{name}.{k}")),
                    format!(
                        "{} is above {} = {population} ({})",
                        need.n,
                        key("population"),
                        need.why
                    ),
                ),
                None => self.err(
                    &key("population"),
                    format!(
                        "must be at least {} for {name} ({}), got {population}",
                        need.n, need.why
                    ),
                ),
            });
        }
        self.validate_optimiser_params(section, &tables.all())
    }

    /// The parameter tables of the optimisers a section offers ([`crate::optim::Optimiser::validate`]),
    /// their keys placed under `section`.
    pub(crate) fn validate_optimiser_params(
        &self,
        section: &str,
        offered: &[&dyn crate::optim::Optimiser],
    ) -> Result<(), SpecError> {
        for opt in offered {
            opt.validate().map_err(|e| match e {
                crate::optim::OptimError::InvalidParameter { key, message } => {
                    self.err(&format!("{section}.{key}"), message)
                }
                other => self.err(section, other),
            })?;
        }
        Ok(())
    }

    /// The folder of the spec file, against which every relative path it names resolves.
    pub fn dir(&self) -> &Path {
        Path::new(&self.path).parent().unwrap_or(Path::new(""))
    }

    /// A path the spec names, resolved against the spec's folder (an absolute path stays).
    pub fn resolve(&self, path: &str) -> std::path::PathBuf {
        self.dir().join(path)
    }

    /// Output folder: `--out`, else the spec's `output`, else `results/<name>`.
    pub fn output_dir(&self, out: Option<&Path>) -> std::path::PathBuf {
        match (out, &self.file.output) {
            (Some(o), _) => o.to_path_buf(),
            (None, Some(o)) => o.into(),
            (None, None) => Path::new("results").join(&self.file.name),
        }
    }
}

#[cfg(test)]
#[path = "spec_tests.rs"]
mod tests;

/// One key a profile sets (see [`Spec::profile_changes`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileChange {
    pub key: String,
    pub value: String,
    pub reduces: bool,
}

fn profile_leaves(base: &toml::Table, over: &toml::Table, at: &str, out: &mut Vec<ProfileChange>) {
    for (k, v) in over {
        let key = if at.is_empty() { k.clone() } else { format!("{at}.{k}") };
        let was = base.get(k);
        match (v, was) {
            (toml::Value::Table(t), Some(toml::Value::Table(b))) => profile_leaves(b, t, &key, out),
            (toml::Value::Table(t), _) => profile_leaves(&toml::Table::new(), t, &key, out),
            _ => {
                let num =
                    |x: &toml::Value| x.as_float().or_else(|| x.as_integer().map(|i| i as f64));
                let reduces = match (v, was) {
                    (toml::Value::Array(a), Some(toml::Value::Array(b))) => a.len() < b.len(),
                    (x, Some(y)) => matches!((num(x), num(y)), (Some(a), Some(b)) if a < b),
                    _ => false,
                };
                out.push(ProfileChange { key, value: v.to_string(), reduces });
            }
        }
    }
}
