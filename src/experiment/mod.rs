//! Experiments: spec -> cells -> runs (on per-cell random streams) -> report files and manifest.

pub(crate) mod datasets;
pub(crate) mod defaults;
pub(crate) mod family;
pub(crate) mod finite;
pub(crate) mod grid_size;
pub(crate) mod limits;
pub(crate) mod log;
pub(crate) mod overrides;
pub(crate) mod packed;
pub(crate) mod readings;
pub(crate) mod renamed;
pub(crate) mod reproduce;
pub(crate) mod runner;
pub(crate) mod seeds;
pub(crate) mod spec;

use anyhow::{Context, Result};
use family::Families;
pub use grid_size::GridSize;
pub use log::log_text;
pub use overrides::Override;
pub use runner::{run_cells, thread_cpu_seconds};
pub use seeds::{cell_rng, seed_hex};
use serde::Serialize;
use spec::{Loaded, Spec};
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// Where and how a run happens (everything that is not the spec).
#[derive(Debug, Clone)]
pub struct RunContext {
    pub out: PathBuf,
    pub jobs: usize,
    pub data_dir: PathBuf,
    /// Keep the cells already in the folder's cell log (same fingerprint required).
    pub resume: bool,
    /// Run only this slice of the cells (no tables: `somnurbs merge` makes them).
    pub shard: Option<log::Shard>,
    /// Set by `run_spec`: the folder's start, done once the inputs have loaded.
    pub session: Option<Arc<Session>>,
    /// Write `report.html` (and its `vendor/`) beside REPORT.md before the manifest: a folder
    /// that is a result of its own (`run`, `merge`), not a chapter of a plan's page.
    pub page: bool,
    /// The command REPORT.md gives to make this folder again, when it is not `somnurbs run` of
    /// the spec (a plan's spec: the plan's `somnurbs reproduce` line).
    pub rerun: Option<String>,
    /// Write the pictures, the 3-D views and the IOHprofiler export (off for a plan's reading
    /// variants, whose tables and claims are what the readings matrix compares).
    pub extras: bool,
    /// Other result folders whose cell logs may hold cells of this run: a cell found there by
    /// its whole key (what it computes) is taken, not computed again (`--reuse`, a plan's
    /// reading sets).
    pub reuse: Vec<PathBuf>,
    /// Whether a cell missing from the logs may be computed (`false`: `merge`, `report`, which
    /// build every table from records alone and name a missing cell).
    pub compute: bool,
    /// Whether the maps a family reads are copied into the folder's `maps/` (off for `export`,
    /// which reads a finished folder's copy and writes only its own files).
    pub keep_maps: bool,
}

impl RunContext {
    /// A plain run: fresh folder, all cells.
    pub fn new(out: PathBuf, jobs: usize, data_dir: PathBuf) -> RunContext {
        RunContext {
            out,
            jobs,
            data_dir,
            resume: false,
            shard: None,
            session: None,
            page: false,
            rerun: None,
            extras: true,
            reuse: Vec::new(),
            compute: true,
            keep_maps: true,
        }
    }

    /// Make the folder this run's: called by the runner when the first cell is about to run,
    /// i.e. after every input (spec, data, maps) has loaded, and before anything is written. The
    /// folder is empty or holds this run unfinished (`claim`); the first call writes the
    /// fingerprint and starts the cell log (kept when resuming); later calls do nothing.
    pub fn begin(&self) -> Result<()> {
        let Some(session) = &self.session else { return Ok(()) };
        let mut pending =
            session.pending.lock().map_err(|_| anyhow::anyhow!("run state lock poisoned"))?;
        if let Some(fp) = pending.take() {
            fp.write(&self.out)?;
            drop(log::CellLog::open(&self.out, self.resume, session.master_seed)?);
        }
        Ok(())
    }

    /// How `spec`'s data sets load: from this run's data folder, relative paths from the spec's
    /// own folder, scaled by the spec's `normalise`; generated shapes as by default (a family
    /// with a reading of one sets it on the loader).
    pub fn loader(&self, spec: &Spec) -> crate::data::registry::Loader {
        crate::data::registry::Loader {
            data_dir: self.data_dir.clone(),
            base: spec.dir().to_path_buf(),
            normalise: spec.file.normalise,
            spindle: Default::default(),
        }
    }

    /// The master seed the cell log tags records with (0 outside `run_spec`).
    pub fn master_seed(&self) -> u64 {
        self.session.as_ref().map_or(0, |s| s.master_seed)
    }
}

/// What `run_spec` hands the runner: the spec's master seed and the folder reset still to do.
#[derive(Debug)]
pub struct Session {
    pub master_seed: u64,
    pending: std::sync::Mutex<Option<log::Fingerprint>>,
}

/// Every check a run makes before its first cell, before the folder is touched (`run` and
/// `--dry-run` call this one function): each data file the spec names is there and loads, the
/// maps folder it names is there (unless it asks for the maps to be recomputed), and each data
/// set has enough points for the maps trained on it. Data are loaded here once more than the run
/// needs: milliseconds for the largest scan.
pub(crate) fn preflight<F: Families>(spec: &Loaded<F>, ctx: &RunContext) -> Result<()> {
    let (loaded, spec) = (spec, &spec.spec);
    for d in limits::dataset_entries(loaded) {
        ctx.loader(spec).load(d).with_context(|| format!("{}: data set `{d}`", spec.path))?;
    }
    loaded.family().require_inputs(spec, &loaded.section, ctx)
}

/// One line per cell for `--dry-run`: key and seed.
pub fn dry_run_listing<F: Families>(spec: &Loaded<F>) -> Vec<(String, String)> {
    logged_cell_keys(spec)
        .into_iter()
        .map(|k| {
            let s = seeds::seed_hex(spec.spec.file.master_seed, &k);
            (k, s)
        })
        .collect()
}

/// The keys of every cell of a spec that goes through the cell log (what a merge must find).
pub(crate) fn logged_cell_keys<F: Families>(spec: &Loaded<F>) -> Vec<String> {
    spec.family().logged_keys(&spec.spec, &spec.section)
}

/// [`logged_cell_keys`] of every variant of a run, in order.
fn logged_variant_keys<F: Families>(variants: &[Loaded<F>]) -> Vec<String> {
    variants.iter().flat_map(logged_cell_keys).collect()
}

/// The manifest: enough to re-run exactly.
#[derive(Debug, Serialize, serde::Deserialize)]
pub(crate) struct Manifest {
    pub(crate) spec_name: String,
    pub(crate) spec_path: String,
    pub(crate) spec_sha256: String,
    pub(crate) profile: String,
    pub(crate) master_seed: u64,
    /// `I/N` when this folder holds one shard of the cells (no tables).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) shard: Option<String>,
    /// The command line's `--set KEY=VALUE` and `--sweep KEY=V1,V2` (absent for a plain run).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) set: Vec<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) sweep: Vec<String>,
    pub(crate) crate_version: String,
    pub(crate) git_commit: String,
    pub(crate) git_dirty: bool,
    pub(crate) rustc: String,
    pub(crate) host: String,
    pub(crate) jobs: usize,
    pub(crate) cells: usize,
    /// The cells this folder's run computed, and those it took from another folder's records
    /// (`--reuse`, a plan's reading sets) because they compute the same.
    #[serde(default)]
    pub(crate) cells_computed: usize,
    #[serde(default)]
    pub(crate) cells_reused: usize,
    pub(crate) started_unix: u64,
    pub(crate) wall_seconds: f64,
    pub(crate) cpu_seconds_cells: f64,
    /// The command REPORT.md names to make the folder again, and whether the folder has its own
    /// report.html and its pictures (what `somnurbs report` renders again).
    #[serde(default)]
    pub(crate) rerun: String,
    #[serde(default)]
    pub(crate) page: bool,
    #[serde(default)]
    pub(crate) extras: bool,
    /// The family's metric definitions (none: no table).
    #[serde(skip_serializing_if = "Definitions::is_empty", skip_deserializing)]
    pub(crate) definitions: Definitions,
    pub(crate) spec_text: String,
}

/// The exact definitions of the metrics a family reports (libraries disagree on them), in its
/// order: (name, definition).
#[derive(Debug, Clone, Copy, Default)]
pub struct Definitions(pub &'static [(&'static str, &'static str)]);

impl Definitions {
    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl Serialize for Definitions {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(self.0.iter().copied())
    }
}

/// The fingerprint of a run of a spec's variants (one for a plain run) in a folder (what
/// `--resume` and `merge` compare).
pub(crate) fn fingerprint<F: Families>(
    variants: &[Loaded<F>],
    shard: Option<log::Shard>,
) -> log::Fingerprint {
    let spec = &variants[0].spec;
    log::Fingerprint {
        spec_name: spec.file.name.clone(),
        spec_path: spec.path.clone(),
        spec_sha256: hex::encode(<sha2::Sha256 as sha2::Digest>::digest(spec.text.as_bytes())),
        profile: spec.profile.clone().unwrap_or_else(|| "default".into()),
        master_seed: spec.file.master_seed,
        cells: logged_variant_keys(variants).len(),
        shard: shard.map(|s| s.to_string()),
        spec_text: spec.text.clone(),
        set: spec.cli.set.clone(),
        sweep: spec.cli.sweep.clone(),
        readings: spec.readings.clone(),
    }
}

/// Run a whole spec: cells, tables, pictures, REPORT.md, report.html, and last the manifest (its
/// presence marks a complete run). The folder is locked for the whole run (one writer) and must
/// be empty, or with `resume` hold this same run ([`claim`]); the fingerprint and the cell log
/// come only when the first cell is about to run ([`RunContext::begin`]), after every input
/// (data, maps) has loaded. With a shard, only its cells run and no tables are written (`merge`
/// writes them). With `resume`, the cells in the folder's log are kept if the folder's
/// fingerprint and every logged seed match, else the run is refused before anything is touched;
/// a folder that already holds this run finished is left as it is.
pub(crate) fn run_spec<F: Families>(spec: &Loaded<F>, ctx: &RunContext) -> Result<PathBuf> {
    run_variants(std::slice::from_ref(spec), ctx)
}

/// [`run_spec`] of the variants of one spec (`--set`/`--sweep`: [`spec::CliOverrides`]) into one
/// folder: one cell log, one fingerprint and manifest, the family's tables over every variant.
pub(crate) fn run_variants<F: Families>(
    variants: &[Loaded<F>],
    ctx: &RunContext,
) -> Result<PathBuf> {
    let first = variants.first().context("no spec to run")?;
    let spec = &first.spec;
    preflight(first, ctx)?;
    let _lock = crate::io::outdir::lock(&ctx.out, &format!("run {}", spec.path))?;
    let fp = fingerprint(variants, ctx.shard);
    match claim(&ctx.out, &fp, ctx.resume)? {
        Claimed::Finished => {
            crate::notice::emit(&format!(
                "somnurbs: {} already holds this run, finished; nothing to do (`somnurbs report {}` makes a lost table or picture again from its records)",
                ctx.out.display(),
                ctx.out.display()
            ));
            Ok(ctx.out.clone())
        }
        Claimed::Start => run_spec_locked(variants, ctx),
    }
}

/// What a writer may do with its (locked) output folder.
#[derive(Debug, PartialEq)]
enum Claimed {
    /// Run: the folder is empty, or (resuming) holds this run unfinished.
    Start,
    /// The folder holds this run finished (resuming): leave it as it is.
    Finished,
}

/// The folder contract for a run: a fresh run needs an empty folder; `--resume` needs an empty
/// folder or one holding this same run (its fingerprint), whose leftover temporary files it
/// removes. Anything else is refused, naming what the folder holds.
fn claim(out: &Path, fp: &log::Fingerprint, resume: bool) -> Result<Claimed> {
    if !resume {
        crate::io::outdir::require_empty(out)?;
        return Ok(Claimed::Start);
    }
    let Some(old) = log::Fingerprint::read(out)? else {
        if log::has_log(out) {
            anyhow::bail!(
                "cannot resume in {}: it has a cell log but no {}",
                out.display(),
                log::FINGERPRINT_FILE
            );
        }
        crate::io::outdir::require_empty(out)?;
        return Ok(Claimed::Start);
    };
    if let Some(diff) = old.difference(fp) {
        anyhow::bail!("cannot resume in {}: it holds a different run ({diff}); use another --out or drop --resume", out.display());
    }
    if out.join(crate::io::outdir::MANIFEST).exists() {
        return Ok(Claimed::Finished);
    }
    let removed = crate::io::outdir::remove_leftovers(out)?;
    if removed > 0 {
        crate::notice::emit(&format!(
            "somnurbs: removed {removed} temporary file(s) the interrupted run left in {}",
            out.display()
        ));
    }
    Ok(Claimed::Start)
}

/// [`run_variants`] in a folder the caller has locked and claimed.
fn run_spec_locked<F: Families>(variants: &[Loaded<F>], ctx: &RunContext) -> Result<PathBuf> {
    render_locked(variants, ctx, None)
}

/// [`run_spec_locked`], or with `stored` (a finished folder's manifest: `somnurbs report`) the
/// tables, pictures and REPORT.md of its records alone, under its own manifest, which stays.
fn render_locked<F: Families>(
    variants: &[Loaded<F>],
    ctx: &RunContext,
    stored: Option<Manifest>,
) -> Result<PathBuf> {
    let first = variants.first().context("no spec to run")?;
    let spec = &first.spec;
    let fp = fingerprint(variants, ctx.shard);
    let manifest_path = ctx.out.join(crate::io::outdir::MANIFEST);
    let session = Arc::new(Session {
        master_seed: spec.file.master_seed,
        pending: std::sync::Mutex::new(stored.is_none().then(|| fp.clone())),
    });
    let ctx = &RunContext { session: Some(session), ..ctx.clone() };
    let started = Instant::now();
    let started_unix = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let tables = ctx.shard.is_none();

    let family = first.family();
    let family::Outcome { section, cpu_s: cpu, cells } =
        family.run_variants(variants, ctx, tables)?;
    ctx.begin()?;

    let cells_reused = log::count_reused(&ctx.out)?;
    let rerun = ctx.rerun.clone().unwrap_or_else(|| run_command(spec, &fp, &ctx.out));
    let manifest = Manifest {
        spec_name: spec.file.name.clone(),
        spec_path: spec.path.clone(),
        spec_sha256: fp.spec_sha256.clone(),
        profile: fp.profile.clone(),
        master_seed: spec.file.master_seed,
        shard: fp.shard.clone(),
        set: fp.set.clone(),
        sweep: fp.sweep.clone(),
        crate_version: env!("CARGO_PKG_VERSION").into(),
        git_commit: env!("SOMNURBS_GIT_COMMIT").into(),
        git_dirty: env!("SOMNURBS_GIT_DIRTY") == "true",
        rustc: env!("SOMNURBS_RUSTC").into(),
        host: crate::io::outdir::host_name(),
        jobs: ctx.jobs,
        cells,
        cells_computed: cells.saturating_sub(cells_reused),
        cells_reused,
        started_unix,
        wall_seconds: started.elapsed().as_secs_f64(),
        cpu_seconds_cells: cpu,
        rerun,
        page: ctx.page,
        extras: ctx.extras,
        definitions: family.definitions(),
        spec_text: spec.text.clone(),
    };
    let (manifest, write_manifest) = match stored {
        Some(m) => (Manifest { definitions: family.definitions(), ..m }, false),
        None => (manifest, true),
    };
    if let Some(section) = section {
        let mut report = report_md(first, &manifest, &manifest.rerun, &[section]);
        if !ctx.extras {
            report.push_str(NO_PICTURES);
        }
        crate::io::write_atomic(&ctx.out.join("REPORT.md"), report.as_bytes())?;
        if ctx.page {
            crate::report::html::write(&ctx.out)?;
        }
    }
    // A finished run's log is kept compressed (a shard's stays plain for `merge`).
    if tables {
        log::compress(&ctx.out)?;
    }
    // The manifest is the very last write: its presence says every file above is whole.
    if write_manifest {
        let text = toml::to_string_pretty(&manifest).context("cannot serialise the manifest")?;
        crate::io::write_atomic(&manifest_path, text.as_bytes())?;
    }
    Ok(ctx.out.clone())
}

/// `somnurbs report DIR`: the tables, pictures, REPORT.md and report.html of a finished folder
/// of `somnurbs run` (or `merge`), made again from its cell records alone (no cell runs; a
/// missing record is an error naming the cell). A file that is missing is written; one that is
/// there must already hold exactly what the records render (the folder is never rewritten).
pub(crate) fn report<F: Families>(dir: &Path, data_dir: PathBuf, jobs: usize) -> Result<PathBuf> {
    let _lock = crate::io::outdir::lock_to_fill(dir, "report")?;
    let fp = log::Fingerprint::read(dir)?.with_context(|| {
        if dir.join(crate::io::outdir::PLAN_FILE).exists() {
            return format!(
                "{}: a `reproduce` folder: `somnurbs report` re-renders each spec's sub-folder (e.g. {}); its combined REPORT.md is `reproduce`'s",
                dir.display(),
                dir.join("ch6_same").display()
            );
        }
        format!(
            "{}: no {}; name a folder `somnurbs run` or `merge` wrote",
            dir.display(),
            log::FINGERPRINT_FILE
        )
    })?;
    if let Some(s) = &fp.shard {
        anyhow::bail!("{}: holds shard {s} only; `somnurbs merge` the shards", dir.display());
    }
    let path = dir.join(crate::io::outdir::MANIFEST);
    if !path.exists() {
        anyhow::bail!(
            "{}: the run is not finished (no {}); `somnurbs run ... --resume` finishes it",
            dir.display(),
            crate::io::outdir::MANIFEST
        );
    }
    let manifest: Manifest = crate::io::read_toml(&path)?;
    if manifest.rerun.is_empty() {
        anyhow::bail!(
            "{}: written by an older somnurbs (no `rerun`): run the spec again",
            path.display()
        );
    }
    let profile = (fp.profile != "default").then_some(fp.profile.as_str());
    let mut variants: Vec<Loaded<F>> = if fp.readings.is_empty() {
        fp.overrides().variants(&fp.spec_path, &fp.spec_text, profile)
    } else {
        let over = fp.reading_overrides();
        Loaded::parse_reaching(&fp.spec_path, &fp.spec_text, profile, &over).map(|(l, _)| vec![l])
    }
    .with_context(|| format!("{}: the folder's spec", dir.display()))?;
    if let Some(maps) = reproduce::plan_maps_of(dir)? {
        for v in &mut variants {
            let family = v.family();
            family.use_maps(&mut v.section, &maps);
        }
    }
    let ctx = RunContext {
        resume: true,
        compute: false,
        page: manifest.page,
        extras: manifest.extras,
        rerun: Some(manifest.rerun.clone()),
        ..RunContext::new(dir.to_path_buf(), jobs, data_dir)
    };
    render_locked(&variants, &ctx, Some(manifest))
}

/// The `somnurbs run` command that makes the folder `out` again: the spec, its profile, `--out`
/// unless it is the spec's default folder, and every `--set` and `--sweep`.
pub(crate) fn run_command(spec: &Spec, m: &log::Fingerprint, out: &Path) -> String {
    let mut s = format!("somnurbs run {}", m.spec_path);
    if m.profile != "default" {
        let _ = write!(s, " --profile {}", m.profile);
    }
    if out != spec.output_dir(None) {
        let _ = write!(s, " --out {}", out.display());
    }
    for a in &m.set {
        let _ = write!(s, " --set {a}");
    }
    for a in &m.sweep {
        let _ = write!(s, " --sweep {a}");
    }
    s
}

/// REPORT.md: a header naming the run and the command that makes it again (`rerun`), then the
/// chapters' sections.
pub(crate) fn report_md<F: Families>(
    loaded: &Loaded<F>,
    m: &Manifest,
    rerun: &str,
    sections: &[String],
) -> String {
    let spec = &loaded.spec;
    let mut s = String::new();
    let _ = writeln!(s, "# somnurbs report: {}\n", spec.file.name);
    if !spec.file.description.is_empty() {
        let _ = writeln!(s, "{}\n", spec.file.description.trim());
    }
    let commit = if m.git_commit.is_empty() {
        "unknown".to_string()
    } else {
        format!(
            "{}{}",
            &m.git_commit[..m.git_commit.len().min(12)],
            if m.git_dirty { " (dirty)" } else { "" }
        )
    };
    let _ = writeln!(
        s,
        "Spec `{}` (sha256 {}), profile `{}`, master seed {}, somnurbs {} at commit {}, {} on {} with {} thread(s): {} cells{} in {:.1} s wall, {:.1} s CPU in cells. Re-run: `{}`.\n",
        m.spec_path,
        &m.spec_sha256[..12],
        m.profile,
        m.master_seed,
        m.crate_version,
        commit,
        m.rustc,
        m.host,
        m.jobs,
        m.cells,
        if m.cells_reused > 0 {
            format!(" ({} computed, {} reused from another folder's records)", m.cells_computed, m.cells_reused)
        } else {
            String::new()
        },
        m.wall_seconds,
        m.cpu_seconds_cells,
        rerun
    );
    s.push_str(&profile_note(spec));
    if !limits::dataset_entries(loaded).is_empty() {
        let _ = writeln!(s, "Data sets are {} (`normalise`); a data set given as a relative path is read from the spec's folder.\n", spec.file.normalise.describe());
    }
    for sec in sections {
        s.push_str(sec);
        s.push('\n');
    }
    s
}

/// What the profile changed from the spec as written and, for a reduced profile, the caveat that
/// its counts are no evidence (empty for the spec as written).
pub(crate) fn profile_note(spec: &Spec) -> String {
    let changes = spec.profile_changes();
    let Some(profile) = spec.profile.as_deref().filter(|_| !changes.is_empty()) else {
        return String::new();
    };
    let list: Vec<String> = changes.iter().map(|c| format!("`{} = {}`", c.key, c.value)).collect();
    let mut s =
        format!("Profile `{profile}` changes the spec as written: {}.\n\n", list.join(", "));
    if changes.iter().any(|c| c.reduces) {
        s.push_str(NOT_EVIDENCE);
    }
    s
}

/// The note of a run drawn without pictures.
pub(crate) const NO_PICTURES: &str = "\nNo pictures, 3-D views or IOHprofiler export are written in this folder: it is a reading variant of a plan, whose tables and claims the plan's readings matrix compares. Run the spec with the variant's keys (`somnurbs run SPEC --set KEY=VALUE ...`) to have them.\n";

/// The caveat a reduced run carries at the top of its report.
pub(crate) const NOT_EVIDENCE: &str = "> **Not evidence.** This is a reduced run (fewer cells, repeats or iterations than the spec as written), for checking the harness and the pipeline. Its counts are too few to support or refute a claim, and its verdicts are mostly *undecided* for that reason; cite only a run of the spec as written.\n\n";

/// Combine shard folders of one spec into `out` and write its tables: the shards' fingerprints
/// must agree (apart from the shard) and cover 1..N once, each shard finished, its logged seeds
/// the spec's, and their cell logs together hold exactly the spec's cells; the logs are joined and
/// the spec is run in `out` (locked, and empty) with every cell restored from the log, so the
/// tables equal a one-machine run's.
pub(crate) fn merge<F: Families>(shards: &[PathBuf], ctx: &RunContext) -> Result<PathBuf> {
    if shards.is_empty() {
        anyhow::bail!("merge: no shard folders given");
    }
    log::out_is_no_shard(shards, &ctx.out)?;
    let _lock = crate::io::outdir::lock(&ctx.out, "merge")?;
    crate::io::outdir::require_empty(&ctx.out).context("merge")?;
    let mut first: Option<log::Fingerprint> = None;
    let mut seen: BTreeMap<usize, PathBuf> = BTreeMap::new();
    let mut count = 0;
    let mut records: BTreeMap<String, serde_json::Value> = BTreeMap::new();
    for dir in shards {
        crate::io::outdir::require_not_being_written(dir).context("merge")?;
        let fp = log::Fingerprint::read(dir)?.with_context(|| {
            format!(
                "merge: {} has no {} (not a somnurbs output folder?)",
                dir.display(),
                log::FINGERPRINT_FILE
            )
        })?;
        let shard = fp.shard.as_deref().with_context(|| {
            format!("merge: {} is not a shard (it was run without --shard)", dir.display())
        })?;
        let shard =
            log::Shard::parse(shard).with_context(|| format!("merge: {}", dir.display()))?;
        if !dir.join(crate::io::outdir::MANIFEST).exists() {
            anyhow::bail!("merge: shard {shard} in {} did not finish (no manifest.toml); resume it with --resume first", dir.display());
        }
        let plain = log::Fingerprint { shard: None, ..fp.clone() };
        match &first {
            None => {
                first = Some(plain);
                count = shard.count;
            }
            Some(f) => {
                if let Some(diff) = f.difference(&plain) {
                    anyhow::bail!(
                        "merge: {} belongs to another run than {} ({diff})",
                        dir.display(),
                        shards[0].display()
                    );
                }
                if shard.count != count {
                    anyhow::bail!(
                        "merge: {} is shard {shard} but {} has {count} shards",
                        dir.display(),
                        shards[0].display()
                    );
                }
            }
        }
        if let Some(other) = seen.insert(shard.index, dir.clone()) {
            anyhow::bail!(
                "merge: shard {shard} given twice ({} and {})",
                other.display(),
                dir.display()
            );
        }
        records
            .extend(log::read_records::<serde_json::Value>(dir, fp.master_seed).context("merge")?);
    }
    if let Some(missing) = (1..=count).find(|i| !seen.contains_key(i)) {
        anyhow::bail!("merge: shard {missing}/{count} is missing");
    }
    let fp = first.expect("at least one shard");
    let variants: Vec<Loaded<F>> = fp
        .overrides()
        .variants(
            &fp.spec_path,
            &fp.spec_text,
            if fp.profile == "default" { None } else { Some(fp.profile.as_str()) },
        )
        .context("merge: the shards' spec")?;
    // The log knows a cell by its identity (`PLACE#...`, see `seeds::identity_key`): the shards
    // must hold every place of the spec and no other; the merged run then finds each cell by
    // its identity and computes none.
    let expected: std::collections::BTreeSet<String> =
        logged_variant_keys(&variants).into_iter().collect();
    let places: std::collections::BTreeSet<&str> =
        records.keys().map(|k| seeds::place_of(k)).collect();
    if let Some(k) = expected.iter().find(|k| !places.contains(k.as_str())) {
        anyhow::bail!(
            "merge: no shard logged cell {k} (the shards hold {} of the spec's {} cells)",
            expected.iter().filter(|k| places.contains(k.as_str())).count(),
            expected.len()
        );
    }
    if let Some(k) = records.keys().find(|k| !expected.contains(seeds::place_of(k))) {
        anyhow::bail!("merge: the shards log cell {k}, which the spec does not have");
    }
    {
        let mut out_log = log::CellLog::open(&ctx.out, false, fp.master_seed)?;
        for (key, rec) in &records {
            out_log.push(key, rec)?;
        }
    }
    fingerprint(&variants, None).write(&ctx.out)?;
    run_spec_locked(
        &variants,
        &RunContext { resume: true, shard: None, compute: false, ..ctx.clone() },
    )
}

/// Resolve the data directory: `--data-dir`, else `SOMNURBS_DATA`, else `data/` in the working
/// folder, else the `data/` of the clone somnurbs was built from (said on stderr), the rule of
/// `crate::data::registry::found_folder`.
pub fn data_dir(flag: Option<&Path>) -> PathBuf {
    let (dir, clone) = crate::data::registry::found_folder(flag, Some("SOMNURBS_DATA"), "data");
    if clone {
        crate::notice::emit(&format!(
            "somnurbs: note: no data/ in the working folder; reading data files from the clone somnurbs was built from, {} (--data-dir DIR or SOMNURBS_DATA names another)",
            dir.display()
        ));
    }
    dir
}
