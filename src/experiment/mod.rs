//! Experiments: spec -> cells -> runs (on per-cell random streams) -> report files and manifest.

pub mod ch4;
pub mod ch5;
pub mod ch6;
pub mod compare;
pub mod datasets;
pub mod fit_cmd;
pub mod runner;
pub mod seed001;
pub mod seeds;
pub mod spec;

use anyhow::{Context, Result};
use serde::Serialize;
use spec::Spec;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where and how a run happens (everything that is not the spec).
#[derive(Debug, Clone)]
pub struct RunContext {
    pub out: PathBuf,
    pub jobs: usize,
    pub data_dir: PathBuf,
}

/// One line per cell for `--dry-run`: key and seed.
pub fn dry_run_listing(spec: &Spec) -> Vec<(String, String)> {
    let keys: Vec<String> = spec.som_cells().iter().map(|c| c.key()).chain(spec.fit_cells().iter().map(|c| c.key())).chain(spec.optim_cells().iter().map(|c| c.key())).chain(seed001::cells(spec).iter().map(|c| c.key())).collect();
    keys.into_iter()
        .map(|k| {
            let s = seeds::seed_hex(spec.file.master_seed, &k);
            (k, s)
        })
        .collect()
}

/// The manifest: enough to re-run exactly.
#[derive(Debug, Serialize)]
pub struct Manifest {
    pub spec_name: String,
    pub spec_path: String,
    pub spec_sha256: String,
    pub profile: String,
    pub master_seed: u64,
    pub crate_version: String,
    pub git_commit: String,
    pub git_dirty: bool,
    pub rustc: String,
    pub host: String,
    pub jobs: usize,
    pub cells: usize,
    pub started_unix: u64,
    pub wall_seconds: f64,
    pub cpu_seconds_cells: f64,
    pub definitions: Definitions,
    pub spec_text: String,
}

/// The exact metric definitions a run used (libraries disagree on them).
#[derive(Debug, Serialize)]
pub struct Definitions {
    pub qe: String,
    pub te: String,
    pub te_adjacency: String,
    pub qe_final: String,
    pub te_final: String,
    pub cpu_s: String,
}

impl Default for Definitions {
    fn default() -> Self {
        Definitions {
            qe: "mean over training iterations of |X(t) - W_c(t)| (Euclidean, before the update) (thesis Eq. 4.15)".into(),
            te: "share of training iterations whose first and second winners are not adjacent (Eq. 4.16)".into(),
            te_adjacency: "index distance 1: 4-neighbourhood on 2-D maps, 6-neighbourhood in the 3-D lattice and CKSOM surface, 4-neighbourhood on either DNSOM view over class numbers".into(),
            qe_final: "mean Euclidean distance of every data point to its best-matching unit after training".into(),
            te_final: "share of data points whose two best units are not adjacent (adjacency as above)".into(),
            cpu_s: "thread CPU seconds of weight initialisation and the T training iterations".into(),
        }
    }
}

fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .or_else(|_| std::env::var("HOSTNAME"))
        .unwrap_or_else(|_| "unknown".into())
}

/// Run a whole spec: cells, tables, pictures, REPORT.md, and last the manifest (its presence marks
/// a complete run; an old one is removed first).
pub fn run_spec(spec: &Spec, ctx: &RunContext) -> Result<PathBuf> {
    crate::report::fsio::ensure_dir(&ctx.out)?;
    let probe = ctx.out.join(".somnurbs-write-test");
    std::fs::write(&probe, b"").with_context(|| format!("output folder {} is not writable", ctx.out.display()))?;
    let _ = std::fs::remove_file(&probe);
    let manifest_path = ctx.out.join("manifest.toml");
    if manifest_path.exists() {
        std::fs::remove_file(&manifest_path).with_context(|| format!("cannot remove {}", manifest_path.display()))?;
    }
    let started = Instant::now();
    let started_unix = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);

    let (section, cpu, cells) = if spec.file.som.is_some() {
        let runs = ch4::run(spec, ctx)?;
        let section = crate::report::ch4::write(spec, &runs, &ctx.out)?;
        (section, runs.iter().map(|r| r.row.cpu_s).sum::<f64>(), runs.len())
    } else if spec.file.growing_grid.is_some() {
        let maps = seed001::maps(spec, ctx)?;
        let problems = seed001::problems(spec, &maps)?;
        let runs = seed001::run(spec, ctx, &problems)?;
        let section = crate::report::seed001::write(&maps, &problems, &runs, &ctx.out)?;
        (section, maps.iter().map(|m| m.cpu_s).sum::<f64>() + runs.iter().map(|r| r.row.cpu_s).sum::<f64>(), runs.len())
    } else if spec.file.optim.is_some() {
        let problems = ch6::problems(spec, ctx)?;
        let exact = ch6::exact_optima(spec, ctx, &problems)?;
        let runs = ch6::run(spec, ctx, &problems)?;
        let section = crate::report::ch6::write(&runs, &problems, &exact, &ctx.out)?;
        (section, runs.iter().map(|r| r.row.cpu_s).sum::<f64>(), runs.len())
    } else {
        let maps = ch5::maps(spec, ctx)?;
        let runs = ch5::run(spec, ctx, &maps)?;
        let origins: Vec<(String, String)> = maps.iter().map(|(d, m)| (d.clone(), m.origin.clone())).collect();
        let pictures = spec.file.fit.as_ref().map(|f| f.pictures).unwrap_or(false);
        let section = crate::report::ch5::write(&runs, &ctx.out, &origins, pictures)?;
        (section, runs.iter().map(|r| r.row.cpu_s).sum::<f64>(), runs.len())
    };

    let manifest = Manifest {
        spec_name: spec.file.name.clone(),
        spec_path: spec.path.clone(),
        spec_sha256: hex::encode(<sha2::Sha256 as sha2::Digest>::digest(spec.text.as_bytes())),
        profile: spec.profile.clone().unwrap_or_else(|| "default".into()),
        master_seed: spec.file.master_seed,
        crate_version: env!("CARGO_PKG_VERSION").into(),
        git_commit: env!("SOMNURBS_GIT_COMMIT").into(),
        git_dirty: env!("SOMNURBS_GIT_DIRTY") == "true",
        rustc: env!("SOMNURBS_RUSTC").into(),
        host: host_name(),
        jobs: ctx.jobs,
        cells,
        started_unix,
        wall_seconds: started.elapsed().as_secs_f64(),
        cpu_seconds_cells: cpu,
        definitions: Definitions::default(),
        spec_text: spec.text.clone(),
    };
    let report = crate::report::report_md(spec, &manifest, &[section]);
    crate::report::fsio::write_atomic(&ctx.out.join("REPORT.md"), report.as_bytes())?;
    let _ = std::fs::remove_file(ctx.out.join("runs.csv.partial"));
    let text = toml::to_string_pretty(&manifest).context("cannot serialise the manifest")?;
    crate::report::fsio::write_atomic(&manifest_path, text.as_bytes())?;
    Ok(ctx.out.clone())
}

/// Resolve the data directory: flag, else `SOMNURBS_DATA`, else `./data`.
pub fn data_dir(flag: Option<&Path>) -> PathBuf {
    if let Some(p) = flag {
        return p.to_path_buf();
    }
    match std::env::var_os("SOMNURBS_DATA") {
        Some(v) if !v.is_empty() => PathBuf::from(v),
        _ => PathBuf::from("data"),
    }
}
