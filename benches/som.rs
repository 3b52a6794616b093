//! SOM speed figures (run: `cargo bench --bench som`). Prints, does not assert:
//! - DNSOM 30x30, T = 30000, on one core (the thesis: about 5.3 s on spindle, Table 4.7);
//! - the whole Appendix B grid (5 data x n in {10,20,30} x 4 models) wall time on all cores, and
//!   its ratio to the thesis' summed CPU times.

use somnurbs::experiment::{self, RunContext};
use somnurbs::families;
use somnurbs::som::{self, Model, SomParams};
use std::time::Instant;

fn main() {
    let data_dir = somnurbs::experiment::data_dir(None);
    let ctx = RunContext::new(std::env::temp_dir(), 1, data_dir.clone());
    let spindle = somnurbs::data::load_dataset("spindle", &data_dir).expect("spindle");

    // 1. DNSOM 30x30, T = 30000, one core: median of 5 seeds.
    let topo = Model::Dnsom.topology(30, 30).unwrap();
    let params = SomParams::default();
    let mut times = Vec::new();
    for seed in 0..5 {
        let mut rng = somnurbs::experiment::cell_rng(seed, "bench/dnsom");
        let t0 = experiment::thread_cpu_seconds();
        let r = som::train(topo.as_ref(), &spindle.points, &params, &mut rng).unwrap();
        times.push(experiment::thread_cpu_seconds() - t0);
        std::hint::black_box(r);
    }
    times.sort_by(|a, b| a.total_cmp(b));
    let med = times[2];
    println!(
        "dnsom 30x30 T=30000 spindle, one core: median {:.4} s (thesis 5.309147 s: {:.0}x faster)",
        med,
        5.309147 / med
    );

    // 2. The whole Appendix B grid on all cores.
    let spec_path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/ch4_models.toml");
    let loaded = families::Loaded::load(&spec_path, None).expect("spec");
    let som_spec: &families::som::SomSpec = loaded.section_as().expect("a [som] spec");
    let spec = &loaded.spec;
    let cells: Vec<_> =
        families::som::cells(som_spec).into_iter().filter(|c| c.grid.nx == c.grid.ny).collect();
    let jobs = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let ctx = RunContext { jobs, ..ctx };
    let data = families::som::load_datasets(
        spec,
        &som_spec.datasets,
        &ctx,
        (som_spec.spindle_profile, som_spec.spindle_rings),
    )
    .expect("data sets");
    let t0 = Instant::now();
    let runs = experiment::run_cells(
        &cells,
        jobs,
        "appendix B",
        |c| families::som::run_cell(c, &data[&c.dataset].points, &params, spec.file.master_seed),
        |_, _| Ok(()),
    )
    .unwrap();
    let wall = t0.elapsed().as_secs_f64();
    let cpu: f64 = runs.iter().map(|r| r.row.cpu_s).sum();
    let thesis = somnurbs::report::lookup(families::som::PUBLISHED, "appendix_b").unwrap();
    let thesis_cpu: f64 = thesis
        .rows
        .iter()
        .flat_map(|r| {
            Model::ALL.iter().map(move |m| r[&format!("cpu_s_{}", m.key())].parse::<f64>().unwrap())
        })
        .sum();
    println!(
        "appendix B grid ({} cells), {} threads: {:.2} s wall, {:.2} s CPU in training (thesis: {:.1} s CPU; ratio {:.0}x by CPU, {:.0}x by wall)",
        cells.len(),
        jobs,
        wall,
        cpu,
        thesis_cpu,
        thesis_cpu / cpu,
        thesis_cpu / wall
    );
}
