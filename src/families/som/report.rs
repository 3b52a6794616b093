//! Chapter 4 outputs: runs.csv, the Appendix B/C tables, the neuron-count tables 4.9/4.13/4.14, the
//! saved DNSOM maps, the pictures and the Chapter 4 section of REPORT.md. Reads only the runs.

use super::SomRun;
use crate::experiment::spec::{GridSize, Spec};
use crate::io::{csv_records, csv_text, write_atomic};
use crate::report::claims::Claim;
use crate::report::markdown::{beside, geometric_mean, num, table};
use crate::report::reference::{self, RefTable};
use crate::som::Model;
use anyhow::Result;
use std::fmt::Write;
use std::path::Path;

/// Metrics of Appendix B/C, as (column stem, label, runs.csv field).
const METRICS: [(&str, &str); 5] = [
    ("min_error", "Min error"),
    ("max_error", "Max error"),
    ("qe", "QE"),
    ("te", "TE"),
    ("cpu_s", "CPU time (s)"),
];

fn metric(run: &SomRun, stem: &str) -> f64 {
    let r = &run.row;
    match stem {
        "min_error" => r.min_error,
        "max_error" => r.max_error,
        "qe" => r.qe,
        "te" => r.te,
        _ => r.cpu_s,
    }
}

/// Mean of a metric over repeats of (data, model, grid).
fn mean_of(runs: &[SomRun], data: &str, model: Model, grid: GridSize, stem: &str) -> Option<f64> {
    let v: Vec<f64> = runs
        .iter()
        .filter(|r| r.cell.dataset == data && r.cell.model == model && r.cell.grid == grid)
        .map(|r| metric(r, stem))
        .collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn datasets(runs: &[SomRun]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for r in runs {
        if !out.contains(&r.cell.dataset) {
            out.push(r.cell.dataset.clone());
        }
    }
    out
}

fn grids(runs: &[SomRun], square: bool) -> Vec<GridSize> {
    let mut out: Vec<GridSize> = Vec::new();
    for r in runs {
        let g = r.cell.grid;
        if (g.nx == g.ny) == square && !out.contains(&g) {
            out.push(g);
        }
    }
    out
}

/// Appendix B (square grids, four models) or C (nx != ny, CKSOM and DNSOM) with the reference's
/// exact columns. Returns (header, rows) or None when the runs hold no such cell.
pub(crate) fn appendix_table(runs: &[SomRun], square: bool) -> Option<(Vec<String>, Vec<Vec<String>>)> {
    let name = if square { "appendix_b" } else { "appendix_c" };
    let header = reference::lookup(PUBLISHED, name)?.header;
    let models: Vec<Model> =
        if square { Model::ALL.to_vec() } else { vec![Model::Cksom, Model::Dnsom] };
    let mut rows = Vec::new();
    for data in datasets(runs) {
        for grid in grids(runs, square) {
            if !models.iter().any(|&m| mean_of(runs, &data, m, grid, "qe").is_some()) {
                continue;
            }
            let mut row = vec![data.clone()];
            if square {
                row.push(grid.nx.to_string());
            } else {
                row.push(grid.nx.to_string());
                row.push(grid.ny.to_string());
            }
            for (stem, _) in METRICS {
                for &m in &models {
                    row.push(num(mean_of(runs, &data, m, grid, stem), 6).replace('-', ""));
                }
            }
            rows.push(row);
        }
    }
    (!rows.is_empty()).then_some((header, rows))
}

fn counts(model: Model, g: GridSize) -> Option<crate::som::NeuronCounts> {
    model.topology(g.nx, g.ny).ok().map(|t| t.counts())
}

/// The models of `runs` at grids of one shape (square or not), in the thesis' order.
fn models_at(runs: &[SomRun], square: bool) -> Vec<Model> {
    let at = |m: Model| runs.iter().any(|r| r.cell.model == m && (r.cell.grid.nx == r.cell.grid.ny) == square);
    Model::ALL.into_iter().filter(|&m| at(m)).collect()
}

/// Whether `model` ran at `g`.
fn ran(runs: &[SomRun], model: Model, g: GridSize) -> bool {
    runs.iter().any(|r| r.cell.model == model && r.cell.grid == g)
}

/// `model`'s count columns: Table 4.9's (`table_4_13`: false; SOM 2-D n^2, SOM 3-D n^3, CKSOM
/// and DNSOM NON/NOR/NOV) or Table 4.13's (NON/NOV/NOR).
fn count_names(model: Model, table_4_13: bool) -> Vec<String> {
    let key = model.key();
    match model {
        Model::Som2d | Model::Som3d => vec![key.to_string()],
        Model::Cksom | Model::Dnsom => {
            let order = if table_4_13 { ["non", "nov", "nor"] } else { ["non", "nor", "nov"] };
            order.iter().map(|n| format!("{key}_{n}")).collect()
        }
    }
}

/// `model`'s counts at `g` in [`count_names`]' order (a grid `model` ran at has its topology).
fn count_values(model: Model, g: GridSize, table_4_13: bool) -> Vec<usize> {
    match model {
        Model::Som2d => vec![g.nx * g.ny],
        Model::Som3d => vec![g.nx * g.ny * g.nx.max(g.ny)],
        Model::Cksom | Model::Dnsom => match counts(model, g) {
            Some(c) if table_4_13 => vec![c.non, c.nov, c.nor],
            Some(c) => vec![c.non, c.nor, c.nov],
            None => Vec::new(),
        },
    }
}

/// A counts table: the grid's columns (`n`, or `n_x, n_y` for Table 4.13), then each of
/// `models`' count columns (empty where the model did not run at that grid).
fn counts_table(
    runs: &[SomRun],
    grids: &[GridSize],
    models: &[Model],
    table_4_13: bool,
) -> (Vec<String>, Vec<Vec<String>>) {
    let lead: &[&str] = if table_4_13 { &["n_x", "n_y"] } else { &["n"] };
    let mut header: Vec<String> = lead.iter().map(|s| s.to_string()).collect();
    for &m in models {
        header.extend(count_names(m, table_4_13));
    }
    let rows = grids
        .iter()
        .map(|&g| {
            let mut row = vec![g.nx.to_string()];
            if table_4_13 {
                row.push(g.ny.to_string());
            }
            for &m in models {
                let width = count_names(m, table_4_13).len();
                let values = if ran(runs, m, g) { count_values(m, g, table_4_13) } else { Vec::new() };
                let cells = values.iter().map(|v| v.to_string()).chain(std::iter::repeat(String::new()));
                row.extend(cells.take(width));
            }
            row
        })
        .collect();
    (header, rows)
}

/// Table 4.9 at the square grids that ran, with the columns of the models that ran there.
pub(crate) fn table_4_9(runs: &[SomRun]) -> Option<(Vec<String>, Vec<Vec<String>>)> {
    let grids = grids(runs, true);
    let models = models_at(runs, true);
    (!grids.is_empty()).then(|| counts_table(runs, &grids, &models, false))
}

/// Table 4.13 (CKSOM and DNSOM at nx x ny) at the grids that ran, for those of the two models
/// that ran there.
pub(crate) fn table_4_13(runs: &[SomRun]) -> Option<(Vec<String>, Vec<Vec<String>>)> {
    let grids = grids(runs, false);
    let models: Vec<Model> =
        models_at(runs, false).into_iter().filter(|m| matches!(m, Model::Cksom | Model::Dnsom)).collect();
    (!grids.is_empty() && !models.is_empty())
        .then(|| counts_table(runs, &grids, &models, true))
}

/// The thesis' Table 4.14 grids: DNSOM at small nx x (nx + 1).
pub(crate) const TABLE_4_14_GRIDS: [(usize, usize); 6] = [(2, 3), (3, 4), (4, 5), (5, 6), (6, 7), (7, 8)];

/// Table 4.14 (DNSOM counts at the thesis' small grids), when the spec ran DNSOM: the counts are
/// the structure's, built at each grid (no training), so they need no run at those grids.
pub(crate) fn table_4_14(runs: &[SomRun]) -> Option<(Vec<String>, Vec<Vec<String>>)> {
    if !runs.iter().any(|r| r.cell.model == Model::Dnsom) {
        return None;
    }
    let rows: Vec<Vec<String>> = TABLE_4_14_GRIDS
        .iter()
        .map(|&(nx, ny)| {
            let net = crate::double_net::DoubleNet::new(nx, ny).unwrap();
            [nx, ny, net.non(), net.nov(), net.nor()].iter().map(|v| v.to_string()).collect()
        })
        .collect();
    let header = ["n_x", "n_y", "non", "nov", "nor"].iter().map(|s| s.to_string()).collect();
    Some((header, rows))
}

/// The saved DNSOM map of a run.
pub(crate) fn dnsom_map_csv(run: &SomRun) -> Result<String> {
    let g = run.cell.grid;
    let grid = crate::double_net::TwoViewGrid::from_weights(g.nx, g.ny, &run.weights)
        .ok_or_else(|| anyhow::anyhow!("{}: not a DNSOM map", run.row.cell))?;
    crate::io::map_file::text(&grid)
}

/// Write every Chapter 4 file; returns the REPORT.md section. Each saved map has its data set's
/// frame beside it (`maps/dnsom_<data>_<grid>.frame.toml`, not a table: drift skips `maps/`).
/// Without `pictures` (a plan's reading variant, whose maps no later spec reads) the maps are
/// kept gzip-compressed (`.csv.gz`), as a folder keeps the maps it read.
pub(crate) fn write(
    spec: &Spec,
    som: &super::spec::SomSpec,
    runs: &[SomRun],
    frames: &super::Frames,
    out: &Path,
    pictures: bool,
) -> Result<String> {
    let rows: Vec<_> = runs.iter().map(|r| r.row.clone()).collect();
    write_atomic(&out.join("runs.csv"), csv_text(&rows)?.as_bytes())?;
    let mut written = vec!["runs.csv".to_string()];
    for square in [true, false] {
        if let Some((h, r)) = appendix_table(runs, square) {
            let name = if square { "appendix_b.csv" } else { "appendix_c.csv" };
            write_atomic(&out.join(name), csv_records(&h, &r)?.as_bytes())?;
            written.push(name.into());
        }
    }
    for (name, t) in
        [("table_4_9.csv", table_4_9(runs)), ("table_4_13.csv", table_4_13(runs)), ("table_4_14.csv", table_4_14(runs))]
    {
        if let Some((h, r)) = t {
            write_atomic(&out.join(name), csv_records(&h, &r)?.as_bytes())?;
            written.push(name.into());
        }
    }

    let save = &som.save_maps;
    let mut maps = Vec::new();
    for run in runs.iter().filter(|r| {
        r.cell.model == Model::Dnsom && r.cell.repeat == 0 && save.contains(&r.cell.grid)
    }) {
        let name = format!("maps/dnsom_{}_{}.csv", run.cell.dataset, run.cell.grid);
        let text = dnsom_map_csv(run)?;
        let (name, bytes) = if pictures {
            (name, text.into_bytes())
        } else {
            (format!("{name}.gz"), crate::io::map_file::gzip(text.as_bytes())?)
        };
        write_atomic(&out.join(&name), &bytes)?;
        if let Some(frame) = frames.get(&run.cell.dataset) {
            crate::io::map_file::write_frame(&out.join(&name), frame)?;
        }
        maps.push(name);
    }
    let pictures = if pictures && som.pictures {
        super::pictures::write(runs, out)?
    } else {
        Vec::new()
    };
    let claims_md = crate::report::claims::write(out, &spec.file.name, &claims(runs), false)?;
    Ok(section(runs, &written, &maps, &pictures, &claims_md))
}

/// One ranking claim of Chapter 4: among `models`, `target` has the highest (or lowest) `stem`
/// on every (data, grid) case of the square grids (Appendix B) or the others (Appendix C).
struct Ranking {
    statement: &'static str,
    square: bool,
    models: &'static [Model],
    stem: &'static str,
    target: Model,
    highest: bool,
    note: &'static str,
}

/// The thesis' rankings of the four models (Sections 4.4-4.5).
const RANKINGS: [Ranking; 8] = {
    use Model::{Cksom, Dnsom, Som2d, Som3d};
    const ALL: &[Model] = &Model::ALL;
    const PER_N: &str = "per (data, n)";
    const CPU: &str = "CPU time per (data, n)";
    const APP_C: &str = "Appendix C, per (data, grid)";
    const fn r(
        statement: &'static str,
        square: bool,
        models: &'static [Model],
        stem: &'static str,
        target: Model,
        highest: bool,
        note: &'static str,
    ) -> Ranking {
        Ranking { statement, square, models, stem, target, highest, note }
    }
    [
        r("3-D SOM has the highest TE", true, ALL, "te", Som3d, true, PER_N),
        r("DNSOM has the lowest TE", true, ALL, "te", Dnsom, false, PER_N),
        r("2-D SOM has the highest QE", true, ALL, "qe", Som2d, true, PER_N),
        r("3-D SOM has the lowest QE", true, ALL, "qe", Som3d, false, PER_N),
        r("2-D SOM is the fastest", true, ALL, "cpu_s", Som2d, false, CPU),
        r(
            "DNSOM is faster than 3-D SOM and CKSOM",
            true,
            &[Som3d, Cksom, Dnsom],
            "cpu_s",
            Dnsom,
            false,
            CPU,
        ),
        r(
            "DNSOM has a lower TE than CKSOM at nx != ny",
            false,
            &[Cksom, Dnsom],
            "te",
            Dnsom,
            false,
            APP_C,
        ),
        r(
            "CKSOM has a lower QE than DNSOM at nx != ny",
            false,
            &[Cksom, Dnsom],
            "qe",
            Cksom,
            false,
            APP_C,
        ),
    ]
};

/// A value source: (data, model, grid, metric stem) -> the mean over repeats.
type Src<'a> = &'a dyn Fn(&str, Model, GridSize, &str) -> Option<f64>;

/// Whether the ranking holds in one (data, grid) case of a source (None without every value).
fn ranking_case(rk: &Ranking, src: Src, d: &str, g: GridSize) -> Option<bool> {
    let vals: Vec<f64> = rk.models.iter().map(|&m| src(d, m, g, rk.stem)).collect::<Option<_>>()?;
    let t = src(d, rk.target, g, rk.stem)?;
    Some(vals.iter().all(|&v| if rk.highest { t >= v } else { t <= v }))
}

/// Whether QE falls along one (data, model) series of square grids (None without two values).
fn qe_falls_case(src: Src, d: &str, m: Model, sorted: &[GridSize]) -> Option<bool> {
    let v: Vec<f64> = sorted.iter().map(|&g| src(d, m, g, "qe")).collect::<Option<_>>()?;
    (v.len() >= 2).then(|| v.windows(2).all(|w| w[1] < w[0]))
}

/// (holds, checked) over the cases this run has, and the same count on the thesis when it has
/// every one of those cases (else None: the counts would not be of the same cells).
fn paired(
    cases: impl Iterator<Item = (Option<bool>, Option<bool>)>,
) -> ((usize, usize), Option<(usize, usize)>) {
    let (mut ours, mut theirs, mut covered) = ((0, 0), (0, 0), true);
    for (o, t) in cases {
        let Some(o) = o else { continue };
        ours = (ours.0 + o as usize, ours.1 + 1);
        match t {
            Some(t) => theirs = (theirs.0 + t as usize, theirs.1 + 1),
            None => covered = false,
        }
    }
    (ours, covered.then_some(theirs))
}

/// Chapter 4 claims, checked on the runs and, for the same cases, on the thesis' Appendix B/C.
pub(crate) fn claims(runs: &[SomRun]) -> Vec<Claim> {
    let thesis_b = reference::lookup(PUBLISHED, "appendix_b");
    let thesis_c = reference::lookup(PUBLISHED, "appendix_c");
    let ours = |d: &str, m: Model, g: GridSize, s: &str| mean_of(runs, d, m, g, s);
    let theirs = |d: &str, m: Model, g: GridSize, s: &str| -> Option<f64> {
        if g.nx == g.ny {
            thesis_b.as_ref()?.value(
                &["data", "n"],
                &[d.to_string(), g.nx.to_string()],
                &format!("{s}_{}", m.key()),
            )
        } else {
            thesis_c.as_ref()?.value(
                &["data", "n_x", "n_y"],
                &[d.to_string(), g.nx.to_string(), g.ny.to_string()],
                &format!("{s}_{}", m.key()),
            )
        }
    };
    let data = datasets(runs);
    let mut sq = grids(runs, true);
    sq.sort();
    let nsq = grids(runs, false);
    let claim = |statement: &str, (o, t): ((usize, usize), Option<(usize, usize)>), note: &str| {
        Claim::most("4", statement, o).thesis(t).note(note)
    };
    let series = data.iter().flat_map(|d| Model::ALL.iter().map(move |&m| (d, m)));
    let mut claims = vec![claim(
        "QE falls as n grows, for every model",
        paired(series.map(|(d, m)| {
            (qe_falls_case(&ours, d, m, &sq), qe_falls_case(&theirs, d, m, &sq))
        })),
        "per (data, model) series",
    )];
    for rk in &RANKINGS {
        let gs = if rk.square { &sq } else { &nsq };
        let cases = data.iter().flat_map(|d| gs.iter().map(move |&g| (d, g)));
        let c = claim(
            rk.statement,
            paired(cases.map(|(d, g)| (ranking_case(rk, &ours, d, g), ranking_case(rk, &theirs, d, g)))),
            rk.note,
        );
        claims.push(if rk.stem == "cpu_s" { c.timing() } else { c });
    }
    claims
}

/// The thesis' figures at n x n: Appendix B and the bunny run of Section 4.3 (Figure 4.13).
/// The thesis' Appendices B and C, and Section 4.3's bunny figures (its line "The QE and TE of the
/// experiment were 0.049694 and 0.225400 ... CPU time ... 5.386289 seconds", in Appendix B's
/// columns, DNSOM only).
pub const PUBLISHED: reference::Published = &[
    ("appendix_b", include_str!("../../../experiments/reference/appendix_b.csv")),
    ("appendix_c", include_str!("../../../experiments/reference/appendix_c.csv")),
    ("section_4_bunny", include_str!("../../../experiments/reference/section_4_bunny.csv")),
];

const THESIS_SQUARE: [&str; 2] = ["appendix_b", "section_4_bunny"];

fn side_by_side(runs: &[SomRun], square: bool, thesis: Option<&RefTable>) -> String {
    // Only the models that ran, and "(thesis)" only where the thesis has a value for a cell.
    let shown: &[Model] = if square { &Model::ALL } else { &[Model::Cksom, Model::Dnsom] };
    let models: Vec<Model> =
        shown.iter().copied().filter(|&m| runs.iter().any(|r| r.cell.model == m)).collect();
    let mut s = String::new();
    for (stem, label) in METRICS {
        let mut header = vec!["data".to_string(), "grid".to_string()];
        header.extend(models.iter().map(|m| m.label().to_string()));
        let mut rows = Vec::new();
        let mut any_thesis = false;
        for d in datasets(runs) {
            for g in grids(runs, square) {
                let mut row = vec![d.clone(), g.to_string()];
                for &m in &models {
                    let key: Vec<String> = if square {
                        vec![d.clone(), g.nx.to_string()]
                    } else {
                        vec![d.clone(), g.nx.to_string(), g.ny.to_string()]
                    };
                    let cols: Vec<&str> =
                        if square { vec!["data", "n"] } else { vec!["data", "n_x", "n_y"] };
                    let t =
                        thesis.and_then(|t| t.value(&cols, &key, &format!("{stem}_{}", m.key())));
                    any_thesis |= t.is_some();
                    row.push(beside(
                        mean_of(runs, &d, m, g, stem),
                        t,
                        if stem == "cpu_s" { 3 } else { 4 },
                    ));
                }
                rows.push(row);
            }
        }
        let whose = if any_thesis { "ours (thesis)" } else { "ours (the thesis has none of these cells)" };
        let _ = write!(s, "\n**{label}** — {whose}\n\n{}", table(&header, &rows));
    }
    s
}

fn speed_section(runs: &[SomRun]) -> String {
    let tb = reference::joined(PUBLISHED, &THESIS_SQUARE);
    let tc = reference::lookup(PUBLISHED, "appendix_c");
    let mut rows = Vec::new();
    for m in Model::ALL {
        let mut ratios = Vec::new();
        let (mut ours_sum, mut theirs_sum) = (0.0, 0.0);
        for r in runs.iter().filter(|r| r.cell.model == m) {
            let g = r.cell.grid;
            let t = if g.nx == g.ny {
                tb.as_ref().and_then(|t| {
                    t.value(
                        &["data", "n"],
                        &[r.cell.dataset.clone(), g.nx.to_string()],
                        &format!("cpu_s_{}", m.key()),
                    )
                })
            } else {
                tc.as_ref().and_then(|t| {
                    t.value(
                        &["data", "n_x", "n_y"],
                        &[r.cell.dataset.clone(), g.nx.to_string(), g.ny.to_string()],
                        &format!("cpu_s_{}", m.key()),
                    )
                })
            };
            if let Some(t) = t {
                // Scale the thesis' time to this run's iteration count (the thesis used T = 30000).
                let t_scaled = t * r.row.iterations as f64 / 30_000.0;
                if r.row.cpu_s > 0.0 {
                    ratios.push(t_scaled / r.row.cpu_s);
                    ours_sum += r.row.cpu_s;
                    theirs_sum += t_scaled;
                }
            }
        }
        if !ratios.is_empty() {
            rows.push(vec![
                m.label().to_string(),
                ratios.len().to_string(),
                format!("{theirs_sum:.2}"),
                format!("{ours_sum:.3}"),
                num(geometric_mean(&ratios), 0),
            ]);
        }
    }
    if rows.is_empty() {
        return String::new();
    }
    let header: Vec<String> =
        ["model", "cells", "thesis CPU s (scaled to T)", "ours CPU s", "speed-up (geometric mean)"]
            .iter()
            .map(|s| s.to_string())
            .collect();
    format!(
        "\n### Speed against the thesis' CPU times\n\nCPU seconds of the training loop on one core (thread CPU clock), against Appendix B/C; the thesis' times are scaled to this run's iteration count when it is not 30000.\n\n{}",
        table(&header, &rows)
    )
}

fn section(
    runs: &[SomRun],
    written: &[String],
    maps: &[String],
    pictures: &[String],
    claims_md: &str,
) -> String {
    let mut s = String::from("## Chapter 4: SOM models (Appendices A-D)\n\n");
    let iters: Vec<usize> = runs.iter().map(|r| r.row.iterations).collect();
    let _ = writeln!(
        s,
        "{} cells, T = {} iterations. Files: {}.\n",
        runs.len(),
        iters.first().copied().unwrap_or(0),
        written.iter().map(|w| format!("`{w}`")).collect::<Vec<_>>().join(", ")
    );
    s.push_str(DEFINITIONS);
    if !claims_md.is_empty() {
        s.push_str("\n### Claims\n\n");
        s.push_str(claims_md);
    }
    if appendix_table(runs, true).is_some() {
        s.push_str("\n### Appendix B, side by side\n");
        s.push_str(&side_by_side(runs, true, reference::joined(PUBLISHED, &THESIS_SQUARE).as_ref()));
    }
    if appendix_table(runs, false).is_some() {
        s.push_str("\n### Appendix C, side by side\n");
        s.push_str(&side_by_side(runs, false, reference::lookup(PUBLISHED, "appendix_c").as_ref()));
    }
    s.push_str(&speed_section(runs));
    s.push_str(&count_tables(runs));
    if !maps.is_empty() {
        let _ = writeln!(
            s,
            "\nDNSOM maps saved for Chapter 5: {}.",
            maps.iter().map(|m| format!("`{m}`")).collect::<Vec<_>>().join(", ")
        );
    }
    if !pictures.is_empty() {
        s.push_str("\n### Pictures\n\n");
        for p in pictures.iter().filter(|p| !p.starts_with("png/")) {
            let _ = writeln!(s, "![{p}]({p})\n");
        }
        let per_cell = pictures.iter().filter(|p| p.starts_with("png/")).count();
        let _ = writeln!(s, "One picture per cell ({per_cell}) in `png/`.");
    }
    s
}

/// Tables 4.9, 4.13 and 4.14 as they ran: only the grids and models of the runs, saying which of
/// the thesis' cells did not run.
fn count_tables(runs: &[SomRun]) -> String {
    let mut s = String::new();
    if let Some((h, r)) = table_4_9(runs) {
        let _ = write!(s, "\n### Table 4.9: neurons representing the surface\n\n{}{}", not_run(runs, true), table(&h, &r));
    }
    if let Some((h, r)) = table_4_13(runs) {
        let _ = write!(s, "\n### Table 4.13: CKSOM and DNSOM at nx x ny\n\n{}\n{}{}", table_4_13_note(runs), not_run(runs, false), table(&h, &r));
    }
    if let Some((h, r)) = table_4_14(runs) {
        let _ = write!(s, "\n### Table 4.14: DNSOM neuron counts\n\nThe DNSOM structure at the thesis' small grids, built at each (the counts depend on the grid alone; no map is trained there).\n\n{}", table(&h, &r));
    }
    s
}

/// The sentence before Table 4.9 (`square`) or 4.13 naming the thesis' models that did not run
/// at those grids (empty when all of them ran).
fn not_run(runs: &[SomRun], square: bool) -> String {
    let thesis: &[Model] = if square { &Model::ALL } else { &[Model::Cksom, Model::Dnsom] };
    let ran = models_at(runs, square);
    let missing: Vec<&str> = thesis.iter().filter(|m| !ran.contains(m)).map(|m| m.label()).collect();
    if missing.is_empty() {
        return String::new();
    }
    format!("Only the models that ran; {} did not run at these grids (the thesis' table has them).\n\n", missing.join(", "))
}

/// Table 4.13's note: the thesis' DNSOM counts where DNSOM ran at its grids, and how CKSOM's are
/// built where CKSOM ran.
fn table_4_13_note(runs: &[SomRun]) -> String {
    let thesis = [((10, 8), "160/128/32"), ((20, 12), "480/420/60"), ((18, 30), "1080/988/92")];
    let at: Vec<&str> = thesis
        .iter()
        .filter(|((nx, ny), _)| ran(runs, Model::Dnsom, GridSize { nx: *nx, ny: *ny }))
        .map(|(_, c)| *c)
        .collect();
    let mut s = String::new();
    if !at.is_empty() {
        let _ = write!(s, "DNSOM counts equal the thesis' ({}).", at.join(", "));
    }
    if models_at(runs, false).contains(&Model::Cksom) {
        s.push_str(if s.is_empty() { "" } else { " " });
        s.push_str("The CKSOM counts at nx != ny follow this harness' documented construction (six nx x ny faces on a cube of side max(nx, ny)); the thesis' own construction (400/1308/3040 output neurons) is not published.");
    }
    if !s.is_empty() {
        s.push('\n');
    }
    s
}

/// Exact metric definitions, stated because libraries disagree.
pub(crate) const DEFINITIONS: &str = "\
### Metric definitions

- **QE (online, the thesis' Eq. 4.15)**: mean over the T training iterations of the Euclidean distance |X(t) - W_c(t)| between the drawn input and its winner, measured before that iteration's update. **Min/max error**: the minimum and maximum of the same distance over the iterations.
- **TE (online, Eq. 4.16)**: share of the T iterations whose first and second winners are not adjacent. Adjacent = index-space distance 1: the 4-neighbourhood on a 2-D map, the 6-neighbourhood in the 3-D lattice and on the CKSOM cube surface (across merged edges), and for DNSOM the 4-neighbourhood on either view taken over class numbers (a border neuron is adjacent to its interior neighbours on both views).
- **qe_final / te_final (runs.csv)**: the same two quantities over every data point for the trained map: mean Euclidean (not squared) distance to the best-matching unit, as MiniSom's `quantization_error`; share of points whose two best units are not adjacent with the adjacency above (MiniSom's `topographic_error` instead counts the 8-neighbourhood as adjacent on rectangular maps).
- **CPU time**: CPU seconds of the training loop on its thread (initialisation and T iterations; not data loading or final metrics).
";
