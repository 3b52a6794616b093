//! Chapter 6's problems outside a run, as a benchmark suite (issue 39): what the Python package
//! (`python/`) and any other caller get. The problems are made by the run's own code path
//! ([`super::problems`]) from the same spec, profile and `--set` readings, so a problem's fitness
//! is bit for bit the one `somnurbs run` optimises; this module only adds what a benchmark user
//! needs beside it (names, a second box, the metadata that `compare` checks an external
//! optimiser's logs against).

use super::spec::OptimSpec;
use crate::experiment::overrides::CliOverrides;
use crate::experiment::spec::{GridSize, Spec};
use crate::experiment::RunContext;
use crate::optim::ExactOptions;
use crate::spline::{BoxSpec, ControlNetProblem, Parameterisation};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// One control-net problem of a spec.
#[derive(Debug, Clone)]
pub struct SuiteProblem {
    /// The IOHprofiler function name, as `ioh/` of a run names it
    /// (`<dataset>_<grid>_<net>_<parameterisation>`).
    pub name: String,
    pub dataset: String,
    pub grid: GridSize,
    pub net: GridSize,
    pub param: Parameterisation,
    /// In the spec's search box: the problem `somnurbs run` optimises.
    pub problem: ControlNetProblem,
    /// The same fitness in the data-range box (the smallest per-axis box holding the data and
    /// B's control points, `BoxSpec::Cover { fraction: 0 }`).
    pub wide: ControlNetProblem,
}

/// Every problem of a spec, with the metadata common to them.
#[derive(Debug, Clone)]
pub struct Suite {
    pub spec_name: String,
    pub profile: Option<String>,
    /// The knot reading of approach B's start (README "Readings"): `eq2_10` or `nurbs_book`.
    pub reading: String,
    /// The spec's search box in words ([`box_label`]).
    pub box_label: String,
    /// The exact solver's settings of the spec (its `exact_tol`, `exact_newton_steps`).
    pub exact: ExactOptions,
    pub problems: Vec<SuiteProblem>,
}

/// The search box of an `[optim]` section in words: `B+-<half width>` (Table 6.1's reading) or
/// `cover+<margin>` (the data and B's control points, widened by that share).
pub fn box_label(o: &OptimSpec) -> String {
    match o.search_range {
        Some(r) => format!("B+-{r:e}"),
        None => format!("cover+{:e}", o.bounds_margin),
    }
}

/// A spec by file path, or by the name of a shipped one (`ch6_same`): `experiments/<name>.toml`
/// in the working folder, else in the clone somnurbs was built from.
pub fn spec_path(spec: &str) -> PathBuf {
    let p = Path::new(spec);
    if p.extension().is_some_and(|e| e == "toml") || p.components().count() > 1 {
        return p.to_path_buf();
    }
    let here = Path::new("experiments").join(format!("{spec}.toml"));
    if here.is_file() {
        return here;
    }
    Path::new(crate::data::registry::CLONE_DIR).join("experiments").join(format!("{spec}.toml"))
}

/// Load every control-net problem of a Chapter 6 spec (`[optim]`) under `profile` and the
/// `KEY=VALUE` settings of `set` (as `somnurbs run --set`, e.g. `optim.knots=nurbs_book`).
/// Data files come from `data_dir` (else as the CLI finds them, falling back to the clone's
/// `data/`); a map the spec names but that is missing is recomputed as the run would, written
/// into `work` (a folder the caller owns).
pub fn load(
    spec: &str,
    profile: Option<&str>,
    set: &[String],
    data_dir: Option<&Path>,
    work: &Path,
) -> Result<Suite> {
    // The CLI's families (the engine reads specs through them; a no-op once installed).
    crate::families::install();
    let path = spec_path(spec);
    let cli = CliOverrides { set: set.to_vec(), sweep: Vec::new() };
    let mut variants = Spec::load_variants(&path, profile, &cli)?;
    let spec = variants.pop().context("no spec")?;
    let o = spec.require::<OptimSpec>()?;
    let data_dir = match data_dir {
        Some(d) => d.to_path_buf(),
        None => {
            let d = crate::experiment::data_dir(None);
            if d.is_dir() {
                d
            } else {
                crate::data::registry::clone_data_dir()
            }
        }
    };
    let ctx = RunContext::new(work.to_path_buf(), 1, data_dir);
    let built = super::problems(&spec, &ctx)?;
    let mut problems = Vec::with_capacity(built.len());
    for ((dataset, net, param), problem) in built {
        let wide = ControlNetProblem::new(problem.parts().clone(), BoxSpec::Cover { fraction: 0.0 })
            .with_context(|| format!("{dataset} {net} {}: the data-range box", param.name()))?;
        problems.push(SuiteProblem {
            name: super::ioh::problem_name(
                &dataset,
                &o.grid.to_string(),
                &net.to_string(),
                param.name(),
            ),
            dataset,
            grid: o.grid,
            net,
            param,
            problem,
            wide,
        });
    }
    Ok(Suite {
        spec_name: spec.file.name.clone(),
        profile: profile.map(String::from),
        reading: o.knots.name().to_string(),
        box_label: box_label(o),
        exact: o.exact_options(),
        problems,
    })
}
