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
    /// The IOHprofiler function id, as `ioh/` of a run numbers it: the problem's place in the
    /// spec's order (1-based).
    pub function_id: u32,
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

/// The shipped specs with control-net problems and their text, carried inside the program (and
/// the Python wheel), so that a shipped name needs no clone: Chapter 6's, and seed 001's open
/// surfaces (one view, no exact solver).
pub const SHIPPED: [(&str, &str); 5] = [
    ("ch6_same", include_str!("../../experiments/ch6_same.toml")),
    ("ch6_diff", include_str!("../../experiments/ch6_diff.toml")),
    ("ch6_exact", include_str!("../../experiments/ch6_exact.toml")),
    ("ch6_beyond", include_str!("../../experiments/ch6_beyond.toml")),
    ("seed001_growing_grid", include_str!("../../experiments/seed001_growing_grid.toml")),
];

/// A request `load` refuses before building anything: what was asked and what is offered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RequestError {
    #[error("no shipped spec {name:?} (offered: {}; or give a .toml file's path)", offered.join(", "))]
    Spec { name: String, offered: Vec<String> },
    #[error("{path}: no such spec file")]
    SpecFile { path: String },
    #[error("{spec}: no profile {name:?} (offered: {})", if offered.is_empty() { "none".to_string() } else { offered.join(", ") })]
    Profile { spec: String, name: String, offered: Vec<String> },
}

/// A spec by file path, or by the name of a shipped one (`ch6_same`): `experiments/<name>.toml`
/// in the working folder when there is one (a clone's, which a user may have edited), else the
/// shipped text, written into `work`.
pub fn spec_path(spec: &str, work: &Path) -> Result<PathBuf> {
    let p = Path::new(spec);
    if p.extension().is_some_and(|e| e == "toml") || p.components().count() > 1 {
        if !p.is_file() {
            return Err(RequestError::SpecFile { path: p.display().to_string() }.into());
        }
        return Ok(p.to_path_buf());
    }
    let Some((_, text)) = SHIPPED.iter().find(|(n, _)| *n == spec) else {
        let offered = SHIPPED.iter().map(|(n, _)| n.to_string()).collect();
        return Err(RequestError::Spec { name: spec.to_string(), offered }.into());
    };
    let here = Path::new("experiments").join(format!("{spec}.toml"));
    if here.is_file() {
        return Ok(here);
    }
    let dir = work.join("experiments");
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join(format!("{spec}.toml"));
    crate::io::write_atomic(&path, text.as_bytes())?;
    Ok(path)
}

/// A profile the spec does not define, as the suite's own [`RequestError::Profile`] naming the spec
/// as the caller did; any other error as it is.
fn profile_error(e: crate::experiment::spec::SpecError, shown: &str) -> anyhow::Error {
    match e.unknown_profile.clone() {
        Some((name, offered)) => RequestError::Profile { spec: shown.into(), name, offered }.into(),
        None => e.into(),
    }
}

/// Load every control-net problem of a Chapter 6 spec (`[optimise]`) or of seed 001's
/// (`[growing_grid]`) under `profile` and the `KEY=VALUE` settings of `set` (as
/// `somnurbs run --set`, e.g. `optimise.knots=nurbs_book`). Data files come from `data_dir` (else as
/// the CLI finds them); a map the spec names but that is missing is recomputed as the run would,
/// written into `work` (a folder the caller owns), where a shipped spec's text also goes
/// ([`spec_path`]). An unknown spec or profile is a [`RequestError`].
pub fn load(
    spec: &str,
    profile: Option<&str>,
    set: &[String],
    data_dir: Option<&Path>,
    work: &Path,
) -> Result<Suite> {
    let path = spec_path(spec, work)?;
    let cli = CliOverrides { set: set.to_vec(), sweep: Vec::new() };
    let mut variants =
        Loaded::load_variants(&path, profile, &cli).map_err(|e| profile_error(e, spec))?;
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
    let mut built = optimise::problems(&spec, o, &ctx)?;
    let mut problems = Vec::with_capacity(built.len());
    // The spec's order (data sets, then nets, then parameterisations): the order of its cells,
    // in which `ioh/` of a run numbers its functions, so `function_id` is the run's.
    for entry in &o.datasets {
        let dataset = crate::data::registry::name_of(entry);
        for &net in &o.control_nets {
            for &param in &o.parameterisations {
                let key = ProblemKey::new(&dataset, net, param);
                let problem = built.remove(&key).context("a problem of the spec was not built")?;
                let wide = ControlNetProblem::new(
                    problem.parts().clone(),
                    BoxSpec::Cover { fraction: 0.0 },
                )
                .with_context(|| format!("{dataset} {net} {}: the data-range box", param.name()))?;
                problems.push(SuiteProblem {
                    name: optimise::ioh::problem_name(
                        &dataset,
                        &o.grid.to_string(),
                        &net.to_string(),
                        param.name(),
                    ),
                    function_id: problems.len() as u32 + 1,
                    dataset: dataset.clone(),
                    grid: o.grid,
                    net,
                    param,
                    fitness: Fitness::ControlNet {
                        problem: Box::new(problem),
                        wide: Box::new(wide),
                    },
                });
            }
        }
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
            function_id: problems.len() as u32 + 1,
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

    /// Every spec of experiments/ with control-net problems is shipped, with the file's text.
    #[test]
    fn every_suite_spec_is_shipped_with_its_text() {
        let dir = Path::new(crate::data::registry::CLONE_DIR).join("experiments");
        let mut suites = Vec::new();
        for e in std::fs::read_dir(&dir).unwrap().flatten() {
            let text = std::fs::read_to_string(e.path()).unwrap_or_default();
            if text.contains("\n[optimise]") || text.contains("\n[growing_grid]") {
                let name = e.path().file_stem().unwrap().to_string_lossy().into_owned();
                suites.push((name, text));
            }
        }
        suites.sort();
        let mut shipped: Vec<(String, String)> =
            SHIPPED.iter().map(|(n, t)| (n.to_string(), t.to_string())).collect();
        shipped.sort();
        assert_eq!(suites, shipped);
    }

    /// An unknown spec, spec file or profile is refused with what is offered, before any work.
    #[test]
    fn unknown_requests_name_what_is_offered() {
        let work = tempfile::tempdir().unwrap();
        let err = |spec: &str, profile: Option<&str>| {
            let e = load(spec, profile, &[], None, work.path()).err().unwrap();
            e.downcast::<RequestError>().unwrap()
        };
        assert!(
            matches!(err("nope", None), RequestError::Spec { ref offered, .. } if offered.len() == 5)
        );
        assert!(matches!(err("nope/x.toml", None), RequestError::SpecFile { .. }));
        let RequestError::Profile { offered, .. } = err("ch6_exact", Some("fast")) else {
            panic!()
        };
        assert_eq!(offered, ["quick"]);
        assert!(err("ch6_exact", Some("fast")).to_string().contains("offered: quick"));
    }

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
