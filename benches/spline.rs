//! Chapter 5 speed (run: `cargo bench --bench spline`): all 280 fits of Appendices E + F (5 data
//! x 4 parameterisations x 7 nets x A/B on grids 20x20 and 18x30) on one core, and one 18x18-net
//! fit on the 20x20 grid. Target: the 280 fits in under 0.5 s (a numpy implementation: 1.2 ms per
//! 18x18 fit; geomdl's approximate_surface: 27 ms). Then seed 003's Bezier fitness per example
//! (evaluations per second, and the full-design SVD path of the grid examples).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use somnurbs::double_net::TwoViewGrid;
use somnurbs::experiment;
use somnurbs::families;
use somnurbs::families::som::SomCell;
use somnurbs::optim::Problem;
use somnurbs::som::{Model, SomParams};
use somnurbs::spline::{example3, franke, height_grid, peaks, BezierParamProblem, Layout};
use somnurbs::spline::{fit_two_view, Approach, Parameterisation};
use std::time::Instant;

fn maps(grid: (usize, usize)) -> Vec<TwoViewGrid> {
    let dir = somnurbs::experiment::data_dir(None);
    let names: Vec<String> =
        ["cube", "sphere", "spindle", "oiltank", "talus"].iter().map(|s| s.to_string()).collect();
    let data: std::collections::BTreeMap<String, _> = names
        .iter()
        .map(|n| {
            (
                n.clone(),
                somnurbs::data::load_dataset(n, &dir)
                    .expect("data sets (talus needs SOMNURBS_DATA)"),
            )
        })
        .collect();
    names
        .iter()
        .map(|d| {
            let g = somnurbs::experiment::GridSize { nx: grid.0, ny: grid.1 };
            let cell = SomCell { dataset: d.clone(), model: Model::Dnsom, grid: g, repeat: 0 };
            let run = families::som::run_cell(&cell, &data[d].points, &SomParams::default(), 2023)
                .unwrap();
            somnurbs::double_net::TwoViewGrid::from_weights(grid.0, grid.1, &run.weights)
                .expect("a DNSOM map")
        })
        .collect()
}

fn main() {
    let _ = experiment::seed_hex(0, "");
    if std::env::args().any(|a| a == "bezier") {
        bezier_fitness(); // `cargo bench --bench spline -- bezier`: seed 003's part only
        return;
    }
    let same = maps((20, 20));
    let diff = maps((18, 30));
    let nets_same: Vec<(usize, usize)> = (3..=9).map(|k| (2 * k, 2 * k)).collect();
    let nets_diff: Vec<(usize, usize)> = (0..7).map(|k| (4 + 2 * k, 16 + 2 * k)).collect();
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t0 = experiment::thread_cpu_seconds();
        let mut n = 0;
        for (grids, nets) in [(&same, &nets_same), (&diff, &nets_diff)] {
            for g in grids.iter() {
                for &(cx, cy) in nets.iter() {
                    for p in Parameterisation::ALL {
                        for a in [Approach::Conventional, Approach::Improved] {
                            std::hint::black_box(
                                fit_two_view(g, cx, cy, p, a, &Default::default()).unwrap(),
                            );
                            n += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(n, 560);
        best = best.min(experiment::thread_cpu_seconds() - t0);
    }
    println!("Appendices E+F: 280 cells (data x parameterisation x net x grid), 560 two-surface fits (A and B), one core: {best:.4} s ({:.3} ms per fit; target < 0.5 s)", best / 560.0 * 1e3);
    let t0 = Instant::now();
    let reps = 200;
    for _ in 0..reps {
        std::hint::black_box(
            fit_two_view(
                &same[2],
                18,
                18,
                Parameterisation::ChordLength,
                Approach::Improved,
                &Default::default(),
            )
            .unwrap(),
        );
    }
    let per = t0.elapsed().as_secs_f64() / reps as f64;
    println!("one 18x18-net fit (both surfaces, approach B) on the 20x20 grid: {:.3} ms (numpy 1.2 ms: {:.1}x; geomdl 27 ms: {:.0}x)", per * 1e3, 1.2e-3 / per, 27e-3 / per);
    bezier_fitness();
}

/// Seed 003: the Bezier parameter problem's fitness per example, one core.
fn bezier_fitness() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let (_, ex3) = example3(628, &mut rng);
    let cases = [
        (
            "example1 29x29 (5,5) grid",
            5,
            Layout::Grid { nu: 29, nv: 29 },
            height_grid(franke, 29, 0.0, 1.0),
        ),
        (
            "example2 41x41 (9,9) grid",
            9,
            Layout::Grid { nu: 41, nv: 41 },
            height_grid(peaks, 41, -3.0, 3.0),
        ),
        ("example3 628 scattered (5,5)", 5, Layout::Scattered, ex3),
    ];
    // `-- bezier example3`: one example only (for profilers)
    let only: Vec<String> = std::env::args().filter(|a| a.starts_with("example")).collect();
    for (name, d, layout, pts) in cases {
        if !only.is_empty() && !only.iter().any(|o| name.starts_with(o.as_str())) {
            continue;
        }
        let dim = match layout {
            Layout::Grid { nu, nv } => nu + nv,
            Layout::Scattered => 2 * pts.len(),
        };
        let xs: Vec<Vec<f64>> =
            (0..64).map(|_| (0..dim).map(|_| rng.gen_range(0.0..1.0)).collect()).collect();
        let prob = BezierParamProblem::new(d, d, layout, pts, xs[0].clone()).unwrap();
        let t = Instant::now();
        let c0 = experiment::thread_cpu_seconds();
        let mut n = 0u64;
        let mut acc = 0.0;
        // BENCH_EVALS=n: exactly n evaluations (for instruction counts under callgrind)
        let fixed: Option<u64> = std::env::var("BENCH_EVALS").ok().and_then(|v| v.parse().ok());
        while fixed.map_or(t.elapsed().as_secs_f64() < 1.0, |f| n < f) {
            acc += prob.fitness(&xs[n as usize % xs.len()]);
            n += 1;
        }
        let secs = t.elapsed().as_secs_f64();
        let cpu = experiment::thread_cpu_seconds() - c0;
        println!(
            "{name}: {:.0} evaluations/s ({:.1} us each, {:.1} us CPU; checksum {acc:.3e})",
            n as f64 / secs,
            1e6 * secs / n as f64,
            1e6 * cpu / n as f64
        );
        if let (Layout::Grid { .. }, None) = (layout, fixed) {
            let t = Instant::now();
            let mut m = 0u64;
            while t.elapsed().as_secs_f64() < 1.0 {
                let _ = prob.fit(&xs[m as usize % xs.len()]);
                m += 1;
            }
            println!(
                "  full-design SVD path: {:.0} evaluations/s",
                m as f64 / t.elapsed().as_secs_f64()
            );
        }
    }
}
