//! Experiment specs: TOML text -> raw serde structs (unknown keys rejected) -> a validated plan.
//!
//! A spec may carry named profiles (`[profiles.quick]`): tables deep-merged over the spec before it
//! is read, so a profile can change any key (e.g. `som.iterations = 3000`) and nothing else.
//! Errors are one line and name the file, the line and column, and the key at fault.

pub use super::grid_size::GridSize;
use super::overrides::apply_override;
pub use super::overrides::{CliOverrides, Override, Variant};
use std::fmt;
use std::path::Path;

/// A spec error: one line, naming the file and (where known) line:column and key.
#[derive(Debug, Clone, PartialEq)]
pub struct SpecError(pub String);

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SpecError {}

/// Declares the experiment families, once (invoked in `families/mod.rs`, the only list of
/// families): each family's module (the first part of its section's path: `som::spec::SomSpec`
/// is in folder `som/`), where each section type sits in the spec file
/// ([`Placed`](super::family::Placed)), and the [`Registry`](super::family::Registry) the engine
/// reaches the families through once `install()` has handed it over: the families in the order
/// their sections are named in messages, and the parser of the whole file (the header plus one
/// optional section per family, `deny_unknown_fields`, so serde names the file, line and column
/// of a bad key). A family is one folder plus one line here.
macro_rules! families {
    ($($(#[$doc:meta])* $field:ident: $module:ident :: $($section:ident)::+ => $($family:ident)::+),* $(,)?) => {
        $(pub mod $module;)*

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

        /// Parse a spec file's text: the header, and each section the file has.
        fn parse(text: &str) -> Result<$crate::experiment::spec::SpecFile, toml::de::Error> {
            let w: Whole = toml::from_str(text)?;
            let mut sections = $crate::experiment::family::Sections::default();
            $(if let Some(s) = w.$field {
                sections.insert(stringify!($field), Box::new(s));
            })*
            Ok($crate::experiment::spec::SpecFile {
                name: w.name,
                description: w.description,
                master_seed: w.master_seed,
                output: w.output,
                normalise: w.normalise,
                profiles: w.profiles,
                sections,
            })
        }

        /// The registry of every family the harness knows.
        pub static REGISTRY: $crate::experiment::family::Registry =
            $crate::experiment::family::Registry {
                families: &[$(&$($family)::+),*],
                parse,
            };

        /// Hand the families to the engine (once per process, before any spec is read).
        pub fn install() {
            $crate::experiment::family::install(&REGISTRY);
        }

        $(impl $crate::experiment::family::Placed for $module::$($section)::+ {
            const NAME: &'static str = stringify!($field);
        })*
    };
}
pub(crate) use families;

/// A spec file as read: the header every spec has, and the family sections it holds (one, once
/// validated; reached through [`Spec::section`]).
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
    /// The family sections the file has.
    pub sections: super::family::Sections,
}

/// The spec text parsed by the installed families' parser.
fn parse_file(text: &str) -> Result<SpecFile, toml::de::Error> {
    (super::family::registry().parse)(text)
}

/// A spec read from a file, with the profile applied.
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
}

/// A spec file's text (UTF-8; a UTF-16 or binary file is named as such).
pub(crate) fn read_spec(path: &Path) -> Result<String, SpecError> {
    let shown = path.display().to_string();
    let bytes =
        std::fs::read(path).map_err(|e| SpecError(format!("{shown}: cannot read spec: {e}")))?;
    crate::io::utf8_text(&shown, bytes).map_err(SpecError)
}

fn toml_error(path: &str, text: &str, e: &toml::de::Error) -> SpecError {
    SpecError(crate::io::toml_message(path, text, e))
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

impl Spec {
    /// This spec's section of type `S` (a family's), if it has one.
    pub fn section<S: super::family::Placed>(&self) -> Option<&S> {
        S::of(&self.file)
    }

    /// The same, or an error naming the missing section.
    pub fn require<S: super::family::Placed>(&self) -> anyhow::Result<&S> {
        use anyhow::Context;
        self.section().with_context(|| format!("spec has no [{}] section", S::NAME))
    }

    /// Parse spec text with a reading set's overrides applied after the profile (each validated
    /// as if written in the file); `path` is used in messages only.
    pub fn parse_with(
        path: &str,
        text: &str,
        profile: Option<&str>,
        overrides: &[Override],
    ) -> Result<Spec, SpecError> {
        let mut spec = Spec::parse(path, text, profile)?;
        if overrides.is_empty() {
            return Ok(spec);
        }
        let mut table: toml::Table =
            toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
        if let Some(over) = profile.and_then(|p| spec.file.profiles.get(p)) {
            merge(&mut table, &over.clone());
        }
        for o in overrides {
            apply_override(&mut table, o).map_err(|e| SpecError(format!("{path}: {e}")))?;
        }
        let merged = toml::to_string(&table).map_err(|e| SpecError(format!("{path}: {e}")))?;
        spec.file = parse_file(&merged).map_err(|e| {
            SpecError(format!(
                "{path}: with {}: {}",
                overrides.iter().map(|o| o.to_string()).collect::<Vec<_>>().join(", "),
                e.message().replace('\n', " ")
            ))
        })?;
        spec.validate()?;
        Ok(spec)
    }

    /// Parse spec text; `path` is used in messages only.
    pub fn parse(path: &str, text: &str, profile: Option<&str>) -> Result<Spec, SpecError> {
        let file = parse_file(text).map_err(|e| toml_error(path, text, &e))?;
        let file = match profile {
            None => file,
            Some(name) => {
                let over = file.profiles.get(name).ok_or_else(|| {
                    let known: Vec<&str> = file.profiles.keys().map(|s| s.as_str()).collect();
                    SpecError(format!(
                        "{path}: no profile `{name}` (the spec defines: {})",
                        if known.is_empty() { "none".to_string() } else { known.join(", ") }
                    ))
                })?;
                let mut table: toml::Table =
                    toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
                merge(&mut table, over);
                let merged =
                    toml::to_string(&table).map_err(|e| SpecError(format!("{path}: {e}")))?;
                parse_file(&merged).map_err(|e| {
                    SpecError(format!(
                        "{path}: [profiles.{name}]: {}",
                        e.message().replace('\n', " ")
                    ))
                })?
            }
        };
        let spec = Spec {
            file,
            text: text.to_string(),
            path: path.to_string(),
            profile: profile.map(String::from),
            cli: CliOverrides::default(),
            variant: Variant::default(),
        };
        spec.validate()?;
        Ok(spec)
    }

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

    /// Read and parse a spec file.
    pub fn load(path: &Path, profile: Option<&str>) -> Result<Spec, SpecError> {
        let shown = path.display().to_string();
        let text = read_spec(path)?;
        Spec::parse(&shown, &text, profile)
    }

    /// Read a spec file and make its variants ([`CliOverrides::variants`]).
    pub fn load_variants(
        path: &Path,
        profile: Option<&str>,
        cli: &CliOverrides,
    ) -> Result<Vec<Spec>, SpecError> {
        let shown = path.display().to_string();
        let text = read_spec(path)?;
        cli.variants(&shown, &text, profile)
    }

    /// An error naming the spec file and the key at fault.
    pub(crate) fn err(&self, key: &str, msg: impl fmt::Display) -> SpecError {
        SpecError(format!("{}: {key}: {msg}", self.path))
    }

    /// Checks every value once, so that a run never starts on a spec it would fail on later.
    pub fn validate(&self) -> Result<(), SpecError> {
        let f = &self.file;
        if f.name.trim().is_empty() || f.name.contains(['/', '\\']) {
            return Err(self.err("name", "must be a non-empty name without slashes"));
        }
        // Bounds, duplicates and names first: later checks allocate from sizes.
        super::limits::check(self)?;
        let families = super::family::present(self);
        match families.len() {
            0 => {
                return Err(SpecError(format!(
                    "{}: the spec has no experiment section (add one of {})",
                    self.path,
                    super::family::section_list()
                )))
            }
            1 => {}
            _ => {
                let names: Vec<String> =
                    families.iter().map(|f| format!("[{}]", f.section())).collect();
                return Err(SpecError(format!("{}: one experiment section per spec, this one has {} (they write the same files: split the spec)", self.path, names.join(" and "))));
            }
        }
        families[0].validate(self)
    }

    /// The checks every optimisation section shares: its optimiser names (from those `offered`),
    /// repeats, generations, and a population each optimiser the section runs can work with,
    /// each error naming `<section>.<key>` (the optimiser's own key where one sets the minimum).
    pub(crate) fn validate_runs(
        &self,
        section: &str,
        optimisers: &[String],
        offered: &[&dyn crate::optim::Optimiser],
        repeats: usize,
        generations: u64,
        population: usize,
    ) -> Result<(), SpecError> {
        let key = |k: &str| format!("{section}.{k}");
        let allowed = crate::optim::names(offered);
        if optimisers.is_empty() {
            return Err(self.err(&key("optimisers"), "is empty"));
        }
        let expected = match allowed.split_last() {
            Some((last, [])) => last.to_string(),
            Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
            None => String::new(),
        };
        for name in optimisers {
            if !allowed.contains(&name.as_str()) {
                return Err(self.err(
                    &key("optimisers"),
                    format!("unknown optimiser `{name}` (expected {expected})"),
                ));
            }
        }
        if repeats == 0 {
            return Err(self.err(&key("repeats"), "must be at least 1"));
        }
        if generations == 0 {
            return Err(self.err(&key("generations"), "must be at least 1"));
        }
        for name in optimisers {
            let Some(opt) = crate::optim::pick(offered, name) else { continue };
            let need = opt.min_population();
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
        Ok(())
    }

    /// The optimisers' own parameter checks, their keys placed under `section`.
    pub(crate) fn validate_optimiser_params<const N: usize>(
        &self,
        section: &str,
        checks: [Result<(), crate::optim::OptimError>; N],
    ) -> Result<(), SpecError> {
        for check in checks {
            check.map_err(|e| match e {
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
