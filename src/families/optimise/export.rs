//! `somnurbs export`: the control net an optimiser found in a finished Chapter 6 folder (or the
//! start, approach B's net), from the cell's record, as control_nets.csv, IGES and OBJ in the data's
//! own frame. The problem is rebuilt from the maps the run saved in the folder (`maps/`), and
//! the record's best fitness (Eq. 6.2) must come out again from the exported net, bit for bit.

use super::{OptimRecord, OptimSpec, ProblemKey};
use crate::experiment::{log, RunContext};
use crate::families::fit::command::{
    diagonal, export_frame, write_surface_files, Outcome, EXCURSION_BOUND, MAX_SAMPLES,
    MIN_SAMPLES,
};
use crate::families::Loaded;
use crate::io::{csv_records, write_atomic};
use crate::optim::Problem;
use anyhow::{Context, Result};

/// The record of the cell `place` (and, in a sweep, of `variant`) in the folder's log.
fn find_record(
    dir: &std::path::Path,
    master_seed: u64,
    place: &str,
    variant: Option<&str>,
) -> Result<(String, OptimRecord)> {
    let records = log::read_records::<serde_json::Value>(dir, master_seed)?;
    let mut found = Vec::new();
    for (key, rec) in records {
        if crate::experiment::seeds::place_of(&key) != place && key != place {
            continue;
        }
        let rec: OptimRecord = serde_json::from_value(rec)
            .with_context(|| format!("cell {key}: its record does not fit this version's"))?;
        let v = rec.row.variant.clone().unwrap_or_default();
        if variant.is_none_or(|want| want == v) {
            found.push((key, rec));
        }
    }
    match found.len() {
        0 => anyhow::bail!(
            "{}: no optimisation cell `{place}`{} in its cell log (runs.csv's `cell` column names them)",
            dir.display(),
            variant.map(|v| format!(" of variant `{v}`")).unwrap_or_default()
        ),
        1 => Ok(found.remove(0)),
        _ => anyhow::bail!(
            "{}: cell `{place}` has {} variants ({}); name one with --variant",
            dir.display(),
            found.len(),
            found.iter().map(|(_, r)| r.row.variant.clone().unwrap_or_default()).collect::<Vec<_>>().join(", ")
        ),
    }
}

/// What `somnurbs export` is asked for (its flags, as the command line gives them).
pub(crate) struct Request {
    pub(crate) results: std::path::PathBuf,
    pub(crate) cell: String,
    pub(crate) variant: Option<String>,
    pub(crate) start: bool,
    pub(crate) out: std::path::PathBuf,
    pub(crate) frame: String,
    pub(crate) units: String,
    pub(crate) samples: usize,
    /// Write a net whose surfaces leave the data by more than [`EXCURSION_BOUND`] (warning).
    pub(crate) allow_excursion: bool,
}

/// parameters.csv's rows: each data point the surface error (Eq. 6.2) counts (the bottom view's
/// all, the top view's interior), with its data parameters (u, v) and its coordinates in the
/// exports' frame: a reader evaluating the exported surfaces there gets the error again.
fn parameter_rows(
    parts: &crate::spline::ControlNetParts,
    place: impl Fn(crate::geom::Point3) -> crate::geom::Point3,
) -> Vec<Vec<String>> {
    let (nx, ny) = (parts.nx, parts.ny);
    let mut rows = Vec::new();
    for (view, data) in [("bottom", &parts.data_bottom), ("top", &parts.data_top)] {
        for i in 0..nx {
            for j in 0..ny {
                let border = i == 0 || j == 0 || i + 1 == nx || j + 1 == ny;
                if view == "top" && border {
                    continue;
                }
                let p = place(data[i * ny + j]);
                rows.push(vec![
                    view.to_string(),
                    i.to_string(),
                    j.to_string(),
                    format!("{:?}", parts.params_u[i]),
                    format!("{:?}", parts.params_v[j]),
                    format!("{:?}", p[0]),
                    format!("{:?}", p[1]),
                    format!("{:?}", p[2]),
                ]);
            }
        }
    }
    rows
}

/// The block `export` prints when the net's surfaces leave the map's bounding box by more than
/// [`EXCURSION_BOUND`] of its diagonal: by how much, the start's (approach B's net) excursion
/// measured on the same problem, and what happens (`written`: written anyway).
fn excursion_block(
    key: &str,
    what: &str,
    problem: &crate::spline::ControlNetProblem,
    x: &[f64],
    start: bool,
    written: Option<&std::path::Path>,
) -> Option<String> {
    let parts = problem.parts();
    let diagonal = diagonal(parts.data_bottom.iter().chain(&parts.data_top));
    let excursion = parts.dense_geometry(x).excursion;
    if excursion <= EXCURSION_BOUND * diagonal {
        return None;
    }
    let pct = |e: f64| 100.0 * e / diagonal;
    let mut s = format!(
        "cell {key}: between the data points the surfaces of {what} leave the map's bounding box by {excursion:.3e}, {:.1}% of its diagonal {diagonal:.3e} (the bound is {}%): their IGES/OBJ are not usable as they are.",
        pct(excursion),
        100.0 * EXCURSION_BOUND
    );
    if !start {
        let e = parts.dense_geometry(problem.initial_point()).excursion;
        let within = if e <= EXCURSION_BOUND * diagonal { "within" } else { "also beyond" };
        s.push_str(&format!("\n  Measured: the start (--start, approach B's net) goes {e:.3e} ({:.1}%), {within} the bound.", pct(e)));
    }
    s.push_str(&match written {
        None => "\n  Nothing was written. Pass --allow-excursion to write this net anyway.".to_string(),
        Some(out) => format!("\n  Written anyway (--allow-excursion) into {}.", crate::io::shown(out)),
    });
    Some(s)
}

/// `somnurbs export RESULTS --cell KEY --out DIR`.
pub(crate) fn export(args: &Request, data_dir: std::path::PathBuf) -> Result<Outcome> {
    if !(MIN_SAMPLES..=MAX_SAMPLES).contains(&args.samples) {
        anyhow::bail!(
            "--samples: must be in [{MIN_SAMPLES}, {MAX_SAMPLES}] (evaluations per direction of the OBJ mesh), got {}",
            args.samples
        );
    }
    let dir = &args.results;
    crate::io::outdir::require_not_being_written(dir)?;
    let fp = log::Fingerprint::read(dir)?.with_context(|| {
        format!("{}: no {}; name a folder `somnurbs run` wrote", dir.display(), log::FINGERPRINT_FILE)
    })?;
    let profile = (fp.profile != "default").then_some(fp.profile.as_str());
    let mut variants: Vec<Loaded> = fp
        .overrides()
        .variants(&fp.spec_path, &fp.spec_text, profile)
        .with_context(|| format!("{}: the folder's spec", dir.display()))?;
    let first = variants.first_mut().context("no spec")?;
    let maps = dir.join("maps");
    first.family().use_maps(&mut first.section, &maps.to_string_lossy());
    let spec = &first.spec;
    let o: &OptimSpec = first.section_as().with_context(|| {
        format!("{}: not a Chapter 6 folder (its spec has no [optimise] section)", dir.display())
    })?;
    let (key, rec) = find_record(dir, spec.file.master_seed, &args.cell, args.variant.as_deref())?;
    let out = &args.out;
    crate::io::outdir::require_folder_outside_results(out, "--out")?;
    let ctx = RunContext {
        compute: false,
        keep_maps: false,
        ..RunContext::new(out.clone(), 1, data_dir)
    };
    let problems = super::problems(spec, o, &ctx)?;
    let param = rec.row.parameterisation.parse().map_err(anyhow::Error::msg)?;
    let cn = crate::experiment::spec::GridSize { nx: rec.row.cn_x, ny: rec.row.cn_y };
    let problem = problems
        .get(&ProblemKey::new(&rec.row.dataset, cn, param))
        .with_context(|| format!("cell {key}: its problem is not among the spec's"))?;
    let best_x: Vec<f64> = rec.best_x.points.iter().flatten().copied().collect();
    let (x, what, recorded) = if args.start {
        (problem.initial_point().to_vec(), "B (the start)", rec.row.b)
    } else {
        (best_x, "the optimiser's best", rec.row.best)
    };
    let error = problem.fitness(&x);
    if error.to_bits() != recorded.to_bits() {
        anyhow::bail!(
            "cell {key}: the exported net's surface error is {error:?}, the record's {recorded:?} (the folder and this build disagree)"
        );
    }
    if let (Some(block), false) =
        (excursion_block(&key, what, problem, &x, args.start, None), args.allow_excursion)
    {
        eprintln!("somnurbs: error: {block}");
        return Ok(Outcome::Refused);
    }
    let frame = maps.join(crate::families::maps::map_file_name(&rec.row.dataset, o.grid));
    let placed = export_frame(&frame, crate::io::map_file::read_frame(&frame)?, &args.frame, &args.units)?;
    let [bottom, top] = problem.parts().surfaces(&x);
    let (bottom, top) = (placed.place(&bottom), placed.place(&top));
    let generated = crate::spline::export::generation_time().map_err(anyhow::Error::msg)?;
    let date = crate::spline::export::iges_date(generated)
        .map_err(anyhow::Error::msg)
        .context("SOURCE_DATE_EPOCH")?;
    let _lock = crate::io::outdir::lock(out, "export")?;
    crate::io::outdir::require_empty(out)?;
    if let Some(line) = &placed.warn {
        eprintln!("{line}");
    }
    write_surface_files(out, &bottom, &top, &placed, args.samples, &date)?;
    let dense = problem.parts().dense_geometry(&x);
    let header: Vec<String> =
        ["results", "cell", "variant", "net", "surface_error", "excursion", "max_control", "frame"]
            .map(String::from)
            .to_vec();
    let row = vec![
        dir.display().to_string(),
        key.clone(),
        rec.row.variant.clone().unwrap_or_default(),
        if args.start { "B".into() } else { rec.row.optimiser.clone() },
        format!("{error:?}"),
        format!("{:?}", dense.excursion),
        format!("{:?}", dense.max_control),
        placed.label.to_string(),
    ];
    write_atomic(&out.join("export.csv"), csv_records(&header, &[row])?.as_bytes())?;
    let params = parameter_rows(problem.parts(), |p| placed.place_point(p));
    let header = ["view", "i", "j", "u", "v", "x", "y", "z"].map(String::from).to_vec();
    write_atomic(&out.join("parameters.csv"), csv_records(&header, &params)?.as_bytes())?;
    println!(
        "{what} of {key}: surface error {error:.9} (as recorded), excursion {:.3e}; wrote control_nets.csv, surfaces.igs, surfaces.obj, export.csv in {}",
        dense.excursion,
        out.display()
    );
    if let Some(block) = excursion_block(&key, what, problem, &x, args.start, Some(out)) {
        eprintln!("warning: {block}");
    }
    Ok(Outcome::Written)
}
