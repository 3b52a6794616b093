//! `somnurbs reproduce`: the thesis' chapters in order, each spec in its own sub-folder, the maps
//! of Chapter 4 feeding Chapters 5 and 6, then one REPORT.md that joins the chapters' reports
//! and adds one table of the claims with their verdicts, the readings matrix, and what each
//! family computes over several of its specs ([`Family::combine`]: Tables 6.8 and 6.9 sum
//! Tables 6.4 + 6.5 and 6.6 + 6.7). The list of specs is data (`experiments/thesis.toml`).
//!
//! [`Family::combine`]: super::family::Family::combine

use super::family::{Combined, Families, PlanView, ReadingRun};
use super::readings::{self as registry, AS_WRITTEN};
use super::spec::{Loaded, Override, Spec};
use super::{run_spec, Claimed, RunContext};
use crate::io::outdir::PLAN_FILE;
use crate::io::{csv_records, write_atomic};
use crate::report::claims::{self, Claim};
use anyhow::{Context, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A plan: `experiments/thesis.toml` (Chapters 4-6), `seeds.toml`, `all.toml`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Plan {
    /// The combined report's title.
    #[serde(default = "default_title")]
    pub(crate) title: String,
    /// Spec names (files `<name>.toml` beside the plan), run in this order.
    pub(crate) specs: Vec<String>,
    /// The spec whose `maps/` folder the later specs read (plans with Chapters 5 or 6).
    #[serde(default)]
    pub(crate) maps_from: Option<String>,
    /// The name of the readings the specs make as written (a row label of the readings matrix).
    #[serde(default = "default_reading")]
    pub(crate) reading: String,
    /// Other reading sets: each runs the specs it names again with its overrides, into
    /// `readings/<name>/`, and the report sets every claim under every reading side by side.
    #[serde(default)]
    pub(crate) readings: Vec<ReadingSet>,
}

/// A named set of readings (docs/readings.md): dotted spec keys and the values to use.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ReadingSet {
    pub(crate) name: String,
    #[serde(default)]
    pub(crate) description: String,
    /// E.g. `"fit.knots" = "nurbs_book"`; a key is applied to the specs that have its section.
    pub(crate) set: std::collections::BTreeMap<String, toml::Value>,
    /// Which of the plan's specs run under this set.
    pub(crate) specs: Vec<String>,
}

impl ReadingSet {
    fn overrides(&self) -> Vec<Override> {
        self.set.iter().map(|(k, v)| Override { key: k.clone(), value: v.clone() }).collect()
    }
}

fn default_reading() -> String {
    "as_written".into()
}

/// A reading-set name is a folder name: lower-case letters, digits and `_`.
fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
}

fn default_title() -> String {
    "reproduction of the thesis".into()
}

/// Where each entry of a plan's `specs` is written in its file (for messages).
#[derive(Deserialize)]
struct SpecSpans {
    specs: Vec<toml::Spanned<String>>,
}

/// Why `name` cannot name a spec of a plan: a spec is the file `<name>.toml` in the plan's own
/// folder, so a name holds no folder part (no `/` or `\`, not `.` or `..`, not absolute) and
/// nothing outside that folder is read.
fn spec_name_fault(name: &str) -> Option<&'static str> {
    if name.trim().is_empty() {
        Some("is empty")
    } else if Path::new(name).is_absolute() {
        Some("is an absolute path")
    } else if name.contains(['/', '\\']) {
        Some("holds a folder part")
    } else if name == "." || name == ".." {
        Some("is a folder")
    } else {
        None
    }
}

impl Plan {
    pub(crate) fn load(path: &Path) -> Result<Plan> {
        let text = crate::io::read_text_of(path, crate::io::input::Kind::Toml)?;
        let shown = path.display().to_string();
        let plan: Plan = toml::from_str(&text)
            .map_err(|e| anyhow::Error::msg(crate::io::toml_message(&shown, &text, &e)))?;
        if plan.specs.is_empty() {
            anyhow::bail!("{shown}: specs: is empty");
        }
        if let Some((k, fault)) =
            plan.specs.iter().enumerate().find_map(|(k, s)| spec_name_fault(s).map(|f| (k, f)))
        {
            let line = toml::from_str::<SpecSpans>(&text)
                .ok()
                .and_then(|s| s.specs.get(k).map(|s| s.span().start))
                .map(|at| format!("{}:", text[..at.min(text.len())].matches('\n').count() + 1))
                .unwrap_or_default();
            anyhow::bail!(
                "{shown}:{line} specs: `{}` {fault}; a plan runs only the specs in its own folder, \
                 each named by its file name without .toml (no `/`, `\\`, `.` or `..`): copy the \
                 spec into {} and name it there",
                plan.specs[k],
                path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")).display()
            );
        }
        if let Some(s) = twice(&plan.specs) {
            anyhow::bail!("{}: specs: `{s}` is listed twice", path.display());
        }
        if let Some(m) = plan.maps_from.as_ref().filter(|m| !plan.specs.contains(m)) {
            anyhow::bail!("{}: maps_from: `{m}` is not one of the specs", path.display());
        }
        let mut names = vec![plan.reading.as_str()];
        for r in &plan.readings {
            if !valid_name(&r.name) {
                anyhow::bail!(
                    "{}: readings: name `{}` must be lower-case letters, digits and _",
                    path.display(),
                    r.name
                );
            }
            if names.contains(&r.name.as_str()) {
                anyhow::bail!("{}: readings: the name `{}` is used twice", path.display(), r.name);
            }
            names.push(&r.name);
            if let Some(s) = twice(&r.specs) {
                anyhow::bail!(
                    "{}: readings.{}.specs: `{s}` is listed twice",
                    path.display(),
                    r.name
                );
            }
            if let Some(s) = r.specs.iter().find(|s| !plan.specs.contains(s)) {
                anyhow::bail!(
                    "{}: readings.{}.specs: `{s}` is not one of the plan's specs",
                    path.display(),
                    r.name
                );
            }
            if r.specs.is_empty() {
                anyhow::bail!(
                    "{}: readings.{}.specs: is empty; list the plan's specs this set runs again \
                     (e.g. specs = [\"{}\"]) or remove the set",
                    path.display(),
                    r.name,
                    plan.specs[0]
                );
            }
            if r.set.is_empty() {
                anyhow::bail!("{}: readings.{}.set: is empty", path.display(), r.name);
            }
        }
        Ok(plan)
    }
}

/// The first entry of `list` that an earlier one repeats.
fn twice(list: &[String]) -> Option<&String> {
    list.iter().enumerate().find(|(k, s)| list[..*k].contains(s)).map(|(_, s)| s)
}

/// The loaded specs of a plan, before anything runs: no two with one `name` (they would share an
/// output folder), and at most [`MAX_PLAN_CELLS`](super::limits::MAX_PLAN_CELLS) cells in all,
/// the reading sets' runs included.
fn check_specs<F: Families>(
    plan_path: &Path,
    specs: &[Loaded<F>],
    readings: &[(&ReadingSet, Vec<Loaded<F>>)],
) -> Result<()> {
    for list in std::iter::once(specs).chain(readings.iter().map(|(_, r)| r.as_slice())) {
        for (k, spec) in list.iter().enumerate() {
            let spec = &spec.spec;
            if let Some(other) =
                list[..k].iter().map(|o| &o.spec).find(|o| o.file.name == spec.file.name)
            {
                anyhow::bail!(
                    "{}: {} and {} have the same name `{}` (they would write one folder)",
                    plan_path.display(),
                    other.path,
                    spec.path,
                    spec.file.name
                );
            }
        }
    }
    let all = specs.iter().chain(readings.iter().flat_map(|(_, r)| r));
    let cells = all.fold(0u64, |n, s| n.saturating_add(super::limits::cell_count(s)));
    if cells > super::limits::MAX_PLAN_CELLS {
        anyhow::bail!(
            "{}: the plan's specs and reading sets have {cells} cells in all, above the limit {}",
            plan_path.display(),
            super::limits::MAX_PLAN_CELLS
        );
    }
    Ok(())
}

/// Load every spec of the plan (all before any runs, so a bad one stops nothing half-way), with
/// the maps of the later ones pointed at `<out>/<maps_from>/maps`.
fn load_specs<F: Families>(
    dir: &Path,
    plan: &Plan,
    profile: Option<&str>,
    out: &Path,
) -> Result<Vec<Loaded<F>>> {
    let loaded = load_reached(dir, plan, &plan.specs, &[], profile, out)?;
    Ok(loaded.into_iter().map(|(spec, _)| spec).collect())
}

/// A reading set's keys: none written under both its former and its present section name
/// (`optim.de.f` and `optimise.de.f`). Returns the former names they use, for the note.
fn check_set_keys<F: Families>(
    plan_path: &Path,
    plan: &Plan,
) -> Result<Vec<(&'static str, &'static str)>> {
    let mut renamed = Vec::new();
    for r in &plan.readings {
        let keys: Vec<&String> = r.set.keys().collect();
        for (k, key) in keys.iter().enumerate() {
            let both = keys[..k].iter().find_map(|b| super::renamed::both_spellings::<F>(b, key));
            if let Some(both) = both {
                anyhow::bail!("{}: readings.{}.set: {both}", plan_path.display(), r.name);
            }
            renamed.extend(super::renamed::renamed_key::<F>(key).map(|(_, pair)| pair));
        }
    }
    Ok(renamed)
}

/// The specs of the reading set `r` with its keys applied. Every key changes at least one of
/// them, and each of them is changed by at least one key: a set would otherwise run a spec as
/// written (or carry a key that does nothing) and list the run as a reading.
fn load_reading<F: Families>(
    dir: &Path,
    plan_path: &Path,
    plan: &Plan,
    r: &ReadingSet,
    profile: Option<&str>,
    out: &Path,
) -> Result<Vec<Loaded<F>>> {
    let overrides = r.overrides();
    let loaded = load_reached::<F>(dir, plan, &r.specs, &overrides, profile, out)?;
    let section = |spec: &Loaded<F>| spec.family().section();
    let idle: Vec<String> = (overrides.iter().enumerate())
        .filter(|(k, _)| loaded.iter().all(|(_, reached)| !reached[*k]))
        .map(|(_, o)| format!("`{}`", o.key))
        .collect();
    if !idle.is_empty() {
        let has: Vec<String> = r
            .specs
            .iter()
            .zip(&loaded)
            .map(|(n, (s, _))| format!("{n}: [{}]", section(s)))
            .collect();
        anyhow::bail!(
            "{}: readings.{}.set: {} {} none of the set's specs ({}); name keys of their \
             sections, or list the specs the {} for",
            plan_path.display(),
            r.name,
            idle.join(", "),
            if idle.len() == 1 { "changes" } else { "change" },
            has.join(", "),
            if idle.len() == 1 { "key is" } else { "keys are" }
        );
    }
    let unchanged = r.specs.iter().zip(&loaded).find(|(_, (_, reached))| !reached.contains(&true));
    if let Some((name, (spec, _))) = unchanged {
        anyhow::bail!(
            "{}: readings.{}.specs: none of the set's keys changes `{name}` (its section is [{}]), \
             so it would run as written; remove it from the set or add a key of [{}]",
            plan_path.display(),
            r.name,
            section(spec),
            section(spec)
        );
    }
    Ok(loaded.into_iter().map(|(spec, _)| spec).collect())
}

/// The specs `names` of the plan with `overrides` applied, each with which overrides reached it
/// ([`Loaded::parse_reaching`]).
fn load_reached<F: Families>(
    dir: &Path,
    plan: &Plan,
    names: &[String],
    overrides: &[Override],
    profile: Option<&str>,
    out: &Path,
) -> Result<Vec<(Loaded<F>, Vec<bool>)>> {
    let maps = plan.maps_from.as_ref().map(|m| plan_maps(out, m));
    names
        .iter()
        .map(|name| {
            let path = dir.join(format!("{name}.toml"));
            let shown = path.display().to_string();
            let text = super::spec::read_spec(&path)?;
            let (mut spec, reached) = Loaded::<F>::parse_reaching(
                &shown,
                &text,
                profile.filter(|p| has_profile(&path, p)),
                overrides,
            )?;
            if let Some(maps) = &maps {
                let family = spec.family();
                family.use_maps(&mut spec.section, maps);
            }
            Ok((spec, reached))
        })
        .collect()
}

/// Whether a spec defines the profile (a spec without `quick` runs as it is, e.g. one that is
/// already quick).
fn has_profile(path: &Path, profile: &str) -> bool {
    crate::io::read_text_of(path, crate::io::input::Kind::Toml)
        .ok()
        .and_then(|t| t.parse::<toml::Table>().ok())
        .and_then(|t| t.get("profiles").and_then(|p| p.get(profile)).map(|_| ()))
        .is_some()
}

/// The folder `--specs` names when it is not given.
pub(crate) const DEFAULT_SPECS: &str = "experiments";

/// The default output folder of a plan: `results/<plan>`, or `results/<plan>_quick`.
pub(crate) fn default_out(plan: &str, profile: &str) -> PathBuf {
    if profile == "quick" {
        format!("results/{plan}_quick").into()
    } else {
        format!("results/{plan}").into()
    }
}

/// The folder of the plans and specs: `--specs`, else `experiments` in the working folder, else
/// the one in the clone somnurbs was built from (said on stderr), the rule of
/// `crate::data::registry::found_folder`. An error names the folder tried and hints `--specs DIR`.
pub(crate) fn specs_dir(flag: Option<&Path>, plan: &str) -> Result<PathBuf> {
    let (dir, clone) = crate::data::registry::found_folder(flag, None, DEFAULT_SPECS);
    let file = format!("{plan}.toml");
    if flag.is_none() && (!dir.is_dir() || (clone && !dir.join(&file).is_file())) {
        anyhow::bail!(
            "--plan {plan}: no folder {DEFAULT_SPECS}/ in the working folder and no {} (run from the top of the clone, or name the folder of the plans with --specs DIR)",
            Path::new(crate::data::registry::CLONE_DIR).join(DEFAULT_SPECS).join(&file).display()
        );
    }
    if clone {
        crate::notice::emit(&format!(
            "somnurbs: reproduce: no {DEFAULT_SPECS}/ in the working folder; using the plans of the clone somnurbs was built from, {} (--specs DIR names another folder)",
            dir.display()
        ));
    }
    Ok(dir)
}

/// The `somnurbs reproduce` command that makes the folder `out` again: `--specs` and `--out`
/// when they are not the defaults.
fn reproduce_command(specs_dir: &Path, plan: &str, profile: &str, out: &Path) -> String {
    let mut s = format!("somnurbs reproduce --plan {plan} --profile {profile}");
    if specs_dir != Path::new(DEFAULT_SPECS) {
        let _ = write!(s, " --specs {}", specs_dir.display());
    }
    if out != default_out(plan, profile) {
        let _ = write!(s, " --out {}", out.display());
    }
    s
}

/// Run the plan into `ctx.out` and write the combined REPORT.md; returns its path.
pub(crate) fn reproduce<F: Families>(
    specs_dir: &Path,
    plan_name: &str,
    profile: &str,
    ctx: &RunContext,
) -> Result<Option<PathBuf>> {
    let plan_path = specs_dir.join(format!("{plan_name}.toml"));
    if !plan_path.exists() {
        anyhow::bail!(
            "--plan {plan_name}: no plan file {} (--specs DIR names the folder of the plans)",
            plan_path.display()
        );
    }
    let plan = Plan::load(&plan_path)?;
    let renamed = check_set_keys::<F>(&plan_path, &plan)?;
    let rerun = reproduce_command(specs_dir, plan_name, profile, &ctx.out);
    let ctx = &RunContext { rerun: Some(rerun.clone()), ..ctx.clone() };
    let profile = if profile == "full" { None } else { Some(profile) };
    let specs: Vec<Loaded<F>> = load_specs(specs_dir, &plan, profile, &ctx.out)?;
    let reading_specs: Vec<(&ReadingSet, Vec<Loaded<F>>)> = plan
        .readings
        .iter()
        .map(|r| Ok((r, load_reading(specs_dir, &plan_path, &plan, r, profile, &ctx.out)?)))
        .collect::<Result<_>>()?;
    check_specs(&plan_path, &specs, &reading_specs)?;
    super::renamed::note(&plan_path.display().to_string(), &renamed);
    // Every data set of every spec loads before the folder changes (a bad --data-dir changes nothing).
    for spec in &specs {
        for d in super::limits::dataset_entries(spec) {
            let spec = &spec.spec;
            ctx.loader(spec).load(d).with_context(|| format!("{}: data set `{d}`", spec.path))?;
        }
    }
    let _lock = crate::io::outdir::lock(&ctx.out, &format!("reproduce --plan {plan_name}"))?;
    let record = PlanRecord::new(plan_name, &plan_path, profile.unwrap_or("full"))?;
    let layout = PlanLayout {
        specs: specs.iter().map(|s| s.spec.file.name.clone()).collect(),
        readings: reading_specs
            .iter()
            .map(|(r, rs)| (r.name.clone(), rs.iter().map(|s| s.spec.file.name.clone()).collect()))
            .collect(),
    };
    if claim_plan(&ctx.out, &layout, &record, ctx.resume)? == Claimed::Finished {
        crate::notice::emit(&format!(
            "somnurbs: {} already holds this reproduction, finished; nothing to do (`somnurbs report {}` makes a lost table or picture of a spec again from its records)",
            ctx.out.display(),
            ctx.out.join(&layout.specs[0]).display()
        ));
        return Ok(None);
    }
    // Every spec has loaded: the folder is unfinished until the combined REPORT.md is written.
    let incomplete = ctx.out.join(crate::io::outdir::INCOMPLETE);
    write_atomic(
        &incomplete,
        format!(
            "reproduce --plan {plan_name} --profile {} started here\n",
            profile.unwrap_or("full")
        )
        .as_bytes(),
    )?;
    record.write(&ctx.out)?;
    let started = Instant::now();
    let mut done = Vec::new();
    for spec in &specs {
        let name = &spec.spec.file.name;
        let sub = RunContext { out: ctx.out.join(name), ..ctx.clone() };
        crate::notice::emit(&format!("somnurbs: reproduce: {name} -> {}", sub.out.display()));
        let t = Instant::now();
        run_spec(spec, &sub)?;
        done.push((name.clone(), t.elapsed().as_secs_f64()));
    }
    run_reading_sets(&reading_specs, ctx, &mut done)?;
    let combined = combine(&ctx.out, &plan, &specs)?;
    let as_written = as_written_claims(&ctx.out, &reading_specs)?;
    let mut report = combined_report(
        &ctx.out,
        &plan,
        plan_name,
        &rerun,
        &specs.iter().map(|s| &s.spec).collect::<Vec<_>>(),
        &done,
        (&combined, as_written.as_ref()),
        profile.unwrap_or("full"),
        started.elapsed().as_secs_f64(),
    )?;
    if !plan.readings.is_empty() {
        let matrix = readings_matrix(&ctx.out, &plan)?;
        report.push_str(&render_readings(&ctx.out, &plan, &matrix)?);
        for part in &combined {
            report.extend(part.readings.iter().map(String::as_str));
        }
    }
    let titles: BTreeMap<String, &'static str> = specs
        .iter()
        .chain(reading_specs.iter().flat_map(|(_, r)| r))
        .map(|s| (s.spec.file.name.clone(), s.family().title()))
        .collect();
    report.push_str(&readings_score::<F>(&ctx.out, &plan, &titles)?);
    let path = ctx.out.join("REPORT.md");
    write_atomic(&path, report.as_bytes())?;
    crate::report::html::write(&ctx.out)?;
    std::fs::remove_file(&incomplete)
        .with_context(|| format!("cannot remove {}", incomplete.display()))?;
    crate::io::outdir::sync_dir(&ctx.out)?;
    Ok(Some(path))
}

/// Run every reading set's specs into `readings/<set>/<spec>/`, each folder's time added to `done`.
/// A set's cells that compute what the plan's did (a Chapter 6 optimiser the set does not change)
/// are taken from the plan's folder of the spec, not computed again.
fn run_reading_sets<F: Families>(
    reading_specs: &[(&ReadingSet, Vec<Loaded<F>>)],
    ctx: &RunContext,
    done: &mut Vec<(String, f64)>,
) -> Result<()> {
    for (reading, rspecs) in reading_specs {
        for spec in rspecs {
            let folder = Path::new(READINGS_DIR).join(&reading.name).join(&spec.spec.file.name);
            let mut reuse = vec![ctx.out.join(&spec.spec.file.name)];
            reuse.extend(ctx.reuse.iter().cloned());
            let sub =
                RunContext { out: ctx.out.join(&folder), extras: false, reuse, ..ctx.clone() };
            crate::notice::emit(&format!(
                "somnurbs: reproduce: {} under the readings `{}` -> {}",
                spec.spec.file.name,
                reading.name,
                sub.out.display()
            ));
            let t = Instant::now();
            run_spec(spec, &sub)?;
            done.push((folder.to_string_lossy().into_owned(), t.elapsed().as_secs_f64()));
        }
    }
    Ok(())
}

/// The maps folder of a plan's `maps_from` spec under the plan's folder `root`, absolute: a
/// relative `maps` would resolve against the spec's folder, this one is the run's.
fn plan_maps(root: &Path, maps_from: &str) -> String {
    let dir = root.join(maps_from).join("maps");
    std::path::absolute(&dir).unwrap_or(dir).to_string_lossy().into_owned()
}

/// The maps folder `reproduce` pointed the spec of the sub-folder `dir` at (`<root>/<maps_from>/maps`,
/// made absolute as the run made it), found from the plan record of its root: `dir`'s parent, or
/// for a reading set's `readings/<set>/<spec>` three levels up. None for a folder of no plan.
/// `somnurbs report` reads the maps the run read, so its tables and text are the run's.
pub(crate) fn plan_maps_of(dir: &Path) -> Result<Option<String>> {
    let parent = dir.parent();
    let in_set = parent
        .and_then(Path::parent)
        .filter(|r| r.file_name().is_some_and(|n| n == READINGS_DIR))
        .and_then(Path::parent);
    for root in [parent, in_set].into_iter().flatten() {
        let Some(record) = PlanRecord::read(root)? else { continue };
        let plan: Plan = toml::from_str(&record.plan_text)
            .with_context(|| format!("{}: the plan's text", root.join(PLAN_FILE).display()))?;
        return Ok(plan.maps_from.map(|m| plan_maps(root, &m)));
    }
    Ok(None)
}

/// The record of the plan a `reproduce` folder holds ([`PLAN_FILE`]): which plan, in which
/// version, under which profile. `--resume` continues only the same plan.
#[derive(Debug, Clone, PartialEq, serde::Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanRecord {
    plan: String,
    plan_path: String,
    plan_sha256: String,
    profile: String,
    plan_text: String,
}

impl PlanRecord {
    fn new(plan: &str, path: &Path, profile: &str) -> Result<PlanRecord> {
        let text = crate::io::read_text(path)?;
        Ok(PlanRecord {
            plan: plan.to_string(),
            plan_path: path.display().to_string(),
            plan_sha256: hex::encode(<sha2::Sha256 as sha2::Digest>::digest(text.as_bytes())),
            profile: profile.to_string(),
            plan_text: text,
        })
    }

    fn read(dir: &Path) -> Result<Option<PlanRecord>> {
        let path = dir.join(PLAN_FILE);
        if !path.exists() {
            return Ok(None);
        }
        crate::io::read_toml(&path).map(Some)
    }

    fn write(&self, dir: &Path) -> Result<()> {
        let text = toml::to_string(self).context("cannot serialise the plan record")?;
        write_atomic(&dir.join(PLAN_FILE), text.as_bytes())
    }

    /// The first field in which `other` differs, as `name: ours vs theirs`.
    fn difference(&self, other: &PlanRecord) -> Option<String> {
        [
            ("plan", &self.plan, &other.plan),
            ("profile", &self.profile, &other.profile),
            ("plan text (sha256)", &self.plan_sha256, &other.plan_sha256),
        ]
        .into_iter()
        .find(|(_, a, b)| a != b)
        .map(|(name, a, b)| format!("{name}: {a} vs {b}"))
    }
}

/// The folder contract for a plan: a fresh reproduction needs an empty folder; `--resume` needs an
/// empty folder or one holding the same plan and profile ([`PlanRecord`]), unfinished (a finished
/// one is left as it is) whose folders are only the plan's (its specs', the reading sets' and
/// `vendor/`); its specs' folders are then claimed one by one as `run --resume` does.
fn claim_plan(
    out: &Path,
    layout: &PlanLayout,
    record: &PlanRecord,
    resume: bool,
) -> Result<Claimed> {
    if !resume {
        crate::io::outdir::require_empty(out)?;
        return Ok(Claimed::Start);
    }
    let Some(old) = PlanRecord::read(out)? else {
        // A kill between the unfinished marker and the record leaves the marker alone.
        let found = crate::io::outdir::entries(out)?;
        if found.iter().all(|e| e == crate::io::outdir::INCOMPLETE) {
            return Ok(Claimed::Start);
        }
        crate::io::outdir::require_empty(out)?;
        return Ok(Claimed::Start);
    };
    if let Some(diff) = old.difference(record) {
        anyhow::bail!("cannot resume in {}: it holds another reproduction ({diff}); use another --out or drop --resume", out.display());
    }
    if !out.join(crate::io::outdir::INCOMPLETE).exists() {
        return Ok(Claimed::Finished);
    }
    require_plan_folders(out, layout)?;
    crate::io::outdir::remove_leftovers(out)?;
    Ok(Claimed::Start)
}

/// The folders a plan makes: one per spec (its `name`), and per reading set one per spec it runs.
struct PlanLayout {
    specs: Vec<String>,
    readings: Vec<(String, Vec<String>)>,
}

/// Refuse a plan folder holding a folder the plan does not make (another spec's, another
/// reading set's), naming it.
fn require_plan_folders(out: &Path, layout: &PlanLayout) -> Result<()> {
    let check = |dir: &Path, allowed: &[&str]| -> Result<()> {
        for e in crate::io::outdir::entries(dir)? {
            let Some(name) = e.strip_suffix('/') else { continue };
            if !allowed.contains(&name) {
                anyhow::bail!(
                    "cannot resume in {}: the folder {} is not one of this plan's (its specs: {}); a plan folder holds exactly its plan",
                    out.display(),
                    dir.join(name).display(),
                    layout.specs.join(", ")
                );
            }
        }
        Ok(())
    };
    let mut top: Vec<&str> = layout.specs.iter().map(String::as_str).collect();
    top.extend([READINGS_DIR, "vendor"]);
    check(out, &top)?;
    let sets: Vec<&str> = layout.readings.iter().map(|r| r.0.as_str()).collect();
    check(&out.join(READINGS_DIR), &sets)?;
    for (name, specs) in &layout.readings {
        let specs: Vec<&str> = specs.iter().map(String::as_str).collect();
        check(&out.join(READINGS_DIR).join(name), &specs)?;
    }
    Ok(())
}

/// Each family's part of the combined report, from its specs' finished folders.
fn combine<F: Families>(out: &Path, plan: &Plan, specs: &[Loaded<F>]) -> Result<Vec<Combined>> {
    let readings: Vec<ReadingRun> = plan
        .readings
        .iter()
        .map(|r| ReadingRun {
            name: r.name.clone(),
            specs: r.specs.clone(),
            root: out.join(READINGS_DIR).join(&r.name),
        })
        .collect();
    combine_in(out, &plan.reading, &readings, specs)
}

/// [`combine`] over the specs that ran into `out` under the reading `reading`, with the sets
/// `readings` beside them.
fn combine_in<F: Families>(
    out: &Path,
    reading: &str,
    readings: &[ReadingRun],
    specs: &[Loaded<F>],
) -> Result<Vec<Combined>> {
    F::all()
        .iter()
        .map(|f| {
            let view = PlanView {
                out,
                specs: specs
                    .iter()
                    .filter(|s| s.family().section() == f.section())
                    .map(|s| (&s.spec, &s.section))
                    .collect(),
                reading,
                readings: readings.to_vec(),
            };
            if view.specs.is_empty() {
                Ok(Combined::default())
            } else {
                f.combine(&view).with_context(|| format!("[{}] over the plan", f.section()))
            }
        })
        .collect()
}

/// The specs the set [`AS_WRITTEN`] ran and the claims it found.
type AsWrittenRun = (Vec<String>, Vec<Claim>);

/// The claims under the as-written readings: those of the specs the set [`AS_WRITTEN`] ran (read
/// back from their `claims.csv`) and those over several of them (each family's combine over its
/// folder), with the names of the specs it ran; `None` for a plan without that set.
fn as_written_claims<F: Families>(
    out: &Path,
    reading_specs: &[(&ReadingSet, Vec<Loaded<F>>)],
) -> Result<Option<AsWrittenRun>> {
    let Some((set, specs)) = reading_specs.iter().find(|(r, _)| r.name == AS_WRITTEN) else {
        return Ok(None);
    };
    let root = out.join(READINGS_DIR).join(&set.name);
    let mut found = Vec::new();
    for s in &set.specs {
        let path = root.join(s).join("claims.csv");
        if path.exists() {
            found.extend(claims::read(&path)?);
        }
    }
    for part in combine_in(&root, &set.name, &[], specs)? {
        found.extend(part.claims);
    }
    Ok(Some((set.specs.clone(), found)))
}

/// Each of the plan's claims with its counterpart under the as-written readings: the same claim
/// (spec, grid, statement) of the set [`AS_WRITTEN`] where it ran all of the claim's specs, the
/// plan's own where it ran none (no calibrated reading touches them), `None` otherwise or without
/// the set.
fn beside_as_written(
    all: Vec<Claim>,
    as_written: Option<&AsWrittenRun>,
) -> Vec<(Claim, Option<Claim>)> {
    all.into_iter()
        .map(|c| {
            let Some((specs, found)) = as_written else { return (c, None) };
            let parts: Vec<&str> = c.spec.split('+').collect();
            let ran = parts.iter().filter(|p| specs.iter().any(|s| s == *p)).count();
            let w = if ran == 0 {
                Some(c.clone())
            } else if ran == parts.len() {
                found
                    .iter()
                    .find(|w| w.spec == c.spec && w.grid == c.grid && w.statement == c.statement)
                    .cloned()
            } else {
                None
            };
            (c, w)
        })
        .collect()
}

/// REPORT.md's paragraph on the as-written verdicts: how many differ from the plan's, and the
/// claims whose verdict reproduces the thesis only under calibration.
fn as_written_summary(
    pairs: &[(Claim, Option<Claim>)],
    has_set: bool,
    calibrated: usize,
) -> String {
    if calibrated == 0 {
        return "No reading of this plan's specs is calibrated (docs/readings.md, the readings table's status): every verdict here is the as-written one.\n".into();
    }
    if !has_set {
        return format!("{calibrated} of this plan's readings are calibrated (docs/readings.md), but the plan has no `{AS_WRITTEN}` set, so the as-written verdicts were not run (`--plan thesis` runs them).\n");
    }
    let compared: Vec<(&Claim, &Claim)> =
        pairs.iter().filter_map(|(c, w)| w.as_ref().map(|w| (c, w))).collect();
    let differ = compared.iter().filter(|(c, w)| c.verdict() != w.verdict()).count();
    let only: Vec<&(&Claim, &Claim)> =
        compared.iter().filter(|(c, w)| claims::calibration_only(c, w)).collect();
    let mut s = format!("**Under calibration only.** {calibrated} of this plan's readings are calibrated (chosen by their fit to the thesis' numbers; docs/readings.md, the readings table's status); the set `{AS_WRITTEN}` ran their specs at the as-written values (column *as written*; the other specs' readings are as written or inferred, so their verdicts are the plan's, on the plan's maps). {differ} of {} verdicts differ under the as-written readings; {} reproduce the thesis only under calibration (the plan's verdict agrees with the thesis' count, or holds where the thesis has none, and the as-written one does not)", compared.len(), only.len());
    if only.is_empty() {
        s.push_str(".\n");
        return s;
    }
    s.push_str(":\n\n");
    for (c, w) in only {
        let grid = if c.grid.is_empty() { "all" } else { c.grid.as_str() };
        let _ = writeln!(
            s,
            "- {} ({grid}): {}: {} {}/{} under the plan's readings, {} {}/{} as written",
            c.spec,
            c.statement,
            c.verdict(),
            c.ours.0,
            c.ours.1,
            w.verdict(),
            w.ours.0,
            w.ours.1
        );
    }
    s
}

/// Where the reading sets' runs go, inside the plan's output folder.
pub(crate) const READINGS_DIR: &str = "readings";

/// One claim under one reading.
struct ReadingClaim {
    reading: String,
    folder: String,
    claim: Claim,
}

/// Every claim of the specs that some reading set runs, under the plan's own reading and under
/// each set (read back from each run's `claims.csv`).
fn readings_matrix(out: &Path, plan: &Plan) -> Result<Vec<ReadingClaim>> {
    let mut compared: Vec<&String> = Vec::new();
    for r in &plan.readings {
        for s in &r.specs {
            if !compared.contains(&s) {
                compared.push(s);
            }
        }
    }
    let mut rows = Vec::new();
    let mut collect = |reading: &str, folder: PathBuf, name: &str| -> Result<()> {
        let path = folder.join("claims.csv");
        if path.exists() {
            for claim in claims::read(&path)? {
                rows.push(ReadingClaim {
                    reading: reading.to_string(),
                    folder: name.to_string(),
                    claim,
                });
            }
        }
        Ok(())
    };
    for s in &compared {
        collect(&plan.reading, out.join(s), s)?;
    }
    for r in &plan.readings {
        for s in &r.specs {
            collect(&r.name, out.join(READINGS_DIR).join(&r.name).join(s), s)?;
        }
    }
    Ok(rows)
}

/// `readings.csv` and the REPORT.md section: one row per (spec, claim), one column per reading,
/// and whether the verdict changes with the reading.
fn render_readings(out: &Path, plan: &Plan, rows: &[ReadingClaim]) -> Result<String> {
    let header: Vec<String> =
        ["spec", "chapter", "grid", "claim", "reading", "verdict", "holds", "checked", "note"]
            .iter()
            .map(|s| s.to_string())
            .collect();
    let csv_rows: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.folder.clone(),
                r.claim.chapter.clone(),
                r.claim.grid.clone(),
                r.claim.statement.clone(),
                r.reading.clone(),
                r.claim.verdict().to_string(),
                r.claim.ours.0.to_string(),
                r.claim.ours.1.to_string(),
                r.claim.note.clone(),
            ]
        })
        .collect();
    write_atomic(&out.join("readings.csv"), csv_records(&header, &csv_rows)?.as_bytes())?;
    let mut readings = vec![plan.reading.clone()];
    readings.extend(plan.readings.iter().map(|r| r.name.clone()));
    let mut s = String::from("\n---\n\n# Readings matrix\n\nThe thesis leaves some steps ambiguous; each is a named spec option (docs/readings.md). The plan's specs ran under the plan's readings");
    let _ = write!(s, " (reading `{}`) and again under each reading set below, from the same maps and seeds; every claim is shown under every reading, so a reader sees which conclusions rest on which reading (`readings.csv`).\n\n", plan.reading);
    s.push_str(&registry::markdown(&plan.specs));
    s.push_str("\n## The reading sets\n\n");
    for r in &plan.readings {
        let keys: Vec<String> = r.set.iter().map(|(k, v)| format!("`{k} = {v}`")).collect();
        let _ = writeln!(
            s,
            "- `{}`: {} ({}; specs {}; folders `readings/{}/`)",
            r.name,
            r.description,
            keys.join(", "),
            r.specs.join(", "),
            r.name
        );
    }
    let mut keys: Vec<(String, String, String)> = Vec::new();
    for r in rows {
        let k = (r.folder.clone(), r.claim.grid.clone(), r.claim.statement.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let mut h = vec!["spec".to_string(), "grid".into(), "claim".into()];
    h.extend(readings.iter().map(|r| format!("`{r}`")));
    h.push("changes with the reading".into());
    let mut md_rows = Vec::new();
    let mut changing = 0;
    for (folder, grid, statement) in &keys {
        let cells: Vec<Option<&Claim>> = readings
            .iter()
            .map(|rd| {
                rows.iter()
                    .find(|r| {
                        &r.reading == rd
                            && &r.folder == folder
                            && &r.claim.grid == grid
                            && &r.claim.statement == statement
                    })
                    .map(|r| &r.claim)
            })
            .collect();
        let verdicts: Vec<&str> = cells.iter().flatten().map(|c| c.verdict()).collect();
        let changes = verdicts.windows(2).any(|w| w[0] != w[1]);
        changing += changes as usize;
        let mut row = vec![folder.clone(), grid.clone(), statement.clone()];
        row.extend(cells.iter().map(|c| {
            c.map(|c| format!("{} {}/{}", c.verdict(), c.ours.0, c.ours.1))
                .unwrap_or_else(|| "-".into())
        }));
        row.push(if changes { "**yes**".into() } else { "no".into() });
        md_rows.push(row);
    }
    let _ = writeln!(
        s,
        "\n{changing} of {} claims change their verdict with the reading.\n",
        keys.len()
    );
    s.push_str(&crate::report::markdown::table(&h, &md_rows));
    Ok(s)
}

/// `readings_score.csv` and its REPORT.md section: per spec folder and reading, the published
/// table cells whose ratio ours/published lies in the band and the claims that agree with the
/// source's own count ([`crate::report::score`]); totals over the specs every reading ran.
fn readings_score<F: Families>(
    out: &Path,
    plan: &Plan,
    titles: &BTreeMap<String, &'static str>,
) -> Result<String> {
    use crate::report::score::{folder_score, Score, BAND};
    let mut readings: Vec<(String, Vec<(String, PathBuf)>)> =
        vec![(plan.reading.clone(), plan.specs.iter().map(|s| (s.clone(), out.join(s))).collect())];
    for r in &plan.readings {
        let root = out.join(READINGS_DIR).join(&r.name);
        readings
            .push((r.name.clone(), r.specs.iter().map(|s| (s.clone(), root.join(s))).collect()));
    }
    let mut rows = Vec::new();
    let mut scores: Vec<(String, String, Score)> = Vec::new();
    for (reading, folders) in &readings {
        for (spec, folder) in folders {
            if !folder.is_dir() {
                continue;
            }
            let sc = folder_score(folder, &super::family::published::<F>)?;
            if sc.cells + sc.claims == 0 {
                continue;
            }
            let share = if sc.cells > 0 {
                format!("{:.4}", sc.within as f64 / sc.cells as f64)
            } else {
                String::new()
            };
            rows.push(vec![
                reading.clone(),
                titles.get(spec).copied().unwrap_or_default().to_string(),
                spec.clone(),
                sc.cells.to_string(),
                sc.within.to_string(),
                share,
                sc.claims.to_string(),
                sc.agree.to_string(),
            ]);
            scores.push((reading.clone(), spec.clone(), sc));
        }
    }
    if rows.is_empty() {
        return Ok(String::new());
    }
    let header: Vec<String> = [
        "reading",
        "chapter",
        "spec",
        "published_cells",
        "within_band",
        "share_within",
        "claims_with_source",
        "claims_agree",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    write_atomic(&out.join("readings_score.csv"), csv_records(&header, &rows)?.as_bytes())?;
    let names: Vec<&String> = readings.iter().map(|r| &r.0).collect();
    let specs: Vec<&String> = crate::report::ordered(scores.iter().map(|s| &s.1));
    let cell = |sc: Option<&Score>| match sc {
        None => "-".to_string(),
        Some(s) => {
            let share = if s.cells > 0 {
                format!("{:.1}% of {} cells", 100.0 * s.within as f64 / s.cells as f64, s.cells)
            } else {
                "no cells".into()
            };
            format!("{share}; {}/{} claims agree", s.agree, s.claims)
        }
    };
    let find = |r: &str, s: &str| scores.iter().find(|x| x.0 == r && x.1 == s).map(|x| &x.2);
    let mut h = vec!["spec".to_string()];
    h.extend(names.iter().map(|n| format!("`{n}`")));
    let mut md_rows: Vec<Vec<String>> = specs
        .iter()
        .map(|s| {
            std::iter::once(s.to_string()).chain(names.iter().map(|r| cell(find(r, s)))).collect()
        })
        .collect();
    md_rows.extend(chapter_totals(&names, &specs, titles, &find, &cell));
    // Comparable totals: over the specs every reading ran.
    let common: Vec<&&String> =
        specs.iter().filter(|s| names.iter().all(|r| find(r, s).is_some())).collect();
    if names.len() > 1 && !common.is_empty() {
        let total = |r: &str| {
            common.iter().filter_map(|s| find(r, s)).fold(Score::default(), |a, b| a + *b)
        };
        let mut row = vec![format!(
            "**all of {}**",
            common.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
        )];
        row.extend(names.iter().map(|r| cell(Some(&total(r)))));
        md_rows.push(row);
    }
    let price = if plan.readings.iter().any(|r| r.name == AS_WRITTEN) {
        price_of_reading_literally(out, &plan.reading, &specs, titles, &find)?
    } else {
        String::new()
    };
    let mut s = format!("\n---\n\n# Readings score\n\nFor each reading and spec, and in total per chapter or seed (over the specs every reading that ran one of them ran): the share of the published tables' value cells (Appendices B-F, K, L and the seeds' tables; CPU seconds left out) whose ratio ours/published lies in [{}, {}], and how many of the claims with the source's own count agree with it (claims about CPU time left out too) (`readings_score.csv`). The reading that reproduces the published numbers best has the highest shares.\n\n", BAND.0, BAND.1);
    s.push_str(&crate::report::markdown::table(&h, &md_rows));
    s.push_str(&price);
    Ok(s)
}

/// The price of reading literally: per chapter, the plan's score and the set [`AS_WRITTEN`]'s over
/// the chapter's specs that set ran (`readings_price.csv` and a REPORT.md paragraph; empty
/// without the set).
fn price_of_reading_literally<'s>(
    out: &Path,
    reading: &str,
    specs: &[&String],
    titles: &BTreeMap<String, &'static str>,
    find: &dyn Fn(&str, &str) -> Option<&'s crate::report::score::Score>,
) -> Result<String> {
    use crate::report::score::Score;
    let share = |sc: &Score| {
        if sc.cells > 0 {
            format!("{:.4}", sc.within as f64 / sc.cells as f64)
        } else {
            String::new()
        }
    };
    let pct = |sc: &Score| {
        if sc.cells > 0 {
            format!("{:.1}%", 100.0 * sc.within as f64 / sc.cells as f64)
        } else {
            "-".into()
        }
    };
    let chapters: Vec<&str> =
        crate::report::ordered(specs.iter().filter_map(|s| titles.get(s.as_str()).copied()));
    let mut rows = Vec::new();
    let mut lines = String::new();
    for chapter in chapters {
        let own: Vec<&&String> = specs
            .iter()
            .filter(|s| titles.get(s.as_str()) == Some(&chapter))
            .filter(|s| find(AS_WRITTEN, s).is_some() && find(reading, s).is_some())
            .collect();
        if own.is_empty() {
            continue;
        }
        let total =
            |r: &str| own.iter().filter_map(|s| find(r, s)).fold(Score::default(), |a, b| a + *b);
        let (p, w) = (total(reading), total(AS_WRITTEN));
        let names: Vec<&str> = own.iter().map(|s| s.as_str()).collect();
        let points = if p.cells > 0 && w.cells > 0 {
            let d = 100.0 * (w.within as f64 / w.cells as f64 - p.within as f64 / p.cells as f64);
            format!(" ({d:+.1} points)")
        } else {
            String::new()
        };
        let _ = writeln!(
            lines,
            "- {chapter} ({}): {} of {} cells and {}/{} claims agree under the plan's readings; {} of {} and {}/{} as written{points}",
            names.join(", "),
            pct(&p),
            p.cells,
            p.agree,
            p.claims,
            pct(&w),
            w.cells,
            w.agree,
            w.claims
        );
        rows.push(vec![
            chapter.to_string(),
            names.join("+"),
            p.cells.to_string(),
            p.within.to_string(),
            share(&p),
            w.cells.to_string(),
            w.within.to_string(),
            share(&w),
            p.claims.to_string(),
            p.agree.to_string(),
            w.claims.to_string(),
            w.agree.to_string(),
        ]);
    }
    if rows.is_empty() {
        return Ok(String::new());
    }
    let header: Vec<String> = [
        "chapter",
        "specs",
        "published_cells_plan",
        "within_band_plan",
        "share_within_plan",
        "published_cells_as_written",
        "within_band_as_written",
        "share_within_as_written",
        "claims_with_source_plan",
        "claims_agree_plan",
        "claims_with_source_as_written",
        "claims_agree_as_written",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    write_atomic(&out.join("readings_price.csv"), csv_records(&header, &rows)?.as_bytes())?;
    Ok(format!("\n**The price of reading literally** (`readings_price.csv`): per chapter, the score of the plan's readings (`{reading}`) and of the set `{AS_WRITTEN}` (every calibrated reading at its as-written value) over the chapter's specs that set ran:\n\n{lines}"))
}

/// The readings score's total per chapter or seed (rows of the Markdown table): for each chapter
/// with two or more specs that every reading running one of them ran, each reading's sum over
/// those specs ("-" for a reading that ran none). A chapter of one such spec has no total row: it
/// would repeat the spec's own.
fn chapter_totals<'s>(
    names: &[&String],
    specs: &[&String],
    titles: &BTreeMap<String, &'static str>,
    find: &dyn Fn(&str, &str) -> Option<&'s crate::report::score::Score>,
    cell: &dyn Fn(Option<&crate::report::score::Score>) -> String,
) -> Vec<Vec<String>> {
    use crate::report::score::Score;
    let chapters: Vec<&str> =
        crate::report::ordered(specs.iter().filter_map(|s| titles.get(s.as_str()).copied()));
    let mut rows = Vec::new();
    for chapter in chapters {
        let own: Vec<&&String> =
            specs.iter().filter(|s| titles.get(s.as_str()) == Some(&chapter)).collect();
        let ran: Vec<&&String> =
            names.iter().filter(|r| own.iter().any(|s| find(r, s).is_some())).collect();
        let common: Vec<&&&String> =
            own.iter().filter(|s| ran.iter().all(|r| find(r, s).is_some())).collect();
        if ran.len() < 2 || common.len() < 2 {
            continue;
        }
        let mut row = vec![format!(
            "**{chapter}: {}**",
            common.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
        )];
        row.extend(names.iter().map(|r| {
            if !ran.contains(&r) {
                return "-".to_string();
            }
            let total =
                common.iter().filter_map(|s| find(r, s)).fold(Score::default(), |a, b| a + *b);
            cell(Some(&total))
        }));
        rows.push(row);
    }
    rows
}

/// The combined REPORT.md: header, claims, Tables 6.8/6.9, then each chapter's report with its
/// links pointed into its sub-folder.
#[allow(clippy::too_many_arguments)]
fn combined_report(
    out: &Path,
    plan: &Plan,
    plan_name: &str,
    rerun: &str,
    specs: &[&Spec],
    done: &[(String, f64)],
    (combined, as_written): (&[Combined], Option<&AsWrittenRun>),
    profile: &str,
    wall: f64,
) -> Result<String> {
    let mut s = format!("# somnurbs: {}\n\n", plan.title);
    let commit = env!("SOMNURBS_GIT_COMMIT");
    let _ = writeln!(
        s,
        "Plan `{plan_name}`, profile `{profile}`, somnurbs {} at commit {}{}, {}: {} specs in {:.1} s wall. Re-run: `{rerun}`.\n",
        env!("CARGO_PKG_VERSION"),
        &commit[..commit.len().min(12)],
        if env!("SOMNURBS_GIT_DIRTY") == "true" { " (dirty)" } else { "" },
        env!("SOMNURBS_RUSTC"),
        done.len(),
        wall
    );
    if specs.iter().any(|s| s.reduced()) {
        s.push_str(super::NOT_EVIDENCE);
    }
    s.push_str("| spec | folder | wall s |\n|---|---|---|\n");
    for (name, secs) in done {
        let _ = writeln!(s, "| {name} | [`{name}/`]({name}/REPORT.md) | {secs:.1} |");
    }
    let mut beyond: Vec<String> = Vec::new();
    let mut plan_claims: Vec<Claim> = Vec::new();
    let mut sections = String::new();
    for part in combined {
        beyond.extend(part.beyond.iter().cloned());
        plan_claims.extend(part.claims.iter().cloned());
        sections.extend(part.sections.iter().map(String::as_str));
    }
    let mut all: Vec<Claim> = Vec::new();
    for spec in specs {
        let path = out.join(&spec.file.name).join("claims.csv");
        if path.exists() {
            let mut cs = claims::read(&path)?;
            cs.retain(|c| c.ours.1 > 0);
            if beyond.contains(&spec.file.name) {
                // Claims of the specs beyond the source's protocol say so.
                for c in cs.iter_mut() {
                    c.chapter = format!("{} (beyond the source's protocol)", c.chapter);
                }
            }
            all.extend(cs);
        }
    }
    all.extend(plan_claims);
    all.retain(|c| c.ours.1 > 0);
    for c in all.iter_mut().filter(|c| c.spec.is_empty()) {
        c.spec = plan_name.to_string();
    }
    let holding = all.iter().filter(|c| c.holds()).count();
    let compared = all.iter().filter(|c| !c.agreement().is_empty()).count();
    let agree = all.iter().filter(|c| c.agreement() == "agrees").count();
    let total = all.len();
    let calibrated = registry::of_specs(&plan.specs)
        .filter(|r| r.status == registry::Status::Calibrated)
        .count();
    // Without a calibrated reading the plan's readings are the as-written ones.
    let none: AsWrittenRun = (Vec::new(), Vec::new());
    let pairs = beside_as_written(all, if calibrated == 0 { Some(&none) } else { as_written });
    let table = claims::write_plan(out, &pairs)?;
    if total > 0 {
        let _ = writeln!(s, "\n## Claims\n\nEach claim of the thesis (or, for the other seeds, of the paper) is counted on this reproduction (`here`), one row per spec, grid and claim, and, where the published tables hold the same cells, on the source's own figures. {holding} of {total} hold here; {agree} of the {compared} with the source's own count agree with it. Also in `claims.csv`.\n");
        s.push_str(&as_written_summary(&pairs, as_written.is_some(), calibrated));
        s.push('\n');
        s.push_str(&table);
    }
    s.push_str(&sections);
    let mut seen: Vec<(String, String)> = Vec::new();
    for spec in specs {
        let name = &spec.file.name;
        let path = out.join(name).join("REPORT.md");
        let text = crate::io::read_text(&path)?;
        let _ = writeln!(s, "\n---\n\n# {name}\n");
        s.push_str(&sub_report(&text, name, &mut seen));
    }
    Ok(s)
}

/// A spec's REPORT.md inside the combined one: headings one level down, links into its folder,
/// its claims left to the table at the top (a link to its `claims.csv` instead), and a
/// sub-section said word for word by an earlier spec (the metric definitions) replaced by a
/// pointer to it. `seen` holds (sub-section text, spec) of the specs so far.
fn sub_report(text: &str, name: &str, seen: &mut Vec<(String, String)>) -> String {
    let mut s = String::new();
    // Split at the sub-sections ("### " in a spec's report); the part before the first is kept.
    let mut parts: Vec<(Option<&str>, Vec<&str>)> = vec![(None, Vec::new())];
    for line in text.lines().skip_while(|l| l.starts_with("# ") || l.trim().is_empty()) {
        match line.strip_prefix("### ") {
            Some(h) => parts.push((Some(h), Vec::new())),
            None => parts.last_mut().expect("starts with one part").1.push(line),
        }
    }
    for (heading, lines) in parts {
        let body = lines.join("\n");
        if let Some(h) = heading {
            let _ = writeln!(s, "#### {h}");
            if h.trim() == "Claims" {
                let _ = writeln!(s, "\nIn the claims table at the top (`{name}/claims.csv`).\n");
                continue;
            }
            let key = format!("{h}\n{body}");
            if let Some((_, first)) = seen.iter().find(|(k, _)| *k == key) {
                let _ = writeln!(s, "\nAs under [{first}](#{first}) above.\n");
                continue;
            }
            seen.push((key, name.to_string()));
        }
        for line in lines {
            let line = if line.starts_with('#') { format!("#{line}") } else { line.to_string() };
            s.push_str(&relink(&line, name));
            s.push('\n');
        }
    }
    s
}

/// Point the relative links and images of a sub-report's line into its folder.
fn relink(line: &str, folder: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut rest = line;
    while let Some(k) = rest.find("](") {
        out.push_str(&rest[..k + 2]);
        rest = &rest[k + 2..];
        if !(rest.starts_with("http") || rest.starts_with('/') || rest.starts_with('#')) {
            out.push_str(folder);
            out.push('/');
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sub_reports_say_a_repeated_section_once_and_leave_claims_to_the_top() {
        let a = "# report: a\n\n## Chapter\n\nintro ![p](png/p.png)\n### Metric definitions\n\n- QE\n### Claims\n\n| x |\n### Tables\n\nA\n";
        let b = "# report: b\n\n## Chapter\n\n### Metric definitions\n\n- QE\n### Tables\n\nB\n";
        let mut seen = Vec::new();
        let ra = sub_report(a, "a", &mut seen);
        let rb = sub_report(b, "b", &mut seen);
        assert!(ra.contains("### Chapter") && ra.contains("![p](a/png/p.png)"), "{ra}");
        assert!(ra.contains("#### Metric definitions\n\n- QE"), "{ra}");
        assert!(
            ra.contains("In the claims table at the top (`a/claims.csv`)") && !ra.contains("| x |")
        );
        assert!(
            rb.contains("#### Metric definitions\n\nAs under [a](#a) above.")
                && !rb.contains("- QE")
        );
        // Sections that differ are kept.
        assert!(ra.contains("#### Tables\n\nA") && rb.contains("#### Tables\n\nB"), "{rb}");
    }

    /// Every shipped plan, full and quick, passes the plan's checks (its cell total is printed
    /// with `--nocapture`); a plan over the cell limit, or with two specs of one name, does not.
    #[test]
    fn shipped_plans_pass_the_plan_checks_and_bad_ones_fail() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
        let out = Path::new("/nonexistent");
        for plan_name in ["thesis", "seeds", "all"] {
            let path = dir.join(format!("{plan_name}.toml"));
            let plan = Plan::load(&path).unwrap();
            assert!(check_set_keys::<crate::families::Section>(&path, &plan).unwrap().is_empty());
            for profile in [None, Some("quick")] {
                let specs: Vec<Loaded<crate::families::Section>> =
                    load_specs(&dir, &plan, profile, out).unwrap();
                let readings: Vec<(&ReadingSet, Vec<_>)> = plan
                    .readings
                    .iter()
                    .map(|r| (r, load_reading(&dir, &path, &plan, r, profile, out).unwrap()))
                    .collect();
                let all = specs.iter().chain(readings.iter().flat_map(|(_, r)| r));
                let cells: u64 = all.map(super::super::limits::cell_count).sum();
                println!("{plan_name} {profile:?}: {cells} cells");
                assert!(cells > 0);
                check_specs(&path, &specs, &readings).unwrap();
            }
        }
        let plan = Plan::load(&dir.join("thesis.toml")).unwrap();
        let specs: Vec<crate::families::Loaded> = load_specs(&dir, &plan, None, out).unwrap();
        let twice = [specs[0].clone(), specs[1].clone(), specs[0].clone()];
        let e = check_specs(Path::new("p.toml"), &twice, &[]).unwrap_err().to_string();
        assert!(
            e.contains("p.toml") && e.contains("ch4_models.toml and") && e.contains("same name"),
            "{e}"
        );
        // Eleven copies of a spec of 10^5 cells under distinct names: above 10^6.
        let text = "name = \"n\"\nmaster_seed = 1\n[som]\ndatasets = [\"cube\"]\niterations = 10\nrepeats = 10000\n[[som.group]]\nmodels = [\"som2d\"]\ngrids = [\"10x10\", \"11x11\", \"12x12\", \"13x13\", \"14x14\", \"15x15\", \"16x16\", \"17x17\", \"18x18\", \"19x19\"]\n";
        let big: Vec<crate::families::Loaded> = (0..11)
            .map(|k| {
                Loaded::parse("n.toml", &text.replace("\"n\"", &format!("\"n{k}\"")), None).unwrap()
            })
            .collect();
        assert_eq!(super::super::limits::cell_count(&big[0]), 100_000);
        check_specs(Path::new("p.toml"), &big[..10], &[]).unwrap();
        let e = check_specs(Path::new("p.toml"), &big, &[]).unwrap_err().to_string();
        assert!(e.contains("1100000 cells in all, above the limit 1000000"), "{e}");
    }

    /// A plan names only the specs of its own folder; a reading set lists its specs and writes
    /// each key once, under one of its spellings.
    #[test]
    fn plan_names_stay_in_their_folder_and_reading_sets_are_whole() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.toml");
        let load = |text: &str| {
            std::fs::write(&path, text).unwrap();
            Plan::load(&path)
        };
        for (name, fault) in [
            ("../x", "holds a folder part"),
            ("sub/x", "holds a folder part"),
            ("a\\b", "holds a folder part"),
            ("/abs/x", "is an absolute path"),
            ("..", "is a folder"),
            (".", "is a folder"),
            (" ", "is empty"),
        ] {
            let e = load(&format!("title = 't'\nspecs = ['a',\n '{name}']\n")).unwrap_err();
            let want = format!("p.toml:3: specs: `{name}` {fault}; a plan runs only the specs");
            assert!(e.to_string().contains(&want), "{e}");
        }
        assert!(load("specs = ['a', 'b.c', '...']").is_ok());
        let set = |keys: &str, specs: &str| {
            format!(
                "specs = ['a']\n[[readings]]\nname = 'r'\nset = {{ {keys} }}\nspecs = {specs}\n"
            )
        };
        let e = load(&set("'x.y' = 1", "[]")).unwrap_err().to_string();
        assert!(e.contains("p.toml: readings.r.specs: is empty; list the plan's specs"), "{e}");
        type S = crate::families::Section;
        let plan = load(&set("'optim.de.f' = 1, 'som.iterations' = 2", "['a']")).unwrap();
        assert_eq!(check_set_keys::<S>(&path, &plan).unwrap(), [("optim", "optimise")]);
        let plan = load(&set("'optimise.de.f' = 1, 'optim.de.f' = 2", "['a']")).unwrap();
        let e = check_set_keys::<S>(&path, &plan).unwrap_err().to_string();
        assert!(
            e.contains("p.toml: readings.r.set: `optim.de.f` and `optimise.de.f` are one key"),
            "{e}"
        );
    }

    /// A plan claim's as-written counterpart: the set's own where it ran all the claim's specs,
    /// the plan's where it ran none, none where it ran only some; the summary lists the verdicts
    /// that reproduce the thesis only under calibration.
    #[test]
    fn claims_meet_their_as_written_verdicts_and_the_summary_names_calibration_only() {
        let claim = |spec: &str, ours| Claim {
            spec: spec.into(),
            ..Claim::most("4", "X", ours).thesis(Some((15, 15)))
        };
        let all = vec![
            claim("ch4_models", (15, 15)),
            claim("ch5_same", (15, 15)),
            claim("ch6_same+ch6_diff", (15, 15)),
            claim("ch6_same+ch6_exact", (15, 15)),
        ];
        let set = (
            vec!["ch4_models".to_string(), "ch6_same".into(), "ch6_diff".into()],
            vec![claim("ch4_models", (2, 15)), claim("ch6_same+ch6_diff", (14, 15))],
        );
        let pairs = beside_as_written(all.clone(), Some(&set));
        let got: Vec<Option<(usize, usize)>> =
            pairs.iter().map(|(_, w)| w.as_ref().map(|w| w.ours)).collect();
        assert_eq!(got, [Some((2, 15)), Some((15, 15)), Some((14, 15)), None]);
        let md = as_written_summary(&pairs, true, 3);
        assert!(md.contains("3 of this plan's readings are calibrated"), "{md}");
        assert!(
            md.contains("1 of 3 verdicts differ under the as-written readings; 1 reproduce"),
            "{md}"
        );
        assert!(md.contains("- ch4_models (all): X: holds 15/15 under the plan's readings, does not hold 2/15 as written"), "{md}");
        assert!(beside_as_written(all, None).iter().all(|(_, w)| w.is_none()));
        assert!(as_written_summary(&pairs, false, 2).contains("has no `as_written` set"));
        assert!(
            as_written_summary(&[], false, 0).contains("every verdict here is the as-written one")
        );
    }

    #[test]
    fn links_point_into_the_sub_folder() {
        assert_eq!(
            relink("![a](png/a.png) and [b](https://x) [c](#c)", "ch4"),
            "![a](ch4/png/a.png) and [b](https://x) [c](#c)"
        );
    }
}
