//! Published tables (transcribed CSV, `experiments/reference/`) as a report reads them; each
//! family compiles in its own ([`Published`]).

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

/// A family's published tables, (name, CSV text), compiled in by the family that reproduces
/// them so that a report can always set a reproduction beside them (the toolkit lists none).
pub(crate) type Published = &'static [(&'static str, &'static str)];

/// The table `name` of `published`.
pub fn lookup(published: Published, name: &str) -> Option<RefTable> {
    published.iter().find(|(n, _)| *n == name).map(|(_, text)| RefTable::parse(text))
}

/// Several tables of `published` with the same columns read as one (e.g. Appendix B and the
/// bunny figures of Section 4.3's text); None when none of them is there.
pub(crate) fn joined(published: Published, names: &[&str]) -> Option<RefTable> {
    let mut parts = names.iter().filter_map(|n| lookup(published, n));
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
    const PUBLISHED: super::Published = &[
        ("t1", "data,n,qe\nbunny,30,0.5\ncube,10,0.25\n"),
        ("t2", "data,n,qe\nsphere,20,0.125\n"),
    ];

    #[test]
    fn tables_are_found_by_name_and_joined() {
        let one = super::lookup(PUBLISHED, "t1").unwrap();
        assert_eq!(one.value(&["data", "n"], &["cube".into(), "10".into()], "qe"), Some(0.25));
        assert!(super::lookup(PUBLISHED, "t3").is_none());
        let j = super::joined(PUBLISHED, &["t1", "t3", "t2"]).unwrap();
        assert_eq!(j.rows.len(), 3);
        assert_eq!(j.value(&["data", "n"], &["sphere".into(), "20".into()], "qe"), Some(0.125));
        assert_eq!(j.value(&["data", "n"], &["sphere".into(), "20".into()], "te"), None);
        assert!(super::joined(PUBLISHED, &["t3"]).is_none());
    }
}
