//! Bounds checked on every spec before anything else in validation (so `--dry-run` too): each
//! size, count and radius has a documented finite range (docs/specs.md, "Spec limits"), lists
//! hold no entry twice, and the experiment's name and data-set names can only name files inside
//! the output folder. The checks only read numbers and list lengths: nothing is allocated from a
//! spec value before it has passed, so a bad value is a one-line error naming its key at once.

use super::family::Families;
use super::spec::{GridSize, Loaded, Spec, SpecError};
use std::collections::HashSet;
use std::fmt::Display;

/// Largest side of any SOM grid or control net.
pub(crate) const MAX_GRID_SIDE: usize = 256;
/// SOM iterations T (Chapter 4 and the map recomputation of Chapters 5 and 6).
pub(crate) const MAX_ITERATIONS: u64 = 10_000_000;
/// Largest initial SOM radius sigma0 (the neighbourhood is tabulated per iteration).
pub(crate) const MAX_SIGMA0: f64 = 256.0;
/// Repeats (runs) per cell.
pub(crate) const MAX_REPEATS: u64 = 10_000;
/// Generations (iterations) of one optimiser run.
pub(crate) const MAX_GENERATIONS: u64 = 1_000_000;
/// Individuals (nests, particles) of one optimiser run.
pub(crate) const MAX_POPULATION: u64 = 10_000;
/// Cells of one spec (all its `--sweep` variants together).
pub(crate) const MAX_CELLS: u64 = 100_000;
/// Variants of one run: the product of the `--sweep` value counts.
pub(crate) const MAX_VARIANTS: u64 = 1_000;
/// Cells of one `reproduce` plan: its specs and its reading sets' runs together.
pub(crate) const MAX_PLAN_CELLS: u64 = 1_000_000;
/// Entries of one list.
pub(crate) const MAX_LIST: usize = 1_000;
/// Initial range, search range and box margin, in units of the (normalised) data's extent.
pub(crate) const MAX_RANGE: f64 = 10.0;
/// Trace checkpoint spacing in evaluations.
pub(crate) const MAX_TRACE_EVERY: u64 = 1_000_000_000_000;
/// Newton steps of the exact solver.
pub(crate) const MAX_NEWTON_STEPS: u64 = 100_000;
/// Lengths in data units (a generated shape's radius or height, a step, an accuracy, a search range).
pub(crate) const MAX_LENGTH: f64 = 1e6;
/// Points or samples per side of a generated data set.
pub(crate) const MAX_SAMPLES: u64 = 100_000;

/// Worker threads per available CPU at most (`--jobs`).
pub(crate) const MAX_JOBS_PER_CPU: usize = 4;

/// The worker threads of `--jobs` (`flag`; default: `cpus`): at least 1 (0 is an error), at most
/// [`MAX_JOBS_PER_CPU`] x `cpus` (a larger flag is cut down, with the note to print).
pub(crate) fn jobs(flag: Option<usize>, cpus: usize) -> anyhow::Result<(usize, Option<String>)> {
    let cpus = cpus.max(1);
    let cap = MAX_JOBS_PER_CPU.saturating_mul(cpus);
    match flag {
        None => Ok((cpus, None)),
        Some(0) => anyhow::bail!("--jobs must be at least 1"),
        Some(n) if n > cap => Ok((
            cap,
            Some(format!(
                "--jobs {n} is above {MAX_JOBS_PER_CPU} x the {cpus} available CPU(s); using {cap}"
            )),
        )),
        Some(n) => Ok((n, None)),
    }
}

/// The bound checks a family applies to its section, each error naming the spec and key.
pub struct Check<'a> {
    pub spec: &'a Spec,
    /// The cell count the section's [`Check::cells`] computed (read by [`cell_count`]).
    counted: std::cell::Cell<u64>,
}

impl Check<'_> {
    pub fn err(&self, key: &str, msg: impl Display) -> SpecError {
        SpecError::new(format!("{}: {key}: {msg}", self.spec.path))
    }

    pub fn int(&self, key: &str, v: impl TryInto<u64>, hi: u64) -> Result<(), SpecError> {
        match v.try_into() {
            Ok(v) if v <= hi => Ok(()),
            Ok(v) => Err(self.err(key, format!("{v} is above the limit {hi}"))),
            Err(_) => Err(self.err(key, format!("is above the limit {hi}"))),
        }
    }

    /// A finite number in [lo, hi] (lo itself allowed or not).
    pub fn real(
        &self,
        key: &str,
        v: f64,
        lo: f64,
        lo_allowed: bool,
        hi: f64,
    ) -> Result<(), SpecError> {
        let above_lo = if lo_allowed { v >= lo } else { v > lo };
        if v.is_finite() && above_lo && v <= hi {
            return Ok(());
        }
        Err(self.err(
            key,
            format!(
                "must be a finite number in {}{lo}, {hi}], got {v}",
                if lo_allowed { "[" } else { "(" }
            ),
        ))
    }

    pub fn grids<'g>(
        &self,
        key: &str,
        grids: impl IntoIterator<Item = &'g GridSize>,
    ) -> Result<(), SpecError> {
        for g in grids {
            if g.nx > MAX_GRID_SIDE || g.ny > MAX_GRID_SIDE {
                return Err(
                    self.err(key, format!("{g} has a side above the limit {MAX_GRID_SIDE}"))
                );
            }
        }
        Ok(())
    }

    /// No entry twice, and not too many entries.
    pub fn list<T: Display + Eq + std::hash::Hash>(
        &self,
        key: &str,
        list: &[T],
    ) -> Result<(), SpecError> {
        if list.len() > MAX_LIST {
            return Err(
                self.err(key, format!("{} entries, above the limit {MAX_LIST}", list.len()))
            );
        }
        let mut seen = HashSet::new();
        match list.iter().find(|v| !seen.insert(*v)) {
            Some(v) => Err(self.err(key, format!("`{v}` is listed twice"))),
            None => Ok(()),
        }
    }

    /// Data-set entries: each a built-in or a point file whose name (stem) is usable, no name twice.
    pub fn datasets(&self, key: &str, list: &[String]) -> Result<(), SpecError> {
        self.list(key, list)?;
        let mut seen: Vec<(String, &String)> = Vec::new();
        for d in list {
            let name = crate::data::registry::dataset_name(d).map_err(|e| self.err(key, e))?;
            if let Some((_, other)) = seen.iter().find(|(n, _)| *n == name) {
                return Err(self.err(key, format!("`{other}` and `{d}` both go by the name `{name}` (a file's name is its stem)")));
            }
            seen.push((name, d));
        }
        Ok(())
    }

    pub fn cells(&self, key: &str, factors: &[usize]) -> Result<(), SpecError> {
        let n = factors.iter().fold(1u64, |a, &f| a.saturating_mul(f as u64));
        self.counted.set(self.counted.get().saturating_add(n));
        if n > MAX_CELLS {
            return Err(
                self.err(key, format!("the spec has {n} cells, above the limit {MAX_CELLS}"))
            );
        }
        Ok(())
    }

    pub fn optimiser_run(
        &self,
        section: &str,
        repeats: usize,
        generations: usize,
        population: usize,
    ) -> Result<(), SpecError> {
        self.int(&format!("{section}.repeats"), repeats, MAX_REPEATS)?;
        self.int(&format!("{section}.generations"), generations, MAX_GENERATIONS)?;
        self.int(&format!("{section}.population"), population, MAX_POPULATION)
    }
}

/// The data-set entries of a spec's section (as written: names or paths).
pub(crate) fn dataset_entries<F: Families>(spec: &Loaded<F>) -> Vec<&String> {
    spec.family().datasets(&spec.section)
}

/// The penalised least squares weight (`fairness`): at most 10^6.
pub(crate) const MAX_FAIRNESS: f64 = 1e6;

/// A usable experiment or file name: not empty, no path separator or NUL, not `.` or `..`.
pub(crate) fn check_name(name: &str) -> Result<(), String> {
    if name.trim().is_empty() || name.contains(['/', '\\', '\0']) || name == "." || name == ".." {
        return Err(format!("`{name}` must be a non-empty name without slashes, not `.` or `..`"));
    }
    Ok(())
}

/// Every bound of a spec and its section (see the module doc), before any other check.
pub(crate) fn check<F: Families>(spec: &Spec, section: &F) -> Result<(), SpecError> {
    let c = Check { spec, counted: Default::default() };
    check_name(&spec.file.name).map_err(|e| c.err("name", e))?;
    section.family().check_limits(&c, section)
}

/// The cells of a spec as its limit counts them (the product of its section's sizes), without
/// making them; 0 when a limit fails (a spec that passed validation has passed them).
pub(crate) fn cell_count<F: Families>(spec: &Loaded<F>) -> u64 {
    let c = Check { spec: &spec.spec, counted: Default::default() };
    match spec.family().check_limits(&c, &spec.section) {
        Ok(()) => c.counted.get(),
        Err(_) => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::spec::CliOverrides;

    const SPEC: &str = "name = \"t\"\nmaster_seed = 1\n[optimise]\ndatasets = [\"sphere\"]\ngrid = \"20x20\"\ncontrol_nets = [\"6x6\"]\nparameterisations = [\"uniform\"]\noptimisers = [\"ga\", \"de\"]\nrepeats = 2\ngenerations = 10\npopulation = 8\n";

    fn refused(from: &str, to: &str, key: &str) {
        let t = std::time::Instant::now();
        let text = SPEC.replace(from, to);
        assert_ne!(text, SPEC, "{from} not in the spec");
        let e = crate::families::Loaded::parse("t.toml", &text, None).unwrap_err().to_string();
        assert!(e.contains(key) && !e.contains('\n'), "{to}: {e}");
        assert!(t.elapsed().as_secs_f64() < 1.0, "{to}: slow refusal");
    }

    #[test]
    fn every_size_has_a_bound_named_by_its_key() {
        crate::families::Loaded::parse("t.toml", SPEC, None).unwrap();
        refused("grid = \"20x20\"", "grid = \"100000x100000\"", "optimise.grid");
        refused(
            "control_nets = [\"6x6\"]",
            "control_nets = [\"6x6\", \"6x100000\"]",
            "optimise.control_nets",
        );
        refused("generations = 10", "generations = 1000000000000", "optimise.generations");
        refused("population = 8", "population = 1000000000000", "optimise.population");
        refused("repeats = 2", "repeats = 100000000", "optimise.repeats");
        refused("population = 8", "population = 8\nsearch_range = 1e308", "optimise.search_range");
        refused("population = 8", "population = 8\nsearch_range = inf", "optimise.search_range");
        refused("population = 8", "population = 8\ninit_range = nan", "optimise.init_range");
        refused(
            "optimisers = [\"ga\", \"de\"]",
            "optimisers = [\"ga\", \"de\", \"ga\"]",
            "optimise.optimisers: `ga` is listed twice",
        );
        refused(
            "control_nets = [\"6x6\"]",
            "control_nets = [\"6x6\", \"6x6\"]",
            "optimise.control_nets: `6x6` is listed twice",
        );
        refused(
            "datasets = [\"sphere\"]",
            "datasets = [\"a/x.xyz\", \"b/x.xyz\"]",
            "both go by the name `x`",
        );
        refused("datasets = [\"sphere\"]", "datasets = [\"..\"]", "optimise.datasets");
        refused("name = \"t\"", "name = \"..\"", "name");
        refused("name = \"t\"", "name = \".\"", "name");
        let som = "name = \"s\"\nmaster_seed = 1\n[som]\ndatasets = [\"cube\"]\niterations = 10\n[[som.group]]\nmodels = [\"som2d\"]\ngrids = [\"10x10\"]\n";
        for (to, key) in [
            ("grids = [\"100000x100000\"]", "som.group[0].grids"),
            ("grids = [\"10x10\"]\n[som.x]", "unknown field"),
            ("grids = [\"10x10\", \"10x10\"]", "`10x10` is listed twice"),
        ] {
            let e = crate::families::Loaded::parse(
                "s.toml",
                &som.replace("grids = [\"10x10\"]", to),
                None,
            )
            .unwrap_err()
            .to_string();
            assert!(e.contains(key), "{e}");
        }
        for (to, key) in [
            ("iterations = 100000000000", "som.iterations"),
            ("iterations = 10\nsigma0 = 1e5", "som.sigma0"),
            ("iterations = 10\nsigma0 = inf", "som.sigma0"),
            ("iterations = 10\nrepeats = 1000000000", "som.repeats"),
        ] {
            let e =
                crate::families::Loaded::parse("s.toml", &som.replace("iterations = 10", to), None)
                    .unwrap_err()
                    .to_string();
            assert!(e.contains(key), "{e}");
        }
    }

    #[test]
    fn jobs_are_at_least_one_and_at_most_four_per_cpu() {
        assert_eq!(jobs(None, 2).unwrap(), (2, None));
        assert_eq!(jobs(Some(3), 2).unwrap(), (3, None));
        assert_eq!(jobs(Some(8), 2).unwrap(), (8, None));
        let (n, note) = jobs(Some(9), 2).unwrap();
        assert_eq!(n, 8);
        assert!(note.unwrap().contains("--jobs 9 is above 4 x the 2 available CPU(s); using 8"));
        assert_eq!(jobs(Some(usize::MAX), 1).unwrap().0, 4);
        assert!(jobs(Some(0), 2).unwrap_err().to_string().contains("at least 1"));
    }

    #[test]
    fn sweeps_are_bounded_before_they_expand() {
        let text = SPEC.replace("optimisers = [\"ga\", \"de\"]", "optimisers = [\"de\"]");
        let sweep = |args: &[&str]| {
            let cli =
                CliOverrides { set: vec![], sweep: args.iter().map(|s| s.to_string()).collect() };
            cli.variants::<crate::families::Section>("t.toml", &text, None).map(|v| v.len())
        };
        let values = |n: usize| {
            (0..n).map(|k| format!("{}", 0.1 + k as f64 * 1e-4)).collect::<Vec<_>>().join(",")
        };
        assert_eq!(sweep(&["optimise.de.f=0.3,0.5"]), Ok(2));
        let t = std::time::Instant::now();
        let big =
            [format!("optimise.de.f={}", values(1000)), format!("optimise.de.cr={}", values(1000))];
        let e = sweep(&[&big[0], &big[1]]).unwrap_err().to_string();
        assert!(e.contains("1000 x 1000 = 1000000 variants, above the limit 1000"), "{e}");
        assert!(t.elapsed().as_secs_f64() < 1.0);
        // 500 variants of 200 cells (one optimiser x 200 repeats): 10^5 in all, the limit; one
        // more repeat is over.
        let ok = format!("optimise.de.f={}", values(500));
        assert_eq!(sweep(&[&ok, "optimise.repeats=200"]), Ok(500));
        let e = sweep(&[&ok, "optimise.repeats=201"]).unwrap_err().to_string();
        assert!(e.contains("cells in all, above the limit 100000"), "{e}");
        for (dup, said) in [
            ("0.3,0.30", "0.3 and 0.30 are one value"),
            ("1,1.0", "1 and 1.0 are one value"),
            ("0.5,5e-1", "0.5 and 5e-1 are one value"),
            ("0.3,0.3", "the value 0.3 is given twice"),
        ] {
            let e = sweep(&[&format!("optimise.de.f={dup}")]).unwrap_err().to_string();
            assert!(e.contains(said), "{dup}: {e}");
        }
    }

    #[test]
    fn population_minimum_is_that_of_the_optimisers_run() {
        let spec = |opts: &str, pop: usize, extra: &str| {
            let t = SPEC
                .replace("optimisers = [\"ga\", \"de\"]", &format!("optimisers = [{opts}]"))
                .replace("population = 8", &format!("population = {pop}\n{extra}"));
            crate::families::Loaded::parse("t.toml", &t, None)
                .map(|_| ())
                .map_err(|e| e.to_string())
        };
        spec("\"ga\"", 4, "").unwrap();
        spec("\"ga\", \"pso\", \"csa\"", 3, "[optimise.ga]\ntournament = 3").unwrap();
        spec("\"pso\"", 1, "").unwrap();
        let e = spec("\"ga\"", 3, "").unwrap_err();
        assert!(
            e.contains("t.toml: optimise.ga.tournament: 4 is above optimise.population = 3"),
            "{e}"
        );
        assert!(!e.contains("DE"), "{e}");
        let e = spec("\"ga\"", 8, "[optimise.ga]\ntournament = 20").unwrap_err();
        assert!(e.contains("optimise.ga.tournament: 20 is above optimise.population = 8"), "{e}");
        let e = spec("\"ga\", \"de\"", 3, "[optimise.ga]\ntournament = 2").unwrap_err();
        assert!(e.contains("optimise.population: must be at least 4 for de"), "{e}");
        let e = spec("\"icsa\"", 1, "").unwrap_err();
        assert!(e.contains("optimise.population: must be at least 2 for icsa"), "{e}");
        let e = spec("\"pso\"", 0, "").unwrap_err();
        assert!(e.contains("optimise.population: must be at least 1 for pso"), "{e}");
    }

    #[test]
    fn many_repeats_expand_in_linear_time() {
        let som = "name = \"s\"\nmaster_seed = 1\n[som]\ndatasets = [\"cube\"]\niterations = 10\nrepeats = 10000\n[[som.group]]\nmodels = [\"som2d\", \"dnsom\"]\ngrids = [\"10x10\", \"12x12\"]\n[[som.group]]\nmodels = [\"som2d\"]\ngrids = [\"10x10\"]\n";
        let t = std::time::Instant::now();
        let spec = crate::families::Loaded::parse("s.toml", som, None).unwrap();
        assert_eq!(crate::families::som::spec::cells(spec.section_as().unwrap()).len(), 40_000);
        assert!(t.elapsed().as_secs_f64() < 2.0, "{:?}", t.elapsed());
    }

    #[test]
    fn file_names_become_stems_in_keys() {
        let text = SPEC.replace("datasets = [\"sphere\"]", "datasets = [\"/some/where/part.xyz\"]");
        let spec = crate::families::Loaded::parse("t.toml", &text, None).unwrap();
        let cells =
            || crate::families::optimise::spec::cells(&spec.spec, spec.section_as().unwrap());
        assert!(
            cells().iter().all(|c| c.key().starts_with("optim/part/")),
            "{:?}",
            cells()[0].key()
        );
    }
}
