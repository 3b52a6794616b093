//! The command line's and the plans' changes to a spec: `--set KEY=VALUE`, `--sweep
//! KEY=V1,V2,...` and a reading set's dotted keys, each applied to the spec's TOML table after
//! its profile and validated exactly as the file's own value.

use super::family::Families;
use super::spec::{Loaded, SpecError};
use std::fmt;

/// The command line's changes to a spec, as written: `--set KEY=VALUE` (one value) and
/// `--sweep KEY=V1,V2,...` (every combination of the swept values is one variant, all run into
/// one folder). Recorded in the fingerprint and the manifest, so `--resume` and `merge` rebuild
/// the same variants.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CliOverrides {
    pub set: Vec<String>,
    pub sweep: Vec<String>,
}

/// One variant of a spec: the `key=value` changes of `--set` and those of `--sweep`, as written.
/// A plain run has none, and its cell keys and seeds are those of the spec alone.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Variant {
    pub set: Vec<String>,
    pub swept: Vec<String>,
}

impl Variant {
    /// What the cell keys (so the seeds) carry: every change, `--set` first (empty: plain run).
    pub fn key(&self) -> String {
        self.set.iter().chain(&self.swept).cloned().collect::<Vec<_>>().join(",")
    }

    /// The `variant` column of a sweep's rows: the swept values (empty without `--sweep`).
    pub fn label(&self) -> String {
        self.swept.join(",")
    }

    /// [`label`](Self::label) of the swept settings whose key `reaches` a cell (`KEY=VALUE`
    /// entries): a cell no swept setting reaches is the same in every variant, so it has none.
    pub fn label_reaching(&self, reaches: impl Fn(&str) -> bool) -> String {
        let reaching =
            self.swept.iter().filter(|a| reaches(a.split_once('=').map_or(a, |(k, _)| k)));
        reaching.cloned().collect::<Vec<_>>().join(",")
    }
}

/// A command-line value as TOML (a number, a boolean, a quoted string, an array), else the text
/// itself as a string (so `--set optimise.knots=nurbs_book` needs no quotes).
fn cli_value(raw: &str) -> toml::Value {
    match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t.remove("v").unwrap_or_else(|| toml::Value::String(raw.to_string())),
        Err(_) => toml::Value::String(raw.to_string()),
    }
}

/// Whether two command-line values are the same setting: equal TOML values, an integer and a
/// float of the same number counting as one (`1` and `1.0`), arrays and tables element-wise.
fn same_value(a: &toml::Value, b: &toml::Value) -> bool {
    use toml::Value::{Array, Float, Integer, Table};
    match (a, b) {
        (Integer(i), Float(f)) | (Float(f), Integer(i)) => *i as f64 == *f,
        (Float(x), Float(y)) => x == y || (x.is_nan() && y.is_nan()),
        (Array(x), Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same_value(p, q))
        }
        (Table(x), Table(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same_value(v, w)))
        }
        _ => a == b,
    }
}

/// What the note on a `--set`/`--sweep` key with a former section name names in place of a file.
const KEYS_NOTED_AS: &str = "--set/--sweep";

impl CliOverrides {
    pub fn is_empty(&self) -> bool {
        self.set.is_empty() && self.sweep.is_empty()
    }

    /// Split `KEY=VALUE` (or `KEY=V1,V2` for a sweep) of `flag`, naming the flag on error.
    fn split<'a>(flag: &str, arg: &'a str) -> Result<(&'a str, &'a str), SpecError> {
        match arg.split_once('=') {
            Some((k, v)) if !k.trim().is_empty() && !v.trim().is_empty() => {
                Ok((k.trim(), v.trim()))
            }
            _ => Err(SpecError::new(format!(
                "{flag} `{arg}`: expected KEY=VALUE, e.g. optimise.de.f=0.5"
            ))),
        }
    }

    /// A `--sweep KEY=V1,V2,...`: its key and values, none empty and none the same setting as
    /// another (`0.3` and `0.30`, `1` and `1.0` are one value).
    fn sweep_values(arg: &str) -> Result<(&str, Vec<&str>), SpecError> {
        let (key, values) = Self::split("--sweep", arg)?;
        let values: Vec<&str> = values.split(',').map(str::trim).collect();
        if values.iter().any(|v| v.is_empty()) {
            return Err(SpecError::new(format!("--sweep {key}: an empty value in `{arg}`")));
        }
        if values.len() > super::limits::MAX_LIST {
            return Err(SpecError::new(format!(
                "--sweep {key}: {} values, above the limit {}",
                values.len(),
                super::limits::MAX_LIST
            )));
        }
        let parsed: Vec<toml::Value> = values.iter().map(|v| cli_value(v)).collect();
        for (k, v) in parsed.iter().enumerate() {
            if let Some(j) = parsed[..k].iter().position(|w| same_value(v, w)) {
                let (a, b) = (values[j], values[k]);
                let shown = if a == b {
                    format!("the value {a} is given twice")
                } else {
                    format!("{a} and {b} are one value, given twice")
                };
                return Err(SpecError::new(format!("--sweep {key}: {shown}")));
            }
        }
        Ok((key, values))
    }

    /// The variants of the spec at `path` (its text and profile): one for a plain run or `--set`
    /// only, else one per combination of the swept values (the first `--sweep` outermost). Each
    /// is parsed and validated exactly as if its values were written in the file; an unknown key,
    /// a bad value, a key given twice or a swept value given twice is a one-line error naming
    /// the key.
    pub fn variants<F: Families>(
        &self,
        path: &str,
        text: &str,
        profile: Option<&str>,
    ) -> Result<Vec<Loaded<F>>, SpecError> {
        let base = Loaded::<F>::parse(path, text, profile)?;
        if self.is_empty() {
            return Ok(vec![base]);
        }
        let flags =
            self.set.iter().map(|a| ("--set", a)).chain(self.sweep.iter().map(|a| ("--sweep", a)));
        let mut seen: Vec<(&str, String)> = Vec::new();
        let mut renamed = Vec::new();
        for (flag, arg) in flags {
            let (key, _) = Self::split(flag, arg)?;
            let canonical = super::renamed::canonical_key::<F>(key);
            if let Some((before, _)) = seen.iter().find(|(_, c)| *c == canonical) {
                let why = super::renamed::both_spellings::<F>(before, key).unwrap_or_else(|| {
                    "the key is given twice (--set and --sweep take each key once)".into()
                });
                return Err(SpecError::new(format!("{flag} {key}: {why}")));
            }
            seen.push((key, canonical.clone().into_owned()));
            renamed.extend(super::renamed::renamed_key::<F>(key).map(|(_, pair)| pair));
            // The sections that take --set/--sweep, as the families declare them.
            let takers: Vec<_> =
                F::all().iter().filter_map(|f| f.overrides().map(|o| (*f, o))).collect();
            let list = takers
                .iter()
                .map(|(f, _)| format!("[{0}] section ({0}.KEY)", f.section()))
                .collect::<Vec<_>>()
                .join(", ");
            let section = canonical.split('.').next().unwrap_or("");
            let Some((family, ov)) = takers.iter().find(|(f, _)| f.section() == section) else {
                return Err(SpecError::new(format!(
                    "{flag} {key}: only keys of the {list} can be set or swept"
                )));
            };
            if family.section() != base.family().section() {
                return Err(SpecError::new(format!(
                    "{flag} {key}: {path} has no [{section}] section (--set and --sweep work on \
                     specs with one)"
                )));
            }
            if flag == "--sweep" && !ov.sweepable(&canonical) {
                return Err(SpecError::new(format!("{flag} {key}: a sweep varies optimiser settings only ({}), so that every variant solves the same problems", ov.describe())));
            }
        }
        let set: Vec<(String, String)> = self
            .set
            .iter()
            .map(|a| Self::split("--set", a).map(|(k, v)| (k.to_string(), v.to_string())))
            .collect::<Result<_, _>>()?;
        let sweeps: Vec<(&str, Vec<&str>)> =
            self.sweep.iter().map(|a| Self::sweep_values(a)).collect::<Result<_, _>>()?;
        // The number of variants, before any is made.
        let variants = sweeps.iter().fold(1u64, |n, (_, v)| n.saturating_mul(v.len() as u64));
        if variants > super::limits::MAX_VARIANTS {
            let counts: Vec<String> = sweeps.iter().map(|(_, v)| v.len().to_string()).collect();
            return Err(SpecError::new(format!(
                "--sweep: {} = {variants} variants, above the limit {}",
                counts.join(" x "),
                super::limits::MAX_VARIANTS
            )));
        }
        // Every combination of the swept values, the first sweep outermost.
        let mut combos: Vec<Vec<(String, String)>> = vec![Vec::new()];
        for (key, values) in &sweeps {
            combos = combos
                .into_iter()
                .flat_map(|c| {
                    values
                        .iter()
                        .map(move |v| [c.clone(), vec![(key.to_string(), v.to_string())]].concat())
                })
                .collect();
        }
        let mut cells = 0u64;
        let loaded: Vec<Loaded<F>> = combos
            .into_iter()
            .map(|swept| {
                let overrides: Vec<Override> = set
                    .iter()
                    .chain(&swept)
                    .map(|(k, v)| Override { key: k.clone(), value: cli_value(v) })
                    .collect();
                let mut spec = Loaded::<F>::parse_with(path, text, profile, &overrides)?;
                cells = cells.saturating_add(super::limits::cell_count(&spec));
                if cells > super::limits::MAX_CELLS {
                    return Err(SpecError::new(format!(
                        "--sweep: the {variants} variants of {path} have at least {cells} cells \
                         in all, above the limit {} (the limit of one spec holds for all its \
                         variants together)",
                        super::limits::MAX_CELLS
                    )));
                }
                spec.spec.cli = self.clone();
                let pairs = |l: &[(String, String)]| {
                    l.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>()
                };
                spec.spec.variant = Variant { set: pairs(&set), swept: pairs(&swept) };
                Ok(spec)
            })
            .collect::<Result<_, SpecError>>()?;
        // Said once the keys are taken, so that a refusal stays one line.
        super::renamed::note(KEYS_NOTED_AS, &renamed);
        Ok(loaded)
    }
}

/// One change to a spec by a dotted key (`fit.knots`, `optimise.de.f`), as a reading set of a plan
/// makes it: applied after the profile and validated exactly as the file's own value.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    pub key: String,
    pub value: toml::Value,
}

impl fmt::Display for Override {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {}", self.key, self.value)
    }
}

/// Apply `over` to a spec table. A key whose section (first part) the spec does not have is
/// skipped (a reading set names keys of several families) and reported as `false`.
pub(crate) fn apply_override(table: &mut toml::Table, over: &Override) -> Result<bool, String> {
    let parts: Vec<&str> = over.key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(format!("`{}` is not a dotted key", over.key));
    }
    if parts.len() > 1 && !matches!(table.get(parts[0]), Some(toml::Value::Table(_))) {
        return Ok(false);
    }
    let mut t = table;
    for p in &parts[..parts.len() - 1] {
        let entry =
            t.entry(p.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
        t = match entry {
            toml::Value::Table(inner) => inner,
            _ => return Err(format!("`{}`: `{p}` is not a table", over.key)),
        };
    }
    t.insert(parts[parts.len() - 1].to_string(), over.value.clone());
    Ok(true)
}
