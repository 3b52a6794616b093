//! Chapter 6 speed (run: `cargo bench --bench optim`): the control-net fitness for an 18x18 net on
//! the 20x20 DNSOM map of the spindle (target: at most 1.5 us per evaluation on one core; the
//! thesis' DE about 600 us), one full DE run (2000 generations x 40) on it (target under 0.2 s;
//! the thesis 48 s), and GA, PSO and cuckoo-search runs. The Python peers (numpy, scipy) are
//! measured on the same problem in the same run by `scripts/bench_peers.sh`.

use somnurbs::experiment::{self, GridSize};
use somnurbs::families;
use somnurbs::families::som::SomCell;
use somnurbs::geom::Point3;
use somnurbs::optim::{default_optimiser, Budget, ExactOptions, Problem};
use somnurbs::simd::Isa;
use somnurbs::som::{Model, SomParams};
use somnurbs::spline::{fit_two_view, Approach, Parameterisation};
use somnurbs::spline::{BoxSpec, ControlNetProblem};
use std::time::Instant;

#[path = "optim/floor.rs"]
mod floor;

fn main() {
    let spindle =
        somnurbs::data::load_dataset("spindle", &somnurbs::experiment::data_dir(None)).unwrap();
    let cell = SomCell {
        dataset: "spindle".into(),
        model: Model::Dnsom,
        grid: GridSize { nx: 20, ny: 20 },
        repeat: 0,
    };
    let run = families::som::run_cell(&cell, &spindle.points, &SomParams::default(), 2023).unwrap();
    let grid =
        somnurbs::double_net::TwoViewGrid::from_weights(20, 20, &run.weights).expect("a DNSOM map");
    let fit = fit_two_view(
        &grid,
        18,
        18,
        Parameterisation::ChordLength,
        Approach::Improved,
        &Default::default(),
    )
    .unwrap();
    let problem = ControlNetProblem::new(
        fit.control_net_parts(&grid).unwrap(),
        BoxSpec::Cover { fraction: 0.0 },
    )
    .unwrap();
    let x0 = problem.initial_point().to_vec();
    if let Ok(what) = std::env::var("BENCH_COUNT") {
        count(&what, &problem);
        return;
    }
    if let Ok(path) = std::env::var("BENCH_EXPORT") {
        export(&problem, std::path::Path::new(&path));
        return;
    }
    println!(
        "control-net problem 18x18 on 20x20: {} variables, B = {:.6}",
        problem.dim(),
        problem.fitness(&x0)
    );
    let reps: usize =
        std::env::var("BENCH_REPS").ok().and_then(|v| v.parse().ok()).unwrap_or(200_000);
    // The machine may be shared: time BENCH_ROUNDS rounds of `reps` evaluations and keep the
    // fastest (the least disturbed), net of the cost of preparing x.
    let rounds: usize =
        std::env::var("BENCH_ROUNDS").ok().and_then(|v| v.parse().ok()).unwrap_or(5);
    let mut xs = x0.clone();
    let mut round = |with_fitness: bool| {
        let t = experiment::thread_cpu_seconds();
        let mut acc = 0.0;
        for k in 0..reps {
            let j = k % x0.len();
            xs[j] += 1e-9;
            if with_fitness {
                acc += problem.fitness(std::hint::black_box(&xs));
            }
            xs[j] = x0[j];
            std::hint::black_box(&xs);
        }
        std::hint::black_box(acc);
        experiment::thread_cpu_seconds() - t
    };
    let per =
        (0..rounds).map(|_| round(true) - round(false)).fold(f64::INFINITY, f64::min) / reps as f64;
    println!("fitness: {:.3} us per evaluation ({:.2} M evaluations/s; target 1.5 us; thesis DE ~600 us: {:.0}x)", per * 1e6, 1e-6 / per, 600e-6 / per);
    let (model, nominal) = cpu_model();
    // Cycles are counted at the clock the core runs at, measured with a loop of independent FMAs
    // (two per cycle on every AVX2 core): /proc/cpuinfo gives the nominal clock, which a core
    // that boosts exceeds (this Zen 3 ran its FMAs at 3.2 GHz with 2445 MHz nominal).
    let peak = fma_peak();
    let mhz = peak.map_or(nominal, |p| p.mhz);
    println!("CPU: {model}, {nominal:.0} MHz nominal (/proc/cpuinfo); load {}", load());
    if let Some(p) = peak {
        println!(
            "clock measured by an FMA loop: {:.0} MHz (0.5 / ns per 4-wide FMA); a 4-wide square root costs {:.2} ns = {:.1} cycles",
            p.mhz,
            p.sqrt_ns,
            p.sqrt_ns * p.mhz / 1e3
        );
    }
    // Every compiled copy of the fitness on this problem, in cycles (ns x the nominal clock)
    // beside the floating-point lower bound (multiply(-add)s on two 4-wide FMA pipes).
    let bound = fma_lower_bound_cycles(20, 20, 18);
    // One second-pass column (and one 4-wide square root) per chunk of 4 grid rows and grid
    // column, both views.
    let (blocks, columns) = kernel_blocks(20, 20, 18);
    if let Some(p) = peak {
        // The square roots run on their own unit beside the FMAs: a second floor, not added to
        // the first.
        println!(
            "square-root floor: {columns} x {:.1} cycles = {:.0} cycles (beside the FMA bound, not on top of it)",
            p.sqrt_ns * mhz / 1e3,
            columns as f64 * p.sqrt_ns * mhz / 1e3
        );
    }
    if let Some(b) = floor::measure(mhz) {
        let sum = blocks as f64 * b.pass1_block + columns as f64 * b.pass2_column;
        println!(
            "AVX2 building blocks alone (data in L1, nothing around them): first-pass block {:.1} cycles (its 16 FMAs: 8), second-pass column {:.1} cycles (its 15 FMAs: 7.5; its root: {:.1}); {blocks} blocks + {columns} columns = {sum:.0} cycles = {:.2}x the FMA bound",
            b.pass1_block,
            b.pass2_column,
            peak.map_or(f64::NAN, |p| p.sqrt_ns * mhz / 1e3),
            sum / bound
        );
    }
    // The fitness has a baseline and an AVX2 copy (under `Avx512Vl` it runs the AVX2 one).
    for isa in [Isa::Baseline, Isa::Avx2] {
        let q = problem.clone().with_isa(isa);
        if q.isa() != isa {
            println!("fitness, {isa:?} copy: not run (this CPU lacks it)");
            continue;
        }
        let ns = best_fitness_ns(&q, &x0, rounds);
        let cycles = ns * mhz / 1e3;
        println!("fitness, {isa:?} copy: {ns:.0} ns = {cycles:.0} cycles per evaluation (at {mhz:.0} MHz); FMA lower bound {bound:.0} cycles (2 pipes x 4 lanes): {:.2}x the bound; {:.2}x at the nominal clock", cycles / bound, ns * nominal / 1e3 / bound);
    }
    // The optimisers' own kernels, every compiled copy (all in L1: the floor of their overhead).
    #[cfg(target_arch = "x86_64")]
    for line in somnurbs::simd::moves_timing::report()
        .into_iter()
        .chain(somnurbs::simd::levy_timing::report())
    {
        println!("{line}");
    }
    if std::env::var("BENCH_SCALING").is_ok_and(|v| v != "0") {
        scaling(&spindle.points, mhz);
    }
    let generations: usize =
        std::env::var("BENCH_GENERATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(2000);
    // BENCH_ONLY=de,pso runs only those optimisers and skips the exact optimum (for profiling).
    let only: Option<Vec<String>> =
        std::env::var("BENCH_ONLY").ok().map(|v| v.split(',').map(str::to_string).collect());
    let exact_boxes = [
        ("optimisers' box (data and B)", BoxSpec::Cover { fraction: 0.0 }),
        ("data range", BoxSpec::DataRange),
    ];
    for (label, bounds) in exact_boxes.into_iter().filter(|_| only.is_none()) {
        let pb = ControlNetProblem::new(problem.parts().clone(), bounds).unwrap();
        let t = Instant::now();
        let ex = pb.exact_optimum(&ExactOptions::default()).unwrap();
        println!(
            "exact optimum in the {label}: f {:.9}, certified lower bound {:.9}, gap {:.2e} ({:.1e} relative), {} Newton steps, {:.2} s; B is {:.3e} above it",
            ex.f,
            ex.lower_bound,
            ex.gap,
            ex.gap / ex.f,
            ex.iterations,
            t.elapsed().as_secs_f64(),
            problem.fitness(&x0) - ex.f
        );
    }
    // BENCH_INIT_RANGE sets the initial population's spread around x0 (the thesis' 5e-6 by default).
    let init_range: f64 =
        std::env::var("BENCH_INIT_RANGE").ok().and_then(|v| v.parse().ok()).unwrap_or(5e-6);
    // BENCH_POPULATION sets the population (40 by default, Table 6.1): with fewer individuals
    // the population's vectors stay in the L2 cache, which shows what memory traffic costs.
    let population: usize =
        std::env::var("BENCH_POPULATION").ok().and_then(|v| v.parse().ok()).unwrap_or(40);
    let budget =
        Budget { generations: generations as u64, population, init_range, trace_every_evals: 400 };
    // Per run: CPU seconds of this thread (the machine may be shared), per evaluation, and what
    // the optimiser itself costs per evaluation on top of the fitness (its per-coordinate work).
    for name in ["de", "ga", "pso", "csa", "icsa"]
        .into_iter()
        .filter(|n| only.as_ref().is_none_or(|o| o.iter().any(|x| x == n)))
    {
        let opt = default_optimiser(name).unwrap();
        let mut rng = somnurbs::experiment::cell_rng(1, "bench");
        let t = experiment::thread_cpu_seconds();
        let r = opt.run(&problem, &budget, &mut rng).unwrap();
        let s = experiment::thread_cpu_seconds() - t;
        let per_eval = s / r.evaluations as f64;
        let target = if name == "de" {
            format!(" (target 0.2 s; thesis 48 s: {:.0}x)", 48.0 / s)
        } else {
            String::new()
        };
        println!(
            "{name} {generations} x {population}: {s:.3} s CPU, {} evaluations ({:.2} M/s), {:.3} us per evaluation = fitness + {:.3} us ({:.2}x the fitness alone), best {:.6}{target}",
            r.evaluations,
            1e-6 / per_eval,
            per_eval * 1e6,
            (per_eval - per) * 1e6,
            per_eval / per,
            r.best_fitness
        );
    }
}

/// `BENCH_EXPORT=file.json`: the bench's problem for the Python peers
/// (`scripts/bench_peers.sh`): both views' sparse bases, data and control-point classes, x0, the
/// box, the optimisers' default parameters, and our fitness at x0 and at a fixed perturbed point
/// (the peers check their own fitness against both before timing it).
fn export(problem: &ControlNetProblem, path: &std::path::Path) {
    use somnurbs::double_net::View;
    let p = problem.parts();
    let x0 = problem.initial_point();
    // A point away from B, the same in every language: x0[k] + 1e-3 sin(k).
    let probe: Vec<f64> = x0.iter().enumerate().map(|(k, v)| v + 1e-3 * (k as f64).sin()).collect();
    let (lo, hi) = problem.bounds();
    let basis =
        |b: &somnurbs::spline::SparseBasis| serde_json::json!({ "first": b.first, "w": b.w });
    let doc = serde_json::json!({
        "what": "control-net problem of benches/optim.rs: spindle, DNSOM 20x20 map, 18x18 net, chord length, approach B, box Cover",
        "nx": p.nx, "ny": p.ny, "cn_x": p.cn_x, "cn_y": p.cn_y,
        "nu": basis(&p.nu), "nv": basis(&p.nv),
        "data_bottom": p.data_bottom, "data_top": p.data_top,
        "class_bottom": problem.net().classes(View::Bottom),
        "class_top": problem.net().classes(View::Top),
        "x0": x0, "lower": lo, "upper": hi,
        "fitness_x0": problem.fitness(x0),
        "probe": probe, "fitness_probe": problem.fitness(&probe),
        "de": default_optimiser_params("de"), "pso": default_optimiser_params("pso"),
        "csa": default_optimiser_params("csa"),
        "budget": { "generations": 2000, "population": 40, "init_range": 5e-6 },
    });
    std::fs::write(path, serde_json::to_string(&doc).unwrap())
        .unwrap_or_else(|e| panic!("BENCH_EXPORT: cannot write {}: {e}", path.display()));
    println!("wrote {}", path.display());
}

/// An optimiser's default parameters as JSON (its serde form).
fn default_optimiser_params(name: &str) -> serde_json::Value {
    match name {
        "de" => serde_json::to_value(somnurbs::optim::De::default()).unwrap(),
        "pso" => serde_json::to_value(somnurbs::optim::Pso::default()).unwrap(),
        _ => serde_json::to_value(somnurbs::optim::Csa::default()).unwrap(),
    }
}

/// The CPU model and nominal clock (MHz) from /proc/cpuinfo ("unknown", 0 elsewhere).
fn cpu_model() -> (String, f64) {
    let info = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let field = |name: &str| {
        info.lines()
            .find(|l| l.starts_with(name))
            .and_then(|l| l.split(':').nth(1))
            .map(|v| v.trim().to_string())
    };
    (
        field("model name").unwrap_or_else(|| "unknown".into()),
        field("cpu MHz").and_then(|v| v.parse().ok()).unwrap_or(0.0),
    )
}

/// The 1-minute load average (the machine may be shared).
fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".into())
}

/// The core's clock as its FMA throughput shows it, and the cost of one 4-wide square root.
#[derive(Clone, Copy)]
struct Peak {
    mhz: f64,
    sqrt_ns: f64,
}

/// Time `f(n)` (thread CPU time, best of 5) in ns per unit of `n`.
fn best_ns_per(n: usize, f: impl Fn(usize) -> f64) -> f64 {
    (0..5)
        .map(|_| {
            let t = experiment::thread_cpu_seconds();
            std::hint::black_box(f(n));
            (experiment::thread_cpu_seconds() - t) / n as f64 * 1e9
        })
        .fold(f64::INFINITY, f64::min)
}

/// Measure [`Peak`] with ten independent chains of 4-wide FMAs (enough to cover their latency on
/// two pipes) and a chain-free run of 4-wide square roots; None without AVX2 + FMA.
fn fma_peak() -> Option<Peak> {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        if !(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")) {
            return None;
        }
        #[target_feature(enable = "avx2,fma")]
        fn fmas(n: usize) -> f64 {
            let mut acc = [_mm256_set1_pd(1.0); 10];
            let (m, c) = (_mm256_set1_pd(0.999_999), _mm256_set1_pd(std::hint::black_box(1e-9)));
            for _ in 0..n {
                for a in acc.iter_mut() {
                    *a = _mm256_fmadd_pd(*a, m, c);
                }
            }
            let mut out = [0.0; 4];
            let sum = acc.iter().fold(_mm256_setzero_pd(), |s, a| _mm256_add_pd(s, *a));
            // SAFETY: `out` holds four f64.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), sum) };
            out.iter().sum()
        }
        #[target_feature(enable = "avx2,fma")]
        fn sqrts(n: usize) -> f64 {
            let mut acc = [_mm256_setzero_pd(); 4];
            let mut x = _mm256_set1_pd(std::hint::black_box(2.0));
            let step = _mm256_set1_pd(1e-12);
            for _ in 0..n {
                for a in acc.iter_mut() {
                    *a = _mm256_add_pd(*a, _mm256_sqrt_pd(x));
                    x = _mm256_add_pd(x, step);
                }
            }
            let mut out = [0.0; 4];
            let sum = acc.iter().fold(_mm256_setzero_pd(), |s, a| _mm256_add_pd(s, *a));
            // SAFETY: `out` holds four f64.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), sum) };
            out.iter().sum()
        }
        // SAFETY (both): the CPU reports AVX2 and FMA (checked above).
        let fma_ns = best_ns_per(2_000_000, |n| unsafe { fmas(n) }) / 10.0;
        let sqrt_ns = best_ns_per(500_000, |n| unsafe { sqrts(n) }) / 4.0;
        Some(Peak { mhz: 1e3 / (2.0 * fma_ns), sqrt_ns })
    }
    #[cfg(not(target_arch = "x86_64"))]
    None
}

/// Floating-point lower bound of one fitness evaluation in cycles: pass 1 is 4 multiply(-add)s
/// per grid row and control coordinate (bottom view: nx rows x 3 cn_y; top: nx - 2 rows x its
/// 3 cn_y - 6 interior coordinates), pass 2 is 12 multiply-adds and 3 for the squared norm per
/// grid point (lanes padded to 4), all on two 4-wide FMA pipes.
fn fma_lower_bound_cycles(nx: usize, ny: usize, cn_y: usize) -> f64 {
    let pad = |n: usize| n.div_ceil(4) * 4;
    let k3 = 3 * cn_y;
    let pass1 = 4 * (nx * k3 + (nx - 2) * (k3 - 6));
    let pass2 = 15 * (pad(nx) * ny + pad(nx - 2) * (ny - 2));
    (pass1 + pass2) as f64 / 8.0
}

/// First-pass blocks and second-pass columns of the vector fitness on an nx x ny map with a
/// cn_y-column net: per chunk of four grid rows, the bottom view's segment of 3 cn_y values in
/// blocks of four (the last one overlapping), the top view's two border blocks and its segment
/// of 3 cn_y - 6; per chunk, one column per grid column (ny bottom, ny - 2 top).
fn kernel_blocks(nx: usize, ny: usize, cn_y: usize) -> (usize, usize) {
    let k3 = 3 * cn_y;
    let (bottom, top) = (nx.div_ceil(4), (nx - 2).div_ceil(4));
    (bottom * k3.div_ceil(4) + top * (2 + (k3 - 6).div_ceil(4)), bottom * ny + top * (ny - 2))
}

/// Best of `rounds` batches of fitness evaluations at x0 (ns per evaluation, thread CPU time).
fn best_fitness_ns(problem: &ControlNetProblem, x0: &[f64], rounds: usize) -> f64 {
    let n = 20_000;
    (0..rounds.max(1))
        .map(|_| {
            let t = experiment::thread_cpu_seconds();
            let mut acc = 0.0;
            for _ in 0..n {
                acc += problem.fitness(std::hint::black_box(x0));
            }
            std::hint::black_box(acc);
            (experiment::thread_cpu_seconds() - t) / n as f64 * 1e9
        })
        .fold(f64::INFINITY, f64::min)
}

/// How cost grows: the fitness and one DE run (BENCH_SCALING_GENERATIONS, default 200, x 40)
/// against net size (6x6 to 28x28) and map size (20x20 to 40x40), BENCH_SCALING=1.
fn scaling(points: &[Point3], mhz: f64) {
    let generations: u64 =
        std::env::var("BENCH_SCALING_GENERATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    println!("\nscaling (spindle, DNSOM map, chord length, approach B; one DE run of {generations} x 40):");
    println!("| map | net | variables | fitness ns | cycles | FMA bound | ratio | DE run s | DE us per evaluation |");
    println!("|---|---|---|---|---|---|---|---|---|");
    // A net needs at most as many control points as the map has neurons per side.
    let cases = [(20, 6), (20, 12), (20, 18), (30, 6), (30, 18), (30, 28), (40, 18), (40, 28)];
    let mut maps: Vec<(usize, somnurbs::double_net::TwoViewGrid)> = Vec::new();
    for (m, cn) in cases {
        if !maps.iter().any(|(k, _)| *k == m) {
            let cell = SomCell {
                dataset: "spindle".into(),
                model: Model::Dnsom,
                grid: GridSize { nx: m, ny: m },
                repeat: 0,
            };
            let run = families::som::run_cell(&cell, points, &SomParams::default(), 2023).unwrap();
            maps.push((
                m,
                somnurbs::double_net::TwoViewGrid::from_weights(m, m, &run.weights)
                    .expect("a DNSOM map"),
            ));
        }
        let grid = &maps.iter().find(|(k, _)| *k == m).unwrap().1;
        let fit = fit_two_view(
            grid,
            cn,
            cn,
            Parameterisation::ChordLength,
            Approach::Improved,
            &Default::default(),
        )
        .unwrap();
        let pb = ControlNetProblem::new(
            fit.control_net_parts(grid).unwrap(),
            BoxSpec::Cover { fraction: 0.0 },
        )
        .unwrap();
        let x0 = pb.initial_point().to_vec();
        let ns = best_fitness_ns(&pb, &x0, 3);
        let bound = fma_lower_bound_cycles(m, m, cn);
        let budget =
            Budget { generations, population: 40, init_range: 5e-6, trace_every_evals: 400 };
        let mut rng = somnurbs::experiment::cell_rng(1, "bench");
        let t = experiment::thread_cpu_seconds();
        let r = default_optimiser("de").unwrap().run(&pb, &budget, &mut rng).unwrap();
        let s = experiment::thread_cpu_seconds() - t;
        println!(
            "| {m}x{m} | {cn}x{cn} | {} | {ns:.0} | {:.0} | {bound:.0} | {:.2} | {s:.3} | {:.3} |",
            pb.dim(),
            ns * mhz / 1e3,
            ns * mhz / 1e3 / bound,
            s / r.evaluations as f64 * 1e6
        );
    }
}

/// `BENCH_COUNT=fitness|ga|de|pso|csa|icsa` (BENCH_GENERATIONS, default 100, x 40): only the work
/// inside [`counted`], for instruction counts by
/// `valgrind --tool=callgrind --toggle-collect='*counted*'` (see `scripts/count_overhead.sh`,
/// which turns them into each optimiser's overhead per evaluation in fitness units). `fitness`
/// evaluates the fitness as many times as a DE run of the same budget does (40 (1 + G)) at
/// points that differ from x0 in one coordinate each.
fn count(what: &str, problem: &ControlNetProblem) {
    let generations: u64 =
        std::env::var("BENCH_GENERATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(100);
    let budget = Budget { generations, population: 40, init_range: 5e-6, trace_every_evals: 400 };
    let (evaluations, value) = counted(what, problem, &budget);
    println!("BENCH_COUNT {what}: {evaluations} evaluations, {value:.9}");
}

/// The counted work of [`count`]: (evaluations, the best or summed fitness).
#[inline(never)]
fn counted(what: &str, problem: &ControlNetProblem, budget: &Budget) -> (u64, f64) {
    if what == "fitness" {
        let n = budget.population as u64 * (1 + budget.generations);
        let x0 = problem.initial_point();
        let mut x = x0.to_vec();
        let mut acc = 0.0;
        for k in 0..n as usize {
            let j = k % x0.len();
            x[j] += 1e-9;
            acc += problem.fitness(std::hint::black_box(&x));
            x[j] = x0[j];
        }
        return (n, acc);
    }
    let opt = default_optimiser(what).unwrap_or_else(|| panic!("BENCH_COUNT: unknown '{what}'"));
    let mut rng = somnurbs::experiment::cell_rng(1, "bench");
    let r = opt.run(problem, budget, &mut rng).unwrap();
    (r.evaluations, r.best_fitness)
}
