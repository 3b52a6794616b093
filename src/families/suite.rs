//! Chapter 6's problems outside a run, as a benchmark suite: what the Python package
//! (`python/`) and any other caller get. It sits beside the registry, not in a family, because it
//! serves two: the problems are made by the runs' own code paths
//! ([`optimise::problems`] for an `[optimise]` spec; `growing_grid::{maps, problems}` for seed 001's
//! open surfaces) from the same spec, profile and `--set` readings, so a problem's fitness is bit for
//! bit the one `somnurbs run` optimises; this module only adds what a benchmark user needs beside
//! it (names, a second box, the metadata that `compare` checks an external optimiser's logs
//! against).

use super::growing_grid::{self, spec::GrowingGridSpec};
use super::maps::ProblemKey;
use super::optimise::{self, spec::OptimSpec};
use super::{Loaded, Section};
use crate::experiment::overrides::CliOverrides;
use crate::experiment::spec::{GridSize, Spec};
use crate::experiment::RunContext;
use crate::optim::exact::ExactResult;
use crate::optim::{ExactOptions, OptimError, Problem};
use crate::spline::open_surface::OpenSurfaceProblem;
use crate::spline::{BoxSpec, ControlNetProblem, KnotRule, Parameterisation};
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// The fitness of a suite problem: Chapter 6's double net, or seed 001's one open surface.
#[derive(Debug, Clone)]
pub enum Fitness {
    /// In the spec's box, and the same fitness in the data-range box (the smallest per-axis box
    /// holding the data and B's control points, `BoxSpec::Cover { fraction: 0 }`).
    ControlNet { problem: Box<ControlNetProblem>, wide: Box<ControlNetProblem> },
    /// Its box is the spec's (the data and the least-squares net, widened by `bounds_margin`).
    OpenSurface(Box<OpenSurfaceProblem>),
}

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
    pub fitness: Fitness,
}

impl SuiteProblem {
    /// The problem `somnurbs run` optimises (its box is the spec's).
    pub fn problem(&self) -> &dyn Problem {
        match &self.fitness {
            Fitness::ControlNet { problem, .. } => problem.as_ref(),
            Fitness::OpenSurface(p) => p.as_ref(),
        }
    }

    /// The data-range box (lower, upper).
    pub fn data_box(&self) -> (&[f64], &[f64]) {
        match &self.fitness {
            Fitness::ControlNet { wide, .. } => wide.bounds(),
            Fitness::OpenSurface(p) => p.bounds(),
        }
    }

    /// The certified optimum in the spec's box (`data_range: false`) or the data-range box; an
    /// error for seed 001's open surfaces, which have no exact solver.
    pub fn exact(&self, data_range: bool, opts: &ExactOptions) -> Result<ExactResult, OptimError> {
        match &self.fitness {
            Fitness::ControlNet { problem, wide } => {
                if data_range { wide } else { problem }.exact_optimum(opts)
            }
            Fitness::OpenSurface(_) => Err(OptimError::Problem(format!(
                "{}: seed 001's open surfaces have no exact solver",
                self.name
            ))),
        }
    }
}

/// Every problem of a spec, with the metadata common to them.
#[derive(Debug, Clone)]
pub struct Suite {
    pub spec_name: String,
    pub profile: Option<String>,
    /// The knot reading of approach B's start (docs/readings.md): `eq2_10` or `nurbs_book`.
    pub reading: String,
    /// The spec's search box in words ([`box_label`]).
    pub box_label: String,
    /// The exact solver's settings of the spec (its `exact_tol`, `exact_newton_steps`).
    pub exact: ExactOptions,
    pub problems: Vec<SuiteProblem>,
}

/// The search box of an `[optimise]` section in words: `B+-<half width>` (Table 6.1's reading) or
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

/// Load every control-net problem of a Chapter 6 spec (`[optimise]`) or of seed 001's
/// (`[growing_grid]`) under `profile` and the `KEY=VALUE` settings of `set` (as
/// `somnurbs run --set`, e.g. `optimise.knots=nurbs_book`). Data files come from `data_dir` (else as
/// the CLI finds them, falling back to the clone's `data/`); a map the spec names but that is
/// missing is recomputed as the run would, written into `work` (a folder the caller owns).
pub fn load(
    spec: &str,
    profile: Option<&str>,
    set: &[String],
    data_dir: Option<&Path>,
    work: &Path,
) -> Result<Suite> {
    let path = spec_path(spec);
    let cli = CliOverrides { set: set.to_vec(), sweep: Vec::new() };
    let mut variants = Loaded::load_variants(&path, profile, &cli)?;
    let Loaded { spec, section } = variants.pop().context("no spec")?;
    let data_dir = crate::data::registry::found_folder(data_dir, Some("SOMNURBS_DATA"), "data").0;
    let ctx = RunContext::new(work.to_path_buf(), 1, data_dir);
    let o = match &section {
        Section::Optim(o) => o,
        Section::GrowingGrid(g) => return open_surfaces(&spec, g, &ctx, profile),
        _ => anyhow::bail!(
            "{}: a suite is made of an [optimise] or a [growing_grid] spec's problems",
            spec.path
        ),
    };
    let built = optimise::problems(&spec, o, &ctx)?;
    let mut problems = Vec::with_capacity(built.len());
    for (ProblemKey { data: dataset, cn: net, param }, problem) in built {
        let wide =
            ControlNetProblem::new(problem.parts().clone(), BoxSpec::Cover { fraction: 0.0 })
                .with_context(|| format!("{dataset} {net} {}: the data-range box", param.name()))?;
        problems.push(SuiteProblem {
            name: optimise::ioh::problem_name(
                &dataset,
                &o.grid.to_string(),
                &net.to_string(),
                param.name(),
            ),
            dataset,
            grid: o.grid,
            net,
            param,
            fitness: Fitness::ControlNet { problem: Box::new(problem), wide: Box::new(wide) },
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

/// Seed 001's problems: the Growing Grid maps and the open surfaces of its run
/// (`growing_grid::grow_maps`, the maps `somnurbs run` logs, without a cell log, then
/// `growing_grid::problems`, as the run calls it).
fn open_surfaces(
    spec: &Spec,
    g: &GrowingGridSpec,
    ctx: &RunContext,
    profile: Option<&str>,
) -> Result<Suite> {
    let maps = growing_grid::grow_maps(spec, g, ctx)?;
    let mut problems = Vec::new();
    for (ProblemKey { data: dataset, cn: net, param }, p) in growing_grid::problems(g, &maps)? {
        let grid = GridSize { nx: p.nx, ny: p.ny };
        problems.push(SuiteProblem {
            name: optimise::ioh::problem_name(
                &dataset,
                &grid.to_string(),
                &net.to_string(),
                param.name(),
            ),
            dataset,
            grid,
            net,
            param,
            fitness: Fitness::OpenSurface(Box::new(p)),
        });
    }
    Ok(Suite {
        spec_name: spec.file.name.clone(),
        profile: profile.map(String::from),
        // `OpenSurfaceProblem` builds its knots by The NURBS Book's rule.
        reading: KnotRule::NurbsBook.name().to_string(),
        box_label: format!("cover+{:e}", g.bounds_margin),
        exact: ExactOptions::default(),
        problems,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quick ch6_exact suite: the run's problems under their IOHprofiler names, B's box and
    /// the data-range box around the same start, the spec's metadata; another reading moves B.
    #[test]
    fn ch6_exact_quick_suite() {
        let work = tempfile::tempdir().unwrap();
        let data = crate::data::registry::clone_data_dir();
        let s = load("ch6_exact", Some("quick"), &[], Some(&data), work.path()).unwrap();
        assert_eq!((s.spec_name.as_str(), s.reading.as_str()), ("ch6_exact", "eq2_10"));
        assert_eq!((s.box_label.as_str(), s.exact.tol_rel_gap), ("B+-5e-6", 1e-9));
        let names: Vec<&str> = s.problems.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "sphere_20x20_6x6_chord_length",
                "sphere_20x20_12x12_chord_length",
                "spindle_20x20_6x6_chord_length",
                "spindle_20x20_12x12_chord_length"
            ]
        );
        for p in &s.problems {
            let q = p.problem();
            let x0 = q.initial_point();
            let (lo, hi) = q.bounds();
            assert!(x0.iter().zip(lo).all(|(x, l)| *l == x - 5e-6));
            assert!(x0.iter().zip(hi).all(|(x, h)| *h == x + 5e-6));
            let (dlo, dhi) = p.data_box();
            assert!((0..x0.len()).all(|k| dlo[k] <= x0[k] && x0[k] <= dhi[k]));
            assert!(p.exact(false, &s.exact).unwrap().lower_bound <= q.fitness(x0));
        }
        let nb = load(
            "ch6_exact",
            Some("quick"),
            &["optimise.knots=nurbs_book".into()],
            Some(&data),
            work.path(),
        )
        .unwrap();
        assert_eq!(nb.reading, "nurbs_book");
        let b =
            |s: &Suite| s.problems[0].problem().fitness(s.problems[0].problem().initial_point());
        assert_ne!(b(&nb), b(&s));
    }
}
