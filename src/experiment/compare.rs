//! `somnurbs compare RESULTS_DIR`: statistics over the optimiser runs of a Chapter 6 folder, read
//! from its runs.csv only (so a folder from another machine or an older run compares the same).

use crate::cli::CompareArgs;
use crate::experiment::ch6::OptimRow;
use crate::report::fsio::{csv_records, write_atomic};
use crate::report::plots;
use crate::stats::{effect, friedman::friedman, rank_sum::rank_sum, wilcoxon::signed_rank, Alternative};
use anyhow::{Context, Result};
use std::collections::BTreeMap;

type CellKey = (String, usize, usize, usize, usize, String);

/// The blocks x treatments table of the Friedman test: one row per cell (data, grid, net,
/// parameterisation) that every optimiser ran, the mean best fitness over repeats of each
/// optimiser (in order of first appearance).
pub fn friedman_table(rows: &[OptimRow]) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut opts: Vec<String> = Vec::new();
    let mut cells: BTreeMap<CellKey, BTreeMap<String, (f64, usize)>> = BTreeMap::new();
    for r in rows {
        if !opts.contains(&r.optimiser) {
            opts.push(r.optimiser.clone());
        }
        let e = cells.entry((r.dataset.clone(), r.grid_x, r.grid_y, r.cn_x, r.cn_y, r.parameterisation.clone())).or_default().entry(r.optimiser.clone()).or_default();
        e.0 += r.best;
        e.1 += 1;
    }
    let table = cells.values().filter(|per| opts.iter().all(|o| per.contains_key(o))).map(|per| opts.iter().map(|o| per[o].0 / per[o].1 as f64).collect()).collect();
    (opts, table)
}

pub fn compare(args: &CompareArgs) -> Result<()> {
    let path = args.results.join("runs.csv");
    let mut reader = csv::Reader::from_path(&path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut rows: Vec<OptimRow> = Vec::new();
    for (n, r) in reader.deserialize().enumerate() {
        rows.push(r.with_context(|| format!("{}: line {}: not a Chapter 6 runs.csv row", path.display(), n + 2))?);
    }
    if rows.is_empty() {
        anyhow::bail!("{}: no runs", path.display());
    }
    let mut opts: Vec<String> = Vec::new();
    let mut cells: BTreeMap<CellKey, BTreeMap<String, Vec<(usize, f64)>>> = BTreeMap::new();
    for r in &rows {
        if !opts.contains(&r.optimiser) {
            opts.push(r.optimiser.clone());
        }
        let key = (r.dataset.clone(), r.grid_x, r.grid_y, r.cn_x, r.cn_y, r.parameterisation.clone());
        cells.entry(key).or_default().entry(r.optimiser.clone()).or_default().push((r.repeat, r.best));
    }
    if opts.len() < 2 {
        anyhow::bail!("{}: only one optimiser ({}); nothing to compare", path.display(), opts[0]);
    }
    // Per cell and pair.
    let header: Vec<String> = ["data", "grid", "cn", "parameterisation", "x", "y", "n", "signed_rank_v", "signed_rank_p", "rank_sum_w", "rank_sum_p", "a12", "a12_magnitude", "h_signed_rank", "h_rank_sum"].iter().map(|s| s.to_string()).collect();
    let mut out = Vec::new();
    let mut wins: BTreeMap<(String, String), (usize, usize)> = BTreeMap::new();
    for (k, per) in &cells {
        for i in 0..opts.len() {
            for j in i + 1..opts.len() {
                let (Some(a), Some(b)) = (per.get(&opts[i]), per.get(&opts[j])) else { continue };
                let mut a = a.clone();
                let mut b = b.clone();
                a.sort_by_key(|x| x.0);
                b.sort_by_key(|x| x.0);
                let xa: Vec<f64> = a.iter().map(|x| x.1).collect();
                let xb: Vec<f64> = b.iter().map(|x| x.1).collect();
                let sr = if xa.len() == xb.len() { signed_rank(&xa, &xb, Alternative::TwoSided).ok() } else { None };
                let rs = rank_sum(&xa, &xb, Alternative::TwoSided).ok();
                let a12 = effect::a12(&xa, &xb);
                let h = |p: Option<f64>| p.map(|p| if p < args.alpha { "1" } else { "0" }).unwrap_or("").to_string();
                if rs.as_ref().map(|r| r.p_value < args.alpha).unwrap_or(false) {
                    let e = wins.entry((opts[i].clone(), opts[j].clone())).or_default();
                    if a12 < 0.5 {
                        e.0 += 1;
                    } else {
                        e.1 += 1;
                    }
                }
                out.push(vec![
                    k.0.clone(),
                    format!("{}x{}", k.1, k.2),
                    format!("{}x{}", k.3, k.4),
                    k.5.clone(),
                    opts[i].clone(),
                    opts[j].clone(),
                    xa.len().to_string(),
                    sr.as_ref().map(|r| r.w_plus.to_string()).unwrap_or_default(),
                    sr.as_ref().map(|r| format!("{:.6}", r.p_value)).unwrap_or_default(),
                    rs.as_ref().map(|r| r.w.to_string()).unwrap_or_default(),
                    rs.as_ref().map(|r| format!("{:.6}", r.p_value)).unwrap_or_default(),
                    format!("{a12:.4}"),
                    effect::magnitude(a12).to_string(),
                    h(sr.as_ref().map(|r| r.p_value)),
                    h(rs.as_ref().map(|r| r.p_value)),
                ]);
            }
        }
    }
    write_atomic(&args.results.join("compare_cells.csv"), csv_records(&header, &out)?.as_bytes())?;
    // Overall: Friedman over cells on the mean best of each optimiser.
    let (_, table) = friedman_table(&rows);
    let f = friedman(&table).map_err(|e| anyhow::anyhow!("{}: Friedman test: {e}", path.display()))?;
    let oh: Vec<String> = ["x", "y", "mean_rank_x", "mean_rank_y", "z", "p", "p_holm", "cells_x_better", "cells_y_better"].iter().map(|s| s.to_string()).collect();
    let orows: Vec<Vec<String>> = f
        .pairwise
        .iter()
        .map(|&(i, j, z, p, ph)| {
            let w = wins.get(&(opts[i].clone(), opts[j].clone())).copied().unwrap_or((0, 0));
            vec![opts[i].clone(), opts[j].clone(), format!("{:.4}", f.mean_ranks[i]), format!("{:.4}", f.mean_ranks[j]), format!("{z:.4}"), format!("{p:.6}"), format!("{ph:.6}"), w.0.to_string(), w.1.to_string()]
        })
        .collect();
    write_atomic(&args.results.join("compare_overall.csv"), csv_records(&oh, &orows)?.as_bytes())?;
    let ranks: Vec<(String, f64)> = opts.iter().cloned().zip(f.mean_ranks.iter().copied()).collect();
    let mut cd_note = String::new();
    if let Some(cd) = f.critical_difference {
        let png = args.results.join("cd_diagram.png");
        match plots::cd_diagram_png(&png, &format!("Mean ranks over {} cells (Nemenyi CD = {cd:.3}, alpha 0.05)", f.blocks), &ranks, cd) {
            Ok(()) => cd_note = format!(", critical-difference diagram {}", png.display()),
            Err(e) => eprintln!("somnurbs: warning: picture skipped: {e}"),
        }
    }
    println!("Friedman over {} cells x {} optimisers: chi-squared {:.3}, df {}, p = {:.3e}", f.blocks, f.treatments, f.chi_squared, f.df, f.p_value);
    for (o, r) in &ranks {
        println!("  mean rank {o:<5} {r:.3}");
    }
    for row in &orows {
        println!("  {} vs {}: z {}, p {} (Holm {}); cells where the rank-sum test favours {}: {}, {}: {}", row[0], row[1], row[4], row[5], row[6], row[0], row[7], row[1], row[8]);
    }
    println!("wrote compare_cells.csv, compare_overall.csv{cd_note} in {}", args.results.display());
    Ok(())
}
