//! The thesis' published tables (transcribed CSV, `experiments/reference/`), compiled in so that a
//! report can always set a reproduction beside them.

use std::collections::BTreeMap;

/// One published table: its header and rows keyed by column name.
#[derive(Debug, Clone)]
pub struct RefTable {
    pub header: Vec<String>,
    pub rows: Vec<BTreeMap<String, String>>,
}

impl RefTable {
    pub fn parse(text: &str) -> RefTable {
        let mut r = csv::Reader::from_reader(text.as_bytes());
        let header: Vec<String> =
            r.headers().map(|h| h.iter().map(String::from).collect()).unwrap_or_default();
        let rows = r
            .records()
            .filter_map(|rec| rec.ok())
            .map(|rec| header.iter().cloned().zip(rec.iter().map(String::from)).collect())
            .collect();
        RefTable { header, rows }
    }

    /// The row whose key columns equal `key` (in order).
    pub fn find(&self, key_cols: &[&str], key: &[String]) -> Option<&BTreeMap<String, String>> {
        self.rows.iter().find(|row| {
            key_cols.iter().zip(key).all(|(c, k)| row.get(*c).map(|v| v == k).unwrap_or(false))
        })
    }

    /// A numeric cell.
    pub fn value(&self, key_cols: &[&str], key: &[String], col: &str) -> Option<f64> {
        self.find(key_cols, key)?.get(col)?.parse().ok()
    }
}

/// Appendix B (SOM models at n x n), Appendix C (CKSOM vs DNSOM at nx x ny), E/F (surface error),
/// K/L (optimised surface error), M/N (optimiser CPU time).
pub fn table(name: &str) -> Option<RefTable> {
    let text = match name {
        "appendix_b" => include_str!("../../experiments/reference/appendix_b.csv"),
        "appendix_c" => include_str!("../../experiments/reference/appendix_c.csv"),
        "appendix_e" => include_str!("../../experiments/reference/appendix_e.csv"),
        "appendix_f" => include_str!("../../experiments/reference/appendix_f.csv"),
        "appendix_k" => include_str!("../../experiments/reference/appendix_k.csv"),
        "appendix_l" => include_str!("../../experiments/reference/appendix_l.csv"),
        "appendix_m" => include_str!("../../experiments/reference/appendix_m.csv"),
        "appendix_n" => include_str!("../../experiments/reference/appendix_n.csv"),
        // Section 4.3's text (thesis line "The QE and TE of the experiment were 0.049694 and
        // 0.225400 ... CPU time ... 5.386289 seconds"), in Appendix B's columns, DNSOM only.
        "section_4_bunny" => include_str!("../../experiments/reference/section_4_bunny.csv"),
        "seed003_table3" => include_str!("../../experiments/reference/seed003_table3.csv"),
        "seed003_table4" => include_str!("../../experiments/reference/seed003_table4.csv"),
        "seed003_table5" => include_str!("../../experiments/reference/seed003_table5.csv"),
        "seed004_table2" => include_str!("../../experiments/reference/seed004_table2.csv"),
        "seed004_table3" => include_str!("../../experiments/reference/seed004_table3.csv"),
        _ => return None,
    };
    Some(RefTable::parse(text))
}

/// Several published tables with the same columns read as one (e.g. Appendix B and the bunny
/// figures of Section 4.3's text); None when none of them is known.
pub fn joined(names: &[&str]) -> Option<RefTable> {
    let mut parts = names.iter().filter_map(|n| table(n));
    let mut first = parts.next()?;
    for t in parts {
        debug_assert_eq!(
            t.header, first.header,
            "joined reference tables must share their columns"
        );
        first.rows.extend(t.rows);
    }
    Some(first)
}

#[cfg(test)]
mod tests {
    #[test]
    fn published_tables_load() {
        let j = super::joined(&["appendix_b", "section_4_bunny"]).unwrap();
        assert_eq!(
            j.value(&["data", "n"], &["bunny".into(), "30".into()], "qe_dnsom"),
            Some(0.049694)
        );
        assert_eq!(j.value(&["data", "n"], &["bunny".into(), "30".into()], "qe_som2d"), None);
        let b = super::table("appendix_b").unwrap();
        assert_eq!(b.rows.len(), 15);
        assert_eq!(
            b.value(&["data", "n"], &["spindle".into(), "30".into()], "cpu_s_dnsom"),
            Some(5.309147)
        );
        assert_eq!(super::table("appendix_k").unwrap().rows.len(), 140);
    }
}
