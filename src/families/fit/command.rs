//! `somnurbs fit`: fit a user's two-view grid and write its control nets, IGES and OBJ, in the
//! data's own coordinates when the map has its frame beside it (or, asked for, the map's).

use crate::experiment::spec::GridSize;
use crate::io::{csv_records, read_text, write_atomic};
use crate::data::frame::Frame;
use crate::spline::export::Units;
use crate::spline::{
    export, fit_two_view, Approach, BSplineSurface, ErrorA, FitOptions, KnotRule,
    Parameterisation,
};
use anyhow::{Context, Result};
use std::path::Path;

/// The coordinates the exports are written in.
pub(crate) struct Export {
    /// fit.csv's `frame`: `data`, `normalised` or `map` (no frame found).
    pub(crate) label: &'static str,
    /// Taken from the map's coordinates to the exports' (None: the map's as they are).
    affine: Option<([f64; 3], [f64; 3])>,
    units: Units,
    /// The line the IGES start section and the OBJ comments carry.
    note: String,
    /// Said on stderr once the output folder is this command's (no frame found).
    pub(crate) warn: Option<String>,
}

impl Export {
    /// `p` in the exports' coordinates.
    pub(crate) fn place_point(&self, p: [f64; 3]) -> [f64; 3] {
        match self.affine {
            Some((offset, scale)) => crate::geom::affine(offset, scale, p),
            None => p,
        }
    }

    /// `s` in the exports' coordinates.
    pub(crate) fn place(&self, s: &BSplineSurface) -> BSplineSurface {
        match self.affine {
            Some((offset, scale)) => s.affine(offset, scale),
            None => s.clone(),
        }
    }
}

/// control_nets.csv, surfaces.igs (dated `date`) and surfaces.obj (`samples` per direction) of
/// the two surfaces, already placed ([`Export::place`]), into `out`.
pub(crate) fn write_surface_files(
    out: &Path,
    bottom: &BSplineSurface,
    top: &BSplineSurface,
    export: &Export,
    samples: usize,
    date: &str,
) -> Result<()> {
    let surfaces = [("bottom", bottom), ("top", top)];
    let header: Vec<String> =
        ["view", "a", "b", "x", "y", "z"].iter().map(|s| s.to_string()).collect();
    let rows = net_rows(&surfaces);
    write_atomic(&out.join("control_nets.csv"), csv_records(&header, &rows)?.as_bytes())?;
    let notes = [export.note.clone()];
    write_atomic(
        &out.join("surfaces.igs"),
        export::write_iges(&surfaces, export.units, &notes, date).as_bytes(),
    )?;
    let obj_notes = [export.note.clone(), format!("{}.", export.units.line())];
    write_atomic(
        &out.join("surfaces.obj"),
        export::write_obj(&surfaces, samples, samples, &obj_notes).as_bytes(),
    )
}

/// How `--frame` and `--units` and the frame beside `grid` (if any) place the exports.
pub(crate) fn export_frame(
    grid: &Path,
    frame: Option<Frame>,
    which: &str,
    units: &str,
) -> Result<Export> {
    let units: Units = units.parse().map_err(anyhow::Error::msg).context("--units")?;
    let data = match which {
        "data" => true,
        "normalised" => false,
        other => anyhow::bail!("--frame: `{other}` is neither data nor normalised"),
    };
    let shown = crate::io::shown(grid);
    let Some(f) = frame else {
        let warn = format!(
            "somnurbs: note: no frame beside {shown} ({}): the exports are in the map's own coordinates",
            crate::io::shown(&crate::data::frame::sidecar(grid))
        );
        let note = format!("Frame: the coordinates of the map {shown} as they are (no frame file beside it).");
        return Ok(Export { label: "map", affine: None, units, note, warn: Some(warn) });
    };
    let normalised = f.normalise != crate::data::Normalise::None;
    if data || !normalised {
        let how = if normalised {
            format!("the {} normalisation of the map undone", normalise_name(f.normalise))
        } else {
            "the spec did not normalise".to_string()
        };
        let note = format!("Frame: {} ({how}).", f.describe());
        let affine = Some((f.offset, f.scale));
        return Ok(Export { label: "data", affine, units, note, warn: None });
    }
    if units != Units::Unknown {
        anyhow::bail!("--units: the normalised frame has no length unit (use --frame data)");
    }
    let note = format!(
        "Frame: the normalised box the map was trained in ({} of {}); the data's coordinates are offset + scale * these, offset {:?}, scale {:?}.",
        normalise_name(f.normalise), f.source, f.offset, f.scale
    );
    Ok(Export { label: "normalised", affine: None, units, note, warn: None })
}

fn normalise_name(n: crate::data::Normalise) -> &'static str {
    match n {
        crate::data::Normalise::PerAxis => "per-axis min-max [0, 1]",
        crate::data::Normalise::Uniform => "uniform (longest axis to [0, 1])",
        crate::data::Normalise::None => "none",
    }
}

/// control_nets.csv's rows: view, a, b, x, y, z.
fn net_rows(surfaces: &[(&str, &BSplineSurface)]) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    for (view, s) in surfaces {
        for a in 0..s.cn_x {
            for b in 0..s.cn_y {
                let p = s.control[a * s.cn_y + b];
                rows.push(vec![
                    view.to_string(),
                    a.to_string(),
                    b.to_string(),
                    format!("{:?}", p[0]),
                    format!("{:?}", p[1]),
                    format!("{:?}", p[2]),
                ]);
            }
        }
    }
    rows
}

/// A fit folder's `manifest.toml`: the grid file it fitted and the options it used.
#[derive(serde::Serialize)]
struct FitManifest {
    kind: &'static str,
    grid: String,
    grid_sha256: String,
    command: String,
    /// The IGES file's generation time (`SOURCE_DATE_EPOCH` when set), seconds since 1970.
    generated_unix: i64,
    crate_version: &'static str,
    git_commit: &'static str,
    git_dirty: bool,
    rustc: &'static str,
    options: FitRecord,
}

/// The options of a fit, each by its canonical name (as `fit`'s flags take them).
#[derive(serde::Serialize)]
struct FitRecord {
    cn: String,
    param: &'static str,
    approach: &'static str,
    knots: &'static str,
    error_a: &'static str,
    fairness: f64,
    frame: String,
    units: String,
    samples: usize,
}

/// The text of a fit folder's `manifest.toml`.
fn manifest_text(grid: &str, grid_text: &str, generated: i64, options: FitRecord) -> Result<String> {
    let manifest = FitManifest {
        kind: "fit",
        grid: grid.to_string(),
        grid_sha256: hex::encode(<sha2::Sha256 as sha2::Digest>::digest(grid_text.as_bytes())),
        command: std::env::args().skip(1).collect::<Vec<_>>().join(" "),
        generated_unix: generated,
        crate_version: env!("CARGO_PKG_VERSION"),
        git_commit: env!("SOMNURBS_GIT_COMMIT"),
        git_dirty: env!("SOMNURBS_GIT_DIRTY") == "true",
        rustc: env!("SOMNURBS_RUSTC"),
        options,
    };
    toml::to_string(&manifest).context("manifest.toml")
}

/// `--samples`: evaluations per direction of the OBJ mesh (two make one quad per surface).
pub(crate) const MIN_SAMPLES: usize = 2;
pub(crate) const MAX_SAMPLES: usize = 1000;

/// What `somnurbs fit` is asked to do (the command line's `FitArgs`, as the family takes it; each
/// name is parsed and checked by [`fit`]).
#[derive(Debug, Clone)]
pub(crate) struct Request {
    /// The two-view grid CSV.
    pub(crate) grid: std::path::PathBuf,
    /// Control-net size CNXxCNY.
    pub(crate) cn: String,
    /// Parameterisation name.
    pub(crate) param: String,
    /// Approach name (conventional, improved).
    pub(crate) approach: String,
    /// Output folder.
    pub(crate) out: std::path::PathBuf,
    /// Evaluation samples per direction in the OBJ mesh.
    pub(crate) samples: usize,
    /// Knot reading name.
    pub(crate) knots: String,
    /// Reading of approach A's surface error.
    pub(crate) error_a: String,
    /// Penalised least squares weight.
    pub(crate) fairness: f64,
    /// Coordinates of the exports: `data` or `normalised`.
    pub(crate) frame: String,
    /// Length unit of the data's coordinates.
    pub(crate) units: String,
}

/// `somnurbs fit`: fit the grid, write its surfaces, fit.csv and the manifest.
pub(crate) fn fit(args: &Request) -> Result<()> {
    let cn: GridSize = args.cn.parse().map_err(anyhow::Error::msg).context("--cn")?;
    let param: Parameterisation =
        args.param.parse().map_err(anyhow::Error::msg).context("--param")?;
    let approach: Approach =
        args.approach.parse().map_err(anyhow::Error::msg).context("--approach")?;
    let knots: KnotRule = args.knots.parse().map_err(anyhow::Error::msg).context("--knots")?;
    let error_a: ErrorA = args.error_a.parse().map_err(anyhow::Error::msg).context("--error-a")?;
    if !(0.0..=1e6).contains(&args.fairness) {
        anyhow::bail!("--fairness: must be in [0, 1e6], got {}", args.fairness);
    }
    if !(MIN_SAMPLES..=MAX_SAMPLES).contains(&args.samples) {
        anyhow::bail!(
            "--samples: must be in [{MIN_SAMPLES}, {MAX_SAMPLES}] (evaluations per direction of the OBJ mesh), got {}",
            args.samples
        );
    }
    let opts = FitOptions { knots, error_a, fairness: args.fairness, ..FitOptions::default() };
    let shown = args.grid.display().to_string();
    let text = read_text(&args.grid)?;
    let grid = crate::data::grid_csv::parse_two_view_grid(&text).with_context(|| shown.clone())?;
    let fit = fit_two_view(&grid, cn.nx, cn.ny, param, approach, &opts)
        .with_context(|| format!("{shown}: {}x{} grid", grid.nx, grid.ny))?;

    let generated = export::generation_time().map_err(anyhow::Error::msg)?;
    let date = export::iges_date(generated).map_err(anyhow::Error::msg).context("SOURCE_DATE_EPOCH")?;
    let frame = crate::io::map_file::read_frame(&args.grid)?;
    let export = export_frame(&args.grid, frame, &args.frame, &args.units)?;
    let (bottom, top) = (export.place(&fit.bottom), export.place(&fit.top));
    let out = &args.out;
    // Every input has loaded: the folder is this command's (one writer at a time), and a fit
    // folder, like a run's, holds one result: it must be missing or empty.
    crate::io::outdir::require_folder_outside_results(out, "--out")?;
    let _lock = crate::io::outdir::lock(out, "fit")?;
    crate::io::outdir::require_empty(out)?;
    if let Some(line) = &export.warn {
        eprintln!("{line}");
    }
    write_surface_files(out, &bottom, &top, &export, args.samples, &date)?;
    let dense = fit.dense_geometry(&grid);
    let summary: Vec<String> = [
        "grid",
        "cn",
        "parameterisation",
        "approach",
        "knots",
        "error_a",
        "fairness",
        "surface_error",
        "gap",
        "excursion",
        "max_control",
        "dense_gap",
        "frame",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let row = vec![
        format!("{}x{}", grid.nx, grid.ny),
        cn.to_string(),
        param.name().into(),
        approach.letter().into(),
        knots.name().into(),
        error_a.name().into(),
        format!("{:?}", args.fairness),
        format!("{:?}", fit.surface_error),
        format!("{:?}", fit.gap),
        format!("{:?}", dense.excursion),
        format!("{:?}", dense.max_control),
        format!("{:?}", dense.border_gap),
        export.label.to_string(),
    ];
    write_atomic(&out.join("fit.csv"), csv_records(&summary, &[row])?.as_bytes())?;
    // Last, the manifest: its presence says the folder is whole; it says what fit did (drift
    // reads it to tell fits apart).
    let options = FitRecord {
        cn: cn.to_string(),
        param: param.name(),
        approach: approach.letter(),
        knots: knots.name(),
        error_a: error_a.name(),
        fairness: args.fairness,
        frame: args.frame.clone(),
        units: args.units.clone(),
        samples: args.samples,
    };
    let manifest = manifest_text(&shown, &text, generated, options)?;
    write_atomic(&out.join(crate::io::outdir::MANIFEST), manifest.as_bytes())?;
    println!("surface error {:.6}, gap {:.3e}, excursion {:.3e}; wrote control_nets.csv, surfaces.igs, surfaces.obj, fit.csv in {}", fit.surface_error, fit.gap, dense.excursion, out.display());
    let (lo, hi) = crate::spline::geometry::bounding_box(grid.bottom.iter().chain(&grid.top));
    let diagonal = crate::geom::dist(lo, hi);
    if dense.excursion > 0.1 * diagonal {
        eprintln!(
            "warning: between the data points the surfaces leave the data's bounding box by {:.3e} ({:.0}% of its diagonal; largest control-point coordinate {:.3e}): the exported IGES/OBJ are not usable as they are. Try --knots eq2_10, a smaller --cn, or --fairness 1e-4.",
            dense.excursion,
            100.0 * dense.excursion / diagonal,
            dense.max_control
        );
    }
    Ok(())
}
