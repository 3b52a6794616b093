//! Qualitative claims of the thesis, each checked on the thesis' own published numbers and on a
//! reproduction's, with the counts behind the verdict.

use anyhow::Context;
use std::fmt::Write;

#[derive(Debug, Clone)]
pub struct Claim {
    pub chapter: String,
    pub statement: String,
    /// (cases where it holds, cases checked) on the reproduction.
    pub ours: (usize, usize),
    /// The same count on the thesis' published figures, when they allow it.
    pub thesis: Option<(usize, usize)>,
    /// For a claim that one option is the best of several ("X is the best parameterisation"):
    /// the most cases any other option wins here. The claim then holds when `ours.0` is above it,
    /// so that `ours` counts the same units (cells won out of cells) as the thesis' count.
    pub rival: Option<usize>,
    pub note: String,
}

impl Claim {
    /// Whether the claim holds here without qualification (the verdict "holds").
    pub fn holds(&self) -> bool {
        self.verdict() == "holds"
    }

    pub fn verdict(&self) -> &'static str {
        match (self.ours, self.rival) {
            ((_, 0), _) => "not checked",
            // Best of several: ahead of every other option.
            ((a, _), Some(r)) if a > r => "holds",
            ((a, _), Some(r)) if a == r => "tied",
            (_, Some(_)) => "does not hold",
            ((a, b), None) if a == b => "holds",
            ((a, b), None) if 2 * a > b => "mostly holds",
            _ => "does not hold",
        }
    }
}

/// The columns of `claims.csv`, which every chapter's report writes (and `reproduce` collects).
/// `best_rival_here` is filled for "X is the best of several" claims only (see [`Claim::rival`]).
pub const CSV_HEADER: [&str; 9] = [
    "chapter",
    "claim",
    "verdict",
    "holds_here",
    "checked_here",
    "holds_thesis",
    "checked_thesis",
    "best_rival_here",
    "note",
];

/// Write `claims.csv` into `out` and return the markdown table of the same claims.
pub fn write(out: &std::path::Path, claims: &[Claim]) -> anyhow::Result<String> {
    let rows: Vec<Vec<String>> = claims
        .iter()
        .map(|c| {
            let (ht, ct) =
                c.thesis.map(|(a, b)| (a.to_string(), b.to_string())).unwrap_or_default();
            let rival = c.rival.map(|r| r.to_string()).unwrap_or_default();
            vec![
                c.chapter.clone(),
                c.statement.clone(),
                c.verdict().to_string(),
                c.ours.0.to_string(),
                c.ours.1.to_string(),
                ht,
                ct,
                rival,
                c.note.clone(),
            ]
        })
        .collect();
    let header: Vec<String> = CSV_HEADER.iter().map(|h| h.to_string()).collect();
    crate::io::write_atomic(
        &out.join("claims.csv"),
        crate::io::csv_records(&header, &rows)?.as_bytes(),
    )?;
    Ok(markdown(claims))
}

/// Claims read back from a `claims.csv` (for the combined report of `reproduce`).
pub fn read(path: &std::path::Path) -> anyhow::Result<Vec<Claim>> {
    let mut rd = csv::Reader::from_path(path).with_context(|| format!("{}", path.display()))?;
    let mut out = Vec::new();
    for (n, rec) in rd.records().enumerate() {
        let rec = rec.with_context(|| format!("{}", path.display()))?;
        let num = |k: usize| -> anyhow::Result<usize> {
            rec.get(k).unwrap_or("").parse().map_err(|_| {
                anyhow::anyhow!(
                    "{}: line {}: column {} is not a count",
                    path.display(),
                    n + 2,
                    CSV_HEADER[k]
                )
            })
        };
        let thesis =
            if rec.get(5).unwrap_or("").is_empty() { None } else { Some((num(5)?, num(6)?)) };
        let rival = if rec.get(7).unwrap_or("").is_empty() { None } else { Some(num(7)?) };
        out.push(Claim {
            chapter: rec.get(0).unwrap_or("").into(),
            statement: rec.get(1).unwrap_or("").into(),
            ours: (num(3)?, num(4)?),
            thesis,
            rival,
            note: rec.get(8).unwrap_or("").into(),
        });
    }
    Ok(out)
}

/// Markdown table of claims.
pub fn markdown(claims: &[Claim]) -> String {
    let mut s = String::from("| chapter | claim | verdict here | here | source's own figures (thesis or paper) | note |\n|---|---|---|---|---|---|\n");
    for c in claims {
        let thesis = c.thesis.map(|(a, b)| format!("{a}/{b}")).unwrap_or_else(|| "-".into());
        let rival = c.rival.map(|r| format!(" (best rival {r})")).unwrap_or_default();
        let _ = writeln!(
            s,
            "| {} | {} | **{}** | {}/{}{rival} | {} | {} |",
            c.chapter,
            c.statement,
            c.verdict(),
            c.ours.0,
            c.ours.1,
            thesis,
            c.note
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn claims_round_trip_through_csv_with_verdicts() {
        let dir = tempfile::tempdir().unwrap();
        let claims = vec![
            Claim {
                chapter: "4".into(),
                statement: "DNSOM has the lowest TE, \"always\"".into(),
                ours: (10, 15),
                thesis: Some((15, 15)),
                rival: None,
                note: "a, b".into(),
            },
            Claim {
                chapter: "6".into(),
                statement: "x".into(),
                ours: (3, 3),
                thesis: None,
                rival: None,
                note: String::new(),
            },
            Claim {
                chapter: "5".into(),
                statement: "exponential is the best".into(),
                ours: (12, 35),
                thesis: Some((14, 35)),
                rival: Some(13),
                note: "wins".into(),
            },
        ];
        let md = write(dir.path(), &claims).unwrap();
        assert!(md.contains("**mostly holds**") && md.contains("**holds**"));
        let back = read(&dir.path().join("claims.csv")).unwrap();
        assert_eq!(back.len(), 3);
        // A best-of-several claim counts cells like the thesis and is judged against its rival.
        assert_eq!(
            (back[2].ours, back[2].rival, back[2].verdict()),
            ((12, 35), Some(13), "does not hold")
        );
        assert_eq!(Claim { rival: Some(11), ..back[2].clone() }.verdict(), "holds");
        assert_eq!(Claim { rival: Some(12), ..back[2].clone() }.verdict(), "tied");
        // The count of claims that hold follows the verdict for both kinds.
        assert!(Claim { rival: Some(11), ..back[2].clone() }.holds() && !back[2].holds());
        assert!(back[1].holds() && !back[0].holds());
        assert_eq!(
            (back[0].statement.as_str(), back[0].ours, back[0].thesis),
            (claims[0].statement.as_str(), (10, 15), Some((15, 15)))
        );
        assert_eq!((back[1].ours, back[1].thesis), ((3, 3), None));
        assert_eq!(back[0].verdict(), "mostly holds");
    }
}
