//! Chapter 6 over both grids, for a plan's combined report: Tables 6.8 and 6.9 (the win counts
//! of Tables 6.4 + 6.5 and 6.6 + 6.7) and the claims they carry (thesis 6.4, "overall").

use super::spec::OptimSpec;
use crate::experiment::family::{Combined, PlanView};
use crate::io::{csv_records, write_atomic};
use crate::report::claims::{self, Claim};
use crate::report::markdown;
use anyhow::{Context, Result};
use std::path::Path;

/// A table's header and rows, as `csv_records` takes them.
type Header = Vec<String>;
type Rows = Vec<Vec<String>>;

/// The thesis' grids and the win tables each writes (see `report::table_names`).
const GRIDS: [(usize, usize); 2] = [(20, 20), (18, 30)];

/// The plan's thesis protocol (the first spec on each grid without the exact solve), Tables 6.8
/// and 6.9 from its win tables, the claims summed over both grids; the other specs are beyond.
pub(crate) fn combine(view: &PlanView<OptimSpec>) -> Result<Combined> {
    let protocol: Vec<(&str, (usize, usize))> = GRIDS
        .iter()
        .filter_map(|&g| {
            view.specs
                .iter()
                .find(|(_, o)| !o.exact && (o.grid.nx, o.grid.ny) == g)
                .map(|(s, _)| (s.file.name.as_str(), g))
        })
        .collect();
    let mut per_grid = Vec::new();
    for (name, _) in &protocol {
        let path = view.out.join(name).join("claims.csv");
        if path.exists() {
            per_grid.extend(claims::read(&path)?.into_iter().filter(|c| c.ours.1 > 0));
        }
    }
    let mut sections = Vec::new();
    // Each overall table sums one win table per grid: the error wins or the time wins.
    type Names = (&'static str, &'static str, &'static str, &'static str);
    let error_wins: fn(Names) -> &'static str = |t| t.2;
    let time_wins: fn(Names) -> &'static str = |t| t.3;
    for (name, title, thesis, wins) in [
        (
            "table_6_8",
            "Table 6.8: least average optimised surface error, overall",
            "the thesis over its 280 cells: GA 0, DE 243, PSO 37",
            error_wins,
        ),
        (
            "table_6_9",
            "Table 6.9: least average CPU time, overall",
            "the thesis over its 280 cells: GA 280, DE 0, PSO 0",
            time_wins,
        ),
    ] {
        let sources: Vec<(&str, &str)> = protocol
            .iter()
            .filter_map(|(spec, g)| {
                super::report::table_names(g.0, g.1).map(|t| (*spec, wins(t)))
            })
            .collect();
        if let Some((file, h, r)) = overall(view.out, &sources, name)? {
            sections.push(format!(
                "\n## {title}\n\n`{file}.csv` ({thesis}).\n\n{}\n",
                markdown::table(&h, &r)
            ));
        }
    }
    Ok(Combined {
        beyond: view
            .specs
            .iter()
            .map(|(s, _)| s.file.name.clone())
            .filter(|n| !protocol.iter().any(|p| p.0 == n))
            .collect(),
        claims: overall_claims(&per_grid),
        sections,
        readings: Vec::new(),
    })
}

/// A win-count table (Tables 6.4-6.7: data, parameterisation, one column per optimiser, cells).
fn win_table(path: &Path) -> Result<Option<(Vec<String>, Vec<usize>)>> {
    if !path.exists() {
        return Ok(None);
    }
    let mut rd = csv::Reader::from_path(path).with_context(|| format!("{}", path.display()))?;
    let header: Vec<String> = rd
        .headers()
        .with_context(|| format!("{}", path.display()))?
        .iter()
        .map(String::from)
        .collect();
    let opts: Vec<String> = header
        .iter()
        .filter(|h| !["data", "parameterisation", "cells"].contains(&h.as_str()))
        .cloned()
        .collect();
    let mut sums = vec![0usize; opts.len() + 1];
    for (n, rec) in rd.records().enumerate() {
        let rec = rec.with_context(|| format!("{}", path.display()))?;
        if rec.get(0) == Some("total") {
            continue;
        }
        for (k, name) in opts.iter().chain(std::iter::once(&"cells".to_string())).enumerate() {
            let col = header.iter().position(|h| h == name).context("column")?;
            sums[k] += rec.get(col).unwrap_or("").parse::<usize>().map_err(|_| {
                anyhow::anyhow!("{}: line {}: {name} is not a count", path.display(), n + 2)
            })?;
        }
    }
    Ok(Some((opts, sums)))
}

/// Table 6.8 (errors) or 6.9 (CPU time): one row per source table, `wins/cells` per optimiser,
/// and a total row; `None` if neither source table exists.
fn overall(
    out: &Path,
    sources: &[(&str, &str)],
    name: &str,
) -> Result<Option<(String, Header, Rows)>> {
    let mut rows = Vec::new();
    let mut opts: Vec<String> = Vec::new();
    let mut total: Vec<usize> = Vec::new();
    for (spec, table) in sources {
        if let Some((o, sums)) = win_table(&out.join(spec).join(format!("{table}.csv")))? {
            if opts.is_empty() {
                opts = o.clone();
                total = vec![0; o.len() + 1];
            }
            if o != opts {
                anyhow::bail!(
                    "{spec}/{table}.csv has optimisers {o:?}, another table has {opts:?}"
                );
            }
            let cells = sums[o.len()];
            let mut row = vec![format!("Table {}", &table["table_".len()..].replace('_', "."))];
            row.extend(sums[..o.len()].iter().map(|w| format!("{w}/{cells}")));
            rows.push(row);
            for (t, s) in total.iter_mut().zip(&sums) {
                *t += s;
            }
        }
    }
    if rows.is_empty() {
        return Ok(None);
    }
    let cells = total[opts.len()];
    let mut row = vec!["overall".to_string()];
    row.extend(total[..opts.len()].iter().map(|w| format!("{w}/{cells}")));
    rows.push(row);
    let mut header = vec!["table".to_string()];
    header.extend(opts.iter().cloned());
    write_atomic(&out.join(format!("{name}.csv")), csv_records(&header, &rows)?.as_bytes())?;
    Ok(Some((name.to_string(), header, rows)))
}

/// Chapter 6's claims over both grids (Tables 6.8 and 6.9): the per-grid counts summed, here
/// and on the thesis' own figures (where both grids have them).
fn overall_claims(per_grid: &[Claim]) -> Vec<Claim> {
    let mut out = Vec::new();
    for (stem, table) in [
        ("DE gives the least average error in most cells", "Table 6.8"),
        ("GA is the fastest", "Table 6.9"),
    ] {
        let parts: Vec<&Claim> = per_grid
            .iter()
            .filter(|c| c.statement.starts_with(stem) && !c.grid.is_empty())
            .collect();
        if parts.len() < 2 {
            continue;
        }
        let ours = parts.iter().fold((0, 0), |a, c| (a.0 + c.ours.0, a.1 + c.ours.1));
        let thesis = parts.iter().try_fold((0, 0), |a, c| c.thesis.map(|t| (a.0 + t.0, a.1 + t.1)));
        let grids: Vec<&str> = parts.iter().map(|c| c.grid.as_str()).collect();
        let specs: Vec<&str> = parts.iter().map(|c| c.spec.as_str()).collect();
        let mut claim = Claim::most("6", format!("{}, {table}", parts[0].statement), ours)
            .on_grid(grids.join("+"))
            .thesis(thesis)
            .note("sum of the two grids' counts");
        claim.timing = parts[0].timing;
        claim.spec = specs.join("+");
        out.push(claim);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overall_tables_sum_the_win_counts() {
        let dir = tempfile::tempdir().unwrap();
        for (spec, table, rows) in [
            (
                "ch6_same",
                "table_6_4",
                "cube,uniform,0,6,1,7\nsphere,uniform,1,5,1,7\ntotal,,1,11,2,14\n",
            ),
            ("ch6_diff", "table_6_5", "cube,uniform,0,7,0,7\n"),
        ] {
            std::fs::create_dir_all(dir.path().join(spec)).unwrap();
            std::fs::write(
                dir.path().join(spec).join(format!("{table}.csv")),
                format!("data,parameterisation,ga,de,pso,cells\n{rows}"),
            )
            .unwrap();
        }
        let (_, h, r) = overall(
            dir.path(),
            &[("ch6_same", "table_6_4"), ("ch6_diff", "table_6_5")],
            "table_6_8",
        )
        .unwrap()
        .unwrap();
        assert_eq!(h, vec!["table", "ga", "de", "pso"]);
        assert_eq!(r[0], vec!["Table 6.4", "1/14", "11/14", "2/14"]);
        assert_eq!(r[2], vec!["overall", "1/21", "18/21", "2/21"]);
        std::fs::write(
            dir.path().join("ch6_diff/table_6_5.csv"),
            "data,parameterisation,ga,de,pso,cells\ncube,uniform,x,7,0,7\n",
        )
        .unwrap();
        let e = overall(dir.path(), &[("ch6_same", "table_6_4"), ("ch6_diff", "table_6_5")], "t")
            .unwrap_err()
            .to_string();
        assert!(e.contains("table_6_5.csv: line 2: ga"), "{e}");
    }
}
