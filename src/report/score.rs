//! The readings score: how near a run's tables are to the published ones, cell by cell, and how
//! many of the sources' claims it counts as the sources do, so that the readings of an ambiguous
//! text can be ranked by how well each reproduces the published numbers.

use super::claims;
use super::reference::RefTable;
use anyhow::{Context, Result};
use std::path::Path;

/// A ratio ours/published inside this band counts as reproduced.
pub(crate) const BAND: (f64, f64) = (0.8, 1.25);

/// Columns that name a row of a published table (the rest are values).
const KEYS: [&str; 9] =
    ["data", "n", "n_x", "n_y", "cn_x", "cn_y", "parameterisation", "statistic", "control_points"];

/// A value column that is no result of the method: CPU seconds (machine-dependent) and the
/// generation at which a best was found.
fn scored(column: &str) -> bool {
    !(column.starts_with("cpu") || column.ends_with("_s") || column == "generation")
}

/// One folder's score.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Score {
    /// Published value cells this folder's tables also hold (both finite, the published non-zero).
    pub(crate) cells: usize,
    /// Of those, the cells whose ratio ours/published lies in [`BAND`].
    pub(crate) within: usize,
    /// Claims with the source's own count over the same cells, other than claims about measured
    /// time ([`claims::Claim::timing`], machine-dependent as CPU seconds are).
    pub(crate) claims: usize,
    /// Of those, the claims whose share agrees with the source's (`Claim::agreement`).
    pub(crate) agree: usize,
}

impl std::ops::Add for Score {
    type Output = Score;
    fn add(self, o: Score) -> Score {
        Score {
            cells: self.cells + o.cells,
            within: self.within + o.within,
            claims: self.claims + o.claims,
            agree: self.agree + o.agree,
        }
    }
}

/// (cells compared, cells within the band) of one of our tables against the published one.
pub(crate) fn table_score(ours: &RefTable, published: &RefTable) -> (usize, usize) {
    let keys: Vec<&str> =
        published.header.iter().map(String::as_str).filter(|c| KEYS.contains(c)).collect();
    let values: Vec<&str> = published
        .header
        .iter()
        .map(String::as_str)
        .filter(|c| !KEYS.contains(c) && scored(c) && ours.header.iter().any(|h| h == c))
        .collect();
    let (mut cells, mut within) = (0, 0);
    for row in &published.rows {
        let key: Vec<String> =
            keys.iter().map(|k| row.get(*k).cloned().unwrap_or_default()).collect();
        let Some(mine) = ours.find(&keys, &key) else { continue };
        for c in &values {
            let num = |r: &std::collections::BTreeMap<String, String>| {
                r.get(*c).and_then(|v| v.parse::<f64>().ok()).filter(|v| v.is_finite())
            };
            if let (Some(o), Some(p)) = (num(mine), num(row).filter(|p| *p != 0.0)) {
                cells += 1;
                let r = o / p;
                within += (BAND.0..=BAND.1).contains(&r) as usize;
            }
        }
    }
    (cells, within)
}

/// The score of a run folder: every CSV named like a table `published` finds, and its
/// `claims.csv`.
pub(crate) fn folder_score(
    folder: &Path,
    published: &dyn Fn(&str) -> Option<RefTable>,
) -> Result<Score> {
    let mut score = Score::default();
    let entries =
        std::fs::read_dir(folder).with_context(|| format!("cannot list {}", folder.display()))?;
    let mut names: Vec<String> = entries
        .filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().to_str().map(String::from))
        .filter(|n| n.ends_with(".csv"))
        .collect();
    names.sort();
    for name in names {
        let Some(published) = published(name.trim_end_matches(".csv")) else { continue };
        let path = folder.join(&name);
        let ours = RefTable::parse(&crate::io::read_text(&path)?);
        let (c, w) = table_score(&ours, &published);
        score.cells += c;
        score.within += w;
    }
    let path = folder.join("claims.csv");
    if path.exists() {
        for c in claims::read(&path)? {
            match c.agreement() {
                _ if c.timing => {}
                "" => {}
                a => {
                    score.claims += 1;
                    score.agree += (a == "agrees") as usize;
                }
            }
        }
    }
    Ok(score)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_matched_by_key_and_counted_inside_the_band() {
        let k = crate::families::optimise::report::PUBLISHED;
        let published = crate::report::reference::lookup(k, "appendix_k").unwrap();
        // Two rows of ours: the first equal to the thesis, the second 30% above it (outside).
        let row = |k: usize, f: f64| -> String {
            let r = &published.rows[k];
            published
                .header
                .iter()
                .map(|h| match r[h].parse::<f64>() {
                    Ok(v) if !KEYS.contains(&h.as_str()) => format!("{}", v * f),
                    _ => r[h].clone(),
                })
                .collect::<Vec<_>>()
                .join(",")
        };
        let text = format!("{}\n{}\n{}\n", published.header.join(","), row(0, 1.0), row(5, 1.3));
        let ours = RefTable::parse(&text);
        // 10 value columns per row (ga/de/pso avg, min, max and b).
        assert_eq!(table_score(&ours, &published), (20, 10));
        // CPU seconds are not scored.
        let m = crate::report::reference::lookup(k, "appendix_m").unwrap();
        assert_eq!(table_score(&m, &m).0, 0);
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("appendix_k.csv"), &text).unwrap();
        std::fs::write(dir.path().join("other.csv"), "a,b\n1,2\n").unwrap();
        let s = folder_score(dir.path(), &|n| crate::report::reference::lookup(k, n)).unwrap();
        assert_eq!((s.cells, s.within, s.claims), (20, 10, 0));
        // Claims: one agreeing, one differing, one about time (left out), one without the
        // source's count (not counted).
        let claims = [
            claims::Claim::most("6", "a", (9, 10)).thesis(Some((9, 10))),
            claims::Claim::most("6", "b", (1, 10)).thesis(Some((10, 10))),
            claims::Claim::most("6", "c", (9, 10)).thesis(Some((9, 10))).timing(),
            claims::Claim::most("6", "d", (9, 10)),
        ];
        claims::write(dir.path(), "s", &claims, false).unwrap();
        let s = folder_score(dir.path(), &|n| crate::report::reference::lookup(k, n)).unwrap();
        assert_eq!((s.claims, s.agree), (2, 1));
        let back = claims::read(&dir.path().join("claims.csv")).unwrap();
        assert_eq!(back.iter().map(|c| c.timing).collect::<Vec<_>>(), [false, false, true, false]);
    }
}
