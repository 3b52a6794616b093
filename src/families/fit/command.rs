//! `somnurbs fit`: fit a user's two-view grid and write its control nets, IGES and OBJ, in the
//! data's own coordinates when the map has its frame beside it (or, asked for, the map's).

use crate::experiment::spec::GridSize;
use crate::io::{csv_records, write_atomic};
use crate::data::frame::Frame;
use crate::spline::export::Units;
use crate::spline::{
    export, fit_two_view, Approach, BSplineSurface, ErrorA, FitOptions, KnotRule,
    Parameterisation, TwoSurfaceFit, TwoViewGrid,
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
    /// Write surfaces that leave the data by more than [`EXCURSION_BOUND`] (with a warning).
    pub(crate) allow_excursion: bool,
}

/// How far the fitted surfaces may leave the map's bounding box between the data points, as a
/// fraction of the box's diagonal, before `fit` and `export` refuse to write them (without
/// `--allow-excursion`); docs/outputs.md.
pub(crate) const EXCURSION_BOUND: f64 = 0.1;

/// What a command that writes surfaces did: wrote them, or refused to (its message printed;
/// exit 2, nothing written).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Outcome {
    Written,
    Refused,
}

/// One fit's choices, as `fit`'s flags name them.
#[derive(Debug, Clone, Copy)]
struct Choice {
    cn: GridSize,
    param: Parameterisation,
    approach: Approach,
    opts: FitOptions,
}

impl Choice {
    fn fit(&self, grid: &TwoViewGrid) -> Result<TwoSurfaceFit> {
        fit_two_view(grid, self.cn.nx, self.cn.ny, self.param, self.approach, &self.opts)
            .map_err(anyhow::Error::from)
    }

    /// The dense excursion of this choice's fit on `grid` (None: no finite fit there).
    fn excursion(&self, grid: &TwoViewGrid) -> Option<f64> {
        let e = self.fit(grid).ok()?.dense_geometry(grid).excursion;
        e.is_finite().then_some(e)
    }

    /// The flags that name this choice.
    fn flags(&self) -> String {
        format!(
            "--cn {} --param {} --knots {} --approach {} --fairness {}",
            self.cn,
            self.param.name(),
            self.opts.knots.name(),
            self.approach.letter(),
            self.opts.fairness
        )
    }
}

/// The diagonal of the bounding box of `points`.
pub(crate) fn diagonal<'a>(points: impl IntoIterator<Item = &'a crate::geom::Point3>) -> f64 {
    let (lo, hi) = crate::spline::geometry::bounding_box(points);
    crate::geom::dist(lo, hi)
}

/// The choices that change one of `c`'s options (the net aside: [`smaller_net`]), with their
/// flag: more fairness, every other parameterisation, the other knot reading and approach.
fn alternatives(c: &Choice) -> Vec<(String, Choice)> {
    let mut out = Vec::new();
    for lambda in [1e-4, 1e-3, 1e-2].into_iter().filter(|&l| l > c.opts.fairness) {
        let opts = FitOptions { fairness: lambda, ..c.opts };
        out.push((format!("--fairness {lambda:e}"), Choice { opts, ..*c }));
    }
    for param in Parameterisation::ALL.into_iter().filter(|&p| p != c.param) {
        out.push((format!("--param {}", param.name()), Choice { param, ..*c }));
    }
    let knots = match c.opts.knots {
        KnotRule::Eq2_10 => KnotRule::NurbsBook,
        KnotRule::NurbsBook => KnotRule::Eq2_10,
    };
    let opts = FitOptions { knots, ..c.opts };
    out.push((format!("--knots {}", knots.name()), Choice { opts, ..*c }));
    let approach = match c.approach {
        Approach::Conventional => Approach::Improved,
        Approach::Improved => Approach::Conventional,
    };
    out.push((format!("--approach {}", approach.letter()), Choice { approach, ..*c }));
    out
}

/// The largest square net below `c`'s, down to 4x4, whose fit on `grid` stays within `bound`:
/// its flag and excursion; None when none does.
fn smaller_net(c: &Choice, grid: &TwoViewGrid, bound: f64) -> Option<(String, f64)> {
    let side = c.cn.nx.min(c.cn.ny);
    (4..=side).rev().filter(|&k| (k, k) != (c.cn.nx, c.cn.ny)).find_map(|k| {
        let cn = GridSize { nx: k, ny: k };
        let e = Choice { cn, ..*c }.excursion(grid)?;
        (e <= bound).then(|| (format!("--cn {cn}"), e))
    })
}

/// The options measured on `grid` in place of `c`: (flag, excursion), those within `bound`
/// first; the square nets are one line (the largest within, or all beyond).
fn measured(c: &Choice, grid: &TwoViewGrid, bound: f64) -> (Vec<(String, f64)>, Vec<String>) {
    let (mut within, mut beyond) = (Vec::new(), Vec::new());
    for (flag, alt) in alternatives(c) {
        match alt.excursion(grid) {
            Some(e) if e <= bound => within.push((flag, e)),
            Some(e) => beyond.push(format!("{flag} ({e:.3e})")),
            None => beyond.push(format!("{flag} (no fit)")),
        }
    }
    match smaller_net(c, grid, bound) {
        Some(net) => within.push(net),
        None if c.cn.nx.min(c.cn.ny) > 4 => {
            beyond.push(format!("every square --cn below {} down to 4x4", c.cn))
        }
        None => {}
    }
    (within, beyond)
}

/// The block `fit` prints when the surfaces leave the data: what and by how much, the options
/// measured on this map that keep them within the bound, and what happens (`written`: the files
/// were written anyway, with --allow-excursion).
fn excursion_block(
    grid: &str,
    c: &Choice,
    dense: &crate::spline::DenseGeometry,
    diagonal: f64,
    found: &(Vec<(String, f64)>, Vec<String>),
    written: Option<&Path>,
) -> String {
    let pct = |e: f64| 100.0 * e / diagonal;
    let mut s = format!(
        "{grid}: between the data points the fitted surfaces ({}) leave the map's bounding box by {:.3e}, {:.1}% of its diagonal {:.3e} (the bound is {}%; largest control-point coordinate {:.3e}): their IGES/OBJ are not usable as they are.\n",
        c.flags(),
        dense.excursion,
        pct(dense.excursion),
        diagonal,
        100.0 * EXCURSION_BOUND,
        dense.max_control
    );
    let (within, beyond) = found;
    if within.is_empty() {
        s.push_str("  No single option measured on this map keeps them within the bound.\n");
    } else {
        s.push_str("  Measured on this map, each of these (one option changed) keeps them within the bound:\n");
        for (flag, e) in within {
            s.push_str(&format!("    {flag:<24} excursion {e:.3e} ({:.1}% of the diagonal)\n", pct(*e)));
        }
    }
    if !beyond.is_empty() {
        s.push_str(&format!("  Measured and still beyond it: {}.\n", beyond.join(", ")));
    }
    s.push_str(&match written {
        None => "  Nothing was written. Re-run with one of the options above, or pass --allow-excursion to write these surfaces anyway.".to_string(),
        Some(out) => format!("  Written anyway (--allow-excursion) into {}.", crate::io::shown(out)),
    });
    s
}

/// The fit's choices from `args`, each flag parsed and checked.
fn choice(args: &Request) -> Result<Choice> {
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
    Ok(Choice { cn, param, approach, opts })
}

/// `somnurbs fit`: fit the grid and, when its surfaces stay within [`EXCURSION_BOUND`] between
/// the data points (or `--allow-excursion`), write them, fit.csv and the manifest; else print
/// the measured alternatives and write nothing.
pub(crate) fn fit(args: &Request) -> Result<Outcome> {
    let c = choice(args)?;
    let shown = args.grid.display().to_string();
    let text = crate::io::map_file::read(&args.grid)?;
    let grid = crate::data::grid_csv::parse_two_view_grid(&text).with_context(|| shown.clone())?;
    let fit = c.fit(&grid).with_context(|| format!("{shown}: {}x{} grid", grid.nx, grid.ny))?;
    let dense = fit.dense_geometry(&grid);
    let generated = export::generation_time().map_err(anyhow::Error::msg)?;
    let date = export::iges_date(generated).map_err(anyhow::Error::msg).context("SOURCE_DATE_EPOCH")?;
    let frame = crate::io::map_file::read_frame(&args.grid)?;
    let export = export_frame(&args.grid, frame, &args.frame, &args.units)?;
    // Every input has loaded and the fit is measured: refuse a fit that leaves the data before
    // the folder is touched.
    let diagonal = diagonal(grid.bottom.iter().chain(&grid.top));
    let bound = EXCURSION_BOUND * diagonal;
    let gate = (dense.excursion > bound).then(|| measured(&c, &grid, bound));
    let name = crate::io::shown(&args.grid);
    if let (Some(found), false) = (&gate, args.allow_excursion) {
        eprintln!("somnurbs: error: {}", excursion_block(&name, &c, &dense, diagonal, found, None));
        return Ok(Outcome::Refused);
    }
    let out = &args.out;
    // The folder is this command's (one writer at a time), and a fit folder, like a run's, holds
    // one result: it must be missing or empty.
    crate::io::outdir::require_folder_outside_results(out, "--out")?;
    let _lock = crate::io::outdir::lock(out, "fit")?;
    crate::io::outdir::require_empty(out)?;
    if let Some(line) = &export.warn {
        eprintln!("{line}");
    }
    let (bottom, top) = (export.place(&fit.bottom), export.place(&fit.top));
    write_surface_files(out, &bottom, &top, &export, args.samples, &date)?;
    write_fit_csv(out, &grid, &c, &fit, &dense, export.label)?;
    // Last, the manifest: its presence says the folder is whole; it says what fit did (drift
    // reads it to tell fits apart).
    let manifest = manifest_text(&shown, &text, generated, record(args, &c))?;
    write_atomic(&out.join(crate::io::outdir::MANIFEST), manifest.as_bytes())?;
    println!("surface error {:.6}, gap {:.3e}, excursion {:.3e}; wrote control_nets.csv, surfaces.igs, surfaces.obj, fit.csv in {}", fit.surface_error, fit.gap, dense.excursion, out.display());
    if let Some(found) = &gate {
        eprintln!("warning: {}", excursion_block(&name, &c, &dense, diagonal, found, Some(out)));
    }
    Ok(Outcome::Written)
}

/// The manifest's `[options]`.
fn record(args: &Request, c: &Choice) -> FitRecord {
    FitRecord {
        cn: c.cn.to_string(),
        param: c.param.name(),
        approach: c.approach.letter(),
        knots: c.opts.knots.name(),
        error_a: c.opts.error_a.name(),
        fairness: args.fairness,
        frame: args.frame.clone(),
        units: args.units.clone(),
        samples: args.samples,
    }
}

/// fit.csv: the fit's options, errors and dense geometry, on the map.
fn write_fit_csv(
    out: &Path,
    grid: &TwoViewGrid,
    c: &Choice,
    fit: &TwoSurfaceFit,
    dense: &crate::spline::DenseGeometry,
    frame: &str,
) -> Result<()> {
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
        c.cn.to_string(),
        c.param.name().into(),
        c.approach.letter().into(),
        c.opts.knots.name().into(),
        c.opts.error_a.name().into(),
        format!("{:?}", c.opts.fairness),
        format!("{:?}", fit.surface_error),
        format!("{:?}", fit.gap),
        format!("{:?}", dense.excursion),
        format!("{:?}", dense.max_control),
        format!("{:?}", dense.border_gap),
        frame.to_string(),
    ];
    write_atomic(&out.join("fit.csv"), csv_records(&summary, &[row])?.as_bytes())
}
