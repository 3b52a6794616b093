//! Chapter 5 outputs: runs.csv, Appendix E/F (surface error of A and B per parameterisation), the
//! win-count tables 5.4-5.9, the gap table, the charts and pictures and the REPORT.md section.

use super::FitRun;
use crate::experiment::spec::GridSize;
use crate::io::{csv_records, csv_text, write_atomic};
use crate::report::claims::Claim;
use crate::report::markdown::{beside, num, table};
use crate::report::ordered;
use crate::report::reference::{self, RefTable};
use crate::spline::{Approach, Parameterisation};
use anyhow::Result;
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::Path;

/// The thesis' Appendices E and F (surface error of approaches A and B).
pub(crate) const PUBLISHED: crate::report::reference::Published = &[
    ("appendix_e", include_str!("../../../experiments/reference/appendix_e.csv")),
    ("appendix_f", include_str!("../../../experiments/reference/appendix_f.csv")),
];

/// Names of a grid's tables: (appendix, param wins for A, param wins for B, A vs B).
fn table_names(grid: GridSize) -> (String, String, String, String) {
    match (grid.nx, grid.ny) {
        (20, 20) => {
            ("appendix_e".into(), "table_5_4".into(), "table_5_5".into(), "table_5_6".into())
        }
        (18, 30) => {
            ("appendix_f".into(), "table_5_7".into(), "table_5_8".into(), "table_5_9".into())
        }
        _ => (
            format!("surface_error_{grid}"),
            format!("param_wins_A_{grid}"),
            format!("param_wins_B_{grid}"),
            format!("approach_wins_{grid}"),
        ),
    }
}

/// Surface error of a (data, cn, param, approach) cell, from the runs or from a published table.
/// Rows of a table (CSV or markdown cells).
type Rows = Vec<Vec<String>>;

fn header(cols: &[&str]) -> Vec<String> {
    cols.iter().map(|c| c.to_string()).collect()
}

type ErrorOf<'a> = dyn Fn(&str, GridSize, Parameterisation, Approach) -> Option<f64> + 'a;

fn runs_error(
    runs: &[FitRun],
) -> impl Fn(&str, GridSize, Parameterisation, Approach) -> Option<f64> + '_ {
    move |d, cn, p, a| {
        runs.iter()
            .find(|r| {
                r.cell.dataset == d && r.cell.cn == cn && r.cell.param == p && r.cell.approach == a
            })
            .map(|r| r.row.surface_error)
    }
}

fn thesis_error(
    t: &RefTable,
) -> impl Fn(&str, GridSize, Parameterisation, Approach) -> Option<f64> + '_ {
    move |d, cn, p, a| {
        t.value(
            &["data", "cn_x", "cn_y"],
            &[d.to_string(), cn.nx.to_string(), cn.ny.to_string()],
            &format!("{}_{}", p.name(), a.letter()),
        )
    }
}

/// Per data set: how many control nets each parameterisation had the least error for approach `a`.
fn param_wins(
    err: &ErrorOf,
    data: &[String],
    cns: &[GridSize],
    params: &[Parameterisation],
    a: Approach,
) -> Vec<(String, Vec<usize>, usize)> {
    data.iter()
        .map(|d| {
            let mut wins = vec![0; params.len()];
            let mut cells = 0;
            for &cn in cns {
                let v: Option<Vec<f64>> = params.iter().map(|&p| err(d, cn, p, a)).collect();
                if let Some(v) = v {
                    cells += 1;
                    let best = v.iter().cloned().fold(f64::INFINITY, f64::min);
                    if let Some(k) = v.iter().position(|&x| x == best) {
                        wins[k] += 1;
                    }
                }
            }
            (d.clone(), wins, cells)
        })
        .collect()
}

/// Per (data, param): control nets where A had less error than B, and where B had less (ties to neither).
fn approach_wins(
    err: &ErrorOf,
    data: &[String],
    cns: &[GridSize],
    params: &[Parameterisation],
) -> Vec<(String, Parameterisation, usize, usize, usize)> {
    let mut out = Vec::new();
    for d in data {
        for &p in params {
            let (mut a_w, mut b_w, mut cells) = (0, 0, 0);
            for &cn in cns {
                if let (Some(a), Some(b)) =
                    (err(d, cn, p, Approach::Conventional), err(d, cn, p, Approach::Improved))
                {
                    cells += 1;
                    a_w += (a < b) as usize;
                    b_w += (b < a) as usize;
                }
            }
            out.push((d.clone(), p, a_w, b_w, cells));
        }
    }
    out
}

/// Write every Chapter 5 file; returns the REPORT.md section.
/// One grid's runs and what its tables are computed over.
struct GridRuns {
    grid: GridSize,
    runs: Vec<FitRun>,
    data: Vec<String>,
    cns: Vec<GridSize>,
    params: Vec<Parameterisation>,
    approaches: Vec<Approach>,
    /// The thesis' Appendix E/F, when this grid has one.
    thesis: Option<RefTable>,
    names: (String, String, String, String),
}

impl GridRuns {
    fn new(runs: &[FitRun], grid: GridSize) -> GridRuns {
        let runs: Vec<FitRun> = runs.iter().filter(|r| r.cell.grid == grid).cloned().collect();
        let names = table_names(grid);
        GridRuns {
            grid,
            data: ordered(runs.iter().map(|r| r.cell.dataset.clone())),
            cns: ordered(runs.iter().map(|r| r.cell.cn)),
            params: ordered(runs.iter().map(|r| r.cell.param)),
            approaches: ordered(runs.iter().map(|r| r.cell.approach)),
            thesis: reference::lookup(PUBLISHED, &names.0),
            names,
            runs,
        }
    }
}

/// Appendix E/F (ours), in the reference's column order where there is one.
fn appendix(g: &GridRuns) -> (Vec<String>, Rows) {
    let ours = runs_error(&g.runs);
    let header: Vec<String> = match &g.thesis {
        Some(t) => t.header.clone(),
        None => {
            let mut h = vec!["data".to_string(), "cn_x".into(), "cn_y".into()];
            for p in Parameterisation::ALL {
                for a in [Approach::Conventional, Approach::Improved] {
                    h.push(format!("{}_{}", p.name(), a.letter()));
                }
            }
            h
        }
    };
    let mut rows = Vec::new();
    for d in &g.data {
        for &cn in &g.cns {
            let mut row = vec![d.clone(), cn.nx.to_string(), cn.ny.to_string()];
            for col in &header[3..] {
                let v = Parameterisation::ALL
                    .iter()
                    .flat_map(|&p| {
                        [Approach::Conventional, Approach::Improved].map(move |a| (p, a))
                    })
                    .find(|(p, a)| format!("{}_{}", p.name(), a.letter()) == *col)
                    .and_then(|(p, a)| ours(d, cn, p, a));
                row.push(v.map(|x| format!("{x:.6}")).unwrap_or_default());
            }
            rows.push(row);
        }
    }
    (header, rows)
}

/// Control nets where each parameterisation gives approach `a` the least surface error, and the
/// claim that the thesis' best parameterisation for `a` is the best here, counted in cells.
fn param_win_table(g: &GridRuns, a: Approach) -> (Vec<String>, Rows, Option<Claim>) {
    let (data, cns, params, grid) = (&g.data, &g.cns, &g.params, g.grid);
    let w = param_wins(&runs_error(&g.runs), data, cns, params, a);
    let mut h = vec!["data".to_string()];
    h.extend(params.iter().map(|p| p.name().to_string()));
    h.push("cells".into());
    let mut rows: Rows = w
        .iter()
        .map(|(d, v, c)| {
            std::iter::once(d.clone())
                .chain(v.iter().map(|x| x.to_string()))
                .chain(std::iter::once(c.to_string()))
                .collect()
        })
        .collect();
    let totals: Vec<usize> = (0..params.len()).map(|k| w.iter().map(|x| x.1[k]).sum()).collect();
    let cells: usize = w.iter().map(|x| x.2).sum();
    rows.push(
        std::iter::once("total".to_string())
            .chain(totals.iter().map(|x| x.to_string()))
            .chain(std::iter::once(cells.to_string()))
            .collect(),
    );
    let thesis_best = if a == Approach::Conventional {
        Parameterisation::Exponential
    } else {
        Parameterisation::ChordLength
    };
    // A best-of-several claim needs several: with one parameterisation there is no rival.
    let claim = params.iter().position(|&p| p == thesis_best).filter(|_| params.len() > 1).map(|k| {
        let t_counts = g.thesis.as_ref().map(|t| {
            let tw = param_wins(&thesis_error(t), data, cns, params, a);
            let tt: Vec<usize> =
                (0..params.len()).map(|k| tw.iter().map(|x| x.1[k]).sum()).collect();
            (tt[k], tw.iter().map(|x| x.2).sum::<usize>())
        });
        // Counted in cells, as the thesis counts them: X wins `totals[k]` of `cells` and holds
        // when no other parameterisation wins as many.
        let rival =
            totals.iter().enumerate().filter(|&(j, _)| j != k).map(|(_, &t)| t).max().unwrap_or(0);
        Claim::best(
            "5",
            format!(
                "{} is the best parameterisation for approach {}",
                thesis_best.name(),
                a.letter()
            ),
            (totals[k], cells),
            rival,
        )
        .on_grid(grid)
        .thesis(t_counts)
        .note(format!(
            "wins here: {}",
            params
                .iter()
                .zip(&totals)
                .map(|(p, t)| format!("{} {t}", p.name()))
                .collect::<Vec<_>>()
                .join(", ")
        ))
    });
    (h, rows, claim)
}

/// Control nets where A or B has the smaller surface error, and the claim that B beats A.
fn approach_win_table(g: &GridRuns) -> (Vec<String>, Rows, Claim) {
    let ab = approach_wins(&runs_error(&g.runs), &g.data, &g.cns, &g.params);
    let h = header(&["data", "parameterisation", "a_wins", "b_wins", "cells"]);
    let mut rows: Rows = ab
        .iter()
        .map(|(d, p, a, b, c)| {
            vec![d.clone(), p.name().into(), a.to_string(), b.to_string(), c.to_string()]
        })
        .collect();
    let (ta, tb, tc) = ab.iter().fold((0, 0, 0), |acc, x| (acc.0 + x.2, acc.1 + x.3, acc.2 + x.4));
    rows.push(vec!["total".into(), String::new(), ta.to_string(), tb.to_string(), tc.to_string()]);
    let thesis_ab = g.thesis.as_ref().map(|t| {
        approach_wins(&thesis_error(t), &g.data, &g.cns, &g.params)
            .iter()
            .fold((0, 0), |acc, x| (acc.0 + x.3, acc.1 + x.4))
    });
    let claim = Claim::most("5", "B beats A in most cells", (tb, tc))
        .on_grid(g.grid)
        .thesis(thesis_ab)
        .note("cells where B has the smaller surface error");
    (h, rows, claim)
}

/// The gap (`gaps_<grid>.csv`) of A and B per cell, and the claim that B leaves none.
fn gap_table(g: &GridRuns) -> (Vec<String>, Rows, Claim) {
    let h = header(&["data", "cn_x", "cn_y", "parameterisation", "gap_A", "gap_B"]);
    let mut rows = Vec::new();
    let (mut b_zero, mut b_all, mut a_pos) = (0, 0, 0);
    for d in &g.data {
        for &cn in &g.cns {
            for &p in &g.params {
                let find = |a: Approach| {
                    g.runs
                        .iter()
                        .find(|r| {
                            &r.cell.dataset == d
                                && r.cell.cn == cn
                                && r.cell.param == p
                                && r.cell.approach == a
                        })
                        .map(|r| r.row.gap)
                };
                let (ga, gb) = (find(Approach::Conventional), find(Approach::Improved));
                if let Some(gb) = gb {
                    b_all += 1;
                    b_zero += (gb == 0.0) as usize;
                }
                a_pos += ga.map(|g| (g > 0.0) as usize).unwrap_or(0);
                rows.push(vec![
                    d.clone(),
                    cn.nx.to_string(),
                    cn.ny.to_string(),
                    p.name().into(),
                    num(ga, 9),
                    num(gb, 9),
                ]);
            }
        }
    }
    let grid = g.grid;
    let claim = Claim::every("5", "The improved approach B leaves no gap", (b_zero, b_all))
        .on_grid(grid)
        .note(format!("gap exactly 0; A has a positive gap in {a_pos} cells (`gaps_{grid}.csv`)"));
    (h, rows, claim)
}

/// The claim that the surface error falls as the control net grows, per (data,
/// parameterisation, approach) series, here and on the thesis' figures.
fn series_claim(g: &GridRuns) -> Claim {
    let mut sorted = g.cns.clone();
    sorted.sort();
    let series = |err: &ErrorOf| -> (usize, usize) {
        let (mut yes, mut all) = (0, 0);
        for d in &g.data {
            for &p in &g.params {
                for &a in &g.approaches {
                    let v: Option<Vec<f64>> = sorted.iter().map(|&cn| err(d, cn, p, a)).collect();
                    if let Some(v) = v.filter(|v| v.len() > 1) {
                        all += 1;
                        yes += v.windows(2).all(|w| w[1] < w[0]) as usize;
                    }
                }
            }
        }
        (yes, all)
    };
    Claim::most("5", "Surface error falls as the control net grows", series(&runs_error(&g.runs)))
        .on_grid(g.grid)
        .thesis(g.thesis.as_ref().map(|t| series(&thesis_error(t))))
        .note("per (data, parameterisation, approach) series")
}

/// Appendix E/F in REPORT.md: ours beside the thesis' value, per data set and control net.
fn side_by_side_table(g: &GridRuns) -> (Vec<String>, Rows) {
    let ours = runs_error(&g.runs);
    let mut rows = Vec::new();
    for d in &g.data {
        for &cn in &g.cns {
            let mut row = vec![d.clone(), cn.to_string()];
            for &p in &g.params {
                for &a in &g.approaches {
                    let t = g.thesis.as_ref().and_then(|t| thesis_error(t)(d, cn, p, a));
                    row.push(beside(ours(d, cn, p, a), t, 3));
                }
            }
            rows.push(row);
        }
    }
    let mut h = vec!["data".to_string(), "CN".into()];
    for &p in &g.params {
        for &a in &g.approaches {
            h.push(format!("{} {}", p.name(), a.letter()));
        }
    }
    (h, rows)
}

/// Write every Chapter 5 file (tables computed first, then rendered); returns the REPORT.md
/// section.
pub(crate) fn write(
    spec_name: &str,
    runs: &[FitRun],
    out: &Path,
    maps_origin: &[(String, String)],
    near: &BTreeMap<String, f64>,
    pictures: bool,
) -> Result<String> {
    let rows: Vec<_> = runs.iter().map(|r| r.row.clone()).collect();
    write_atomic(&out.join("runs.csv"), csv_text(&rows)?.as_bytes())?;
    let csv = |name: &str, h: &[String], rows: &Rows| -> Result<()> {
        write_atomic(&out.join(format!("{name}.csv")), csv_records(h, rows)?.as_bytes())
    };
    let mut s = String::from(
        "## Chapter 5: cubic B-spline approximation, conventional (A) vs improved (B)\n\n",
    );
    let _ = writeln!(
        s,
        "{} fits. Maps: {}.\n",
        runs.len(),
        maps_origin.iter().map(|(d, o)| format!("{d} from {o}")).collect::<Vec<_>>().join("; ")
    );
    s.push_str(&method(runs));
    let mut claims = Vec::new();
    for grid in ordered(runs.iter().map(|r| r.cell.grid)) {
        let g = GridRuns::new(runs, grid);
        let (app_name, wa_name, wb_name, ab_name) = g.names.clone();
        let (h, rows) = appendix(&g);
        csv(&app_name, &h, &rows)?;

        // Win counts.
        let mut wins_md = String::new();
        for (a, name) in [(Approach::Conventional, &wa_name), (Approach::Improved, &wb_name)] {
            if !g.approaches.contains(&a) {
                continue;
            }
            let (h, rows, claim) = param_win_table(&g, a);
            csv(name, &h, &rows)?;
            let _ = write!(wins_md, "\n**`{name}.csv`**: control nets where each parameterisation gives approach {} the least surface error\n\n{}", a.letter(), table(&h, &rows));
            claims.extend(claim);
        }
        if g.approaches.contains(&Approach::Conventional)
            && g.approaches.contains(&Approach::Improved)
        {
            let (h, rows, claim) = approach_win_table(&g);
            csv(&ab_name, &h, &rows)?;
            let _ = write!(wins_md, "\n**`{ab_name}.csv`**: control nets where A or B has the smaller surface error\n\n{}", table(&h, &rows));
            claims.push(claim);
            let (h, rows, claim) = gap_table(&g);
            csv(&format!("gaps_{grid}"), &h, &rows)?;
            claims.push(claim);
        }
        claims.push(series_claim(&g));
        if let Some(t) = &g.thesis {
            let ours = runs_error(&g.runs);
            let ratios =
                thesis_ratios(&ours, &thesis_error(t), &g.data, &g.cns, &g.params, &g.approaches);
            if !ratios.is_empty() {
                let (md, claim) = render_thesis_ratios(&ratios, grid, &app_name, out)?;
                wins_md.push_str(&md);
                claims.push(claim);
            }
        }
        let geo = geometry_rows(&g.runs, &g.cns, &g.approaches);
        let (md, claim) = render_geometry(&geo, &g.runs, grid, near, out)?;
        wins_md.push_str(&md);
        claims.push(claim);

        let (mh, md_rows) = side_by_side_table(&g);
        let whose = if md_rows.iter().flatten().any(|c| c.contains('(')) {
            "ours (thesis)"
        } else {
            "ours (the thesis has none of these cells)"
        };
        let _ = write!(s, "\n### Grid {grid}: `{app_name}.csv`, {whose}\n\n");
        s.push_str(&table(&mh, &md_rows));
        s.push_str(&wins_md);
        if pictures {
            for name in super::pictures::write(&g.runs, grid, out)? {
                let _ = writeln!(s, "\n![{name}]({name})");
            }
        }
    }
    let claims_md = crate::report::claims::write(out, spec_name, &claims, false)?;
    if !claims_md.is_empty() {
        s.push_str("\n### Claims\n\n");
        s.push_str(&claims_md);
    }
    if claims.iter().any(|c| {
        c.statement.starts_with("B beats A")
            && (c.verdict() == "does not hold" || c.agreement() == "differs")
    }) {
        s.push_str(DISAGREEMENT);
    }
    Ok(s)
}

/// Per control-net size: the median, least and largest ratio of our surface error to the thesis'
/// over every (data, parameterisation, approach) with both values.
struct Ratio {
    cn: GridSize,
    median: f64,
    min: f64,
    max: f64,
    cells: usize,
}

fn thesis_ratios(
    ours: &ErrorOf,
    thesis: &ErrorOf,
    data: &[String],
    cns: &[GridSize],
    params: &[Parameterisation],
    approaches: &[Approach],
) -> Vec<Ratio> {
    let mut out = Vec::new();
    for &cn in cns {
        let mut r = Vec::new();
        for d in data {
            for &p in params {
                for &a in approaches {
                    if let (Some(o), Some(t)) = (ours(d, cn, p, a), thesis(d, cn, p, a)) {
                        if t > 0.0 {
                            r.push(o / t);
                        }
                    }
                }
            }
        }
        if let Some(median) = crate::report::markdown::median(&r) {
            let min = r.iter().copied().fold(f64::INFINITY, f64::min);
            let max = r.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            out.push(Ratio { cn, median, min, max, cells: r.len() });
        }
    }
    out
}

/// The band within which a median ratio counts as "the thesis' magnitude".
const RATIO_BAND: (f64, f64) = (0.8, 1.25);

fn render_thesis_ratios(
    ratios: &[Ratio],
    grid: GridSize,
    app_name: &str,
    out: &Path,
) -> Result<(String, Claim)> {
    let h: Vec<String> = ["cn_x", "cn_y", "median_ratio", "min_ratio", "max_ratio", "cells"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let rows: Vec<Vec<String>> = ratios
        .iter()
        .map(|r| {
            vec![
                r.cn.nx.to_string(),
                r.cn.ny.to_string(),
                format!("{:.4}", r.median),
                format!("{:.4}", r.min),
                format!("{:.4}", r.max),
                r.cells.to_string(),
            ]
        })
        .collect();
    let name = format!("{app_name}_vs_thesis");
    write_atomic(&out.join(format!("{name}.csv")), csv_records(&h, &rows)?.as_bytes())?;
    let md = format!("\n**`{name}.csv`**: our surface error divided by the thesis', per control net (over data sets, parameterisations and approaches)\n\n{}", table(&h, &rows));
    let inside =
        ratios.iter().filter(|r| r.median >= RATIO_BAND.0 && r.median <= RATIO_BAND.1).count();
    let claim = Claim::most("5", "Surface errors are of the thesis' magnitude", (inside, ratios.len()))
        .on_grid(grid)
        .note(format!(
            "control nets whose median ratio ours/thesis lies in [{}, {}]; medians {}",
            RATIO_BAND.0,
            RATIO_BAND.1,
            ratios.iter().map(|r| format!("{:.2}", r.median)).collect::<Vec<_>>().join(" ")
        ));
    Ok((md, claim))
}

/// The largest dense measures per (control net, approach).
struct GeometryRow {
    cn: GridSize,
    approach: Approach,
    excursion: f64,
    max_control: f64,
    dense_gap: f64,
}

fn geometry_rows(runs: &[FitRun], cns: &[GridSize], approaches: &[Approach]) -> Vec<GeometryRow> {
    let mut out = Vec::new();
    for &cn in cns {
        for &a in approaches {
            let rs: Vec<&FitRun> =
                runs.iter().filter(|r| r.cell.cn == cn && r.cell.approach == a).collect();
            let max = |f: &dyn Fn(&FitRun) -> f64| rs.iter().map(|r| f(r)).fold(0.0, f64::max);
            out.push(GeometryRow {
                cn,
                approach: a,
                excursion: max(&|r| r.row.excursion),
                max_control: max(&|r| r.row.max_control),
                dense_gap: max(&|r| r.row.dense_gap),
            });
        }
    }
    out
}

fn render_geometry(
    geo: &[GeometryRow],
    runs: &[FitRun],
    grid: GridSize,
    near: &BTreeMap<String, f64>,
    out: &Path,
) -> Result<(String, Claim)> {
    let h: Vec<String> =
        ["cn_x", "cn_y", "approach", "max_excursion", "max_control", "max_dense_gap"]
            .iter()
            .map(|s| s.to_string())
            .collect();
    let rows: Vec<Vec<String>> = geo
        .iter()
        .map(|g| {
            vec![
                g.cn.nx.to_string(),
                g.cn.ny.to_string(),
                g.approach.letter().into(),
                format!("{:.6e}", g.excursion),
                format!("{:.6e}", g.max_control),
                format!("{:.6e}", g.dense_gap),
            ]
        })
        .collect();
    let name = format!("geometry_{grid}");
    write_atomic(&out.join(format!("{name}.csv")), csv_records(&h, &rows)?.as_bytes())?;
    let md = format!(
        "\n**`{name}.csv`**: the surfaces between the data points, evaluated at {} points per data interval and at every knot-span midpoint: the largest distance from the data's bounding box (excursion), the largest control-point coordinate, and the largest gap along the whole shared border (per control net and approach, over data sets and parameterisations)\n\n{}",
        crate::spline::DENSE_FACTOR,
        table(&h, &rows)
    );
    use crate::families::maps::{near_note, near_of};
    let count = runs.iter().filter(|r| r.row.excursion <= near_of(near, &r.cell.dataset)).count();
    let worst = runs.iter().max_by(|a, b| a.row.excursion.total_cmp(&b.row.excursion));
    let datasets = ordered(runs.iter().map(|r| r.cell.dataset.clone()));
    let claim = Claim::every("5", "The fitted surfaces stay near the data", (count, runs.len()))
        .on_grid(grid)
        .note(format!("fits whose dense excursion from the data's bounding box is {}{}", near_note(near, &datasets), worst.map(|w| format!("; largest {:.3e} at {}", w.row.excursion, w.row.cell)).unwrap_or_default()));
    Ok((md, claim))
}

/// The method paragraph, naming the readings the runs used.
fn method(runs: &[FitRun]) -> String {
    let used = |f: &dyn Fn(&FitRun) -> String| ordered(runs.iter().map(f)).join(", ");
    format!(
        "Method: cubic in both directions; parameters per grid row and column by the chosen method, averaged over rows/columns (Eq. 5.1, 5.2), and for B also over the two views (Eq. 5.3, 5.4); clamped knots by the knot reading `{}` (`eq2_10`: Eq. 2.10 applied literally with n = CN - 1; `nurbs_book`: The NURBS Book eq. 9.68-9.69); control net by least squares per coordinate; the four corner control points set to the corner data points; for B the shared border control points of the two nets replaced by their mean (Eq. 5.7). Surface error of B (Eq. 5.13): the sum over the NOV grid class numbers of the distance between the map point and the fitted point; of A by the reading `{}` (`per_surface`: over all 2 nx ny map neurons, each surface against its own fit; `nov_bottom`: Eq. 5.13 with a border class on the bottom surface). The gap is the largest distance between the two fitted surfaces at the shared border positions. Every reading is listed in docs/readings.md; the readings matrix of `somnurbs reproduce` shows which conclusions change with them.\n",
        used(&|r| r.row.knots.clone()),
        used(&|r| r.row.error_a.clone())
    )
}

const DISAGREEMENT: &str = "
**Where this reproduction disagrees.** Under the readings used here, the share of cells where B has the smaller surface error does not hold up or differs from the thesis' on the same cells (126/140 and 118/140 on the full grids, Tables 5.6, 5.9). The readings matrix of `somnurbs reproduce` (`readings.csv`) shows the reading under which the thesis' pattern is reproduced (knots `eq2_10` with A's error `per_surface`) and how far the others are from it.
";
