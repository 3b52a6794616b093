//! Qualitative claims of the sources, each counted on a run and, where the published tables hold
//! the same cells, on the source's own figures, with one verdict rule for all
//! (docs/statistics.md, "Verdicts"):
//! - an [`Kind::Every`] claim (soundness: surfaces near the data, elitism, the bound never beaten;
//!   and what a source states for every case) holds only in every case checked;
//! - a [`Kind::Most`] claim ("in most cells") holds when the Wilson 95% interval of its share lies
//!   above one half, does not hold when it lies below, and is undecided otherwise;
//! - a [`Kind::Best`] claim ("X is the best of several") is judged the same way on X's cells
//!   against its best rival's (X's share of the cells the two win);
//! - beside the source's count, `agreement` says whether the two shares agree: Newcombe's 95%
//!   interval of their difference holds 0 ("agrees") or not ("differs").

use crate::stats::proportion::{difference, wilson, Z95};
use anyhow::Context;
use std::fmt::Write;

/// How a claim is judged (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Every,
    Most,
    Best,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Every => "every",
            Kind::Most => "most",
            Kind::Best => "best",
        }
    }

    fn parse(s: &str) -> Option<Kind> {
        [Kind::Every, Kind::Most, Kind::Best].into_iter().find(|k| k.name() == s)
    }
}

#[derive(Debug, Clone)]
pub struct Claim {
    /// The spec whose run counted it (filled by [`write`] when empty).
    pub spec: String,
    pub chapter: String,
    /// The grid it was counted on; empty for a claim over every run of the spec.
    pub grid: String,
    pub kind: Kind,
    pub statement: String,
    /// (cases where it holds, cases checked) on this run.
    pub ours: (usize, usize),
    /// The same count on the source's published figures for the same cells, when they hold them
    /// all.
    pub thesis: Option<(usize, usize)>,
    /// For a [`Kind::Best`] claim: the most cases any other option wins here.
    pub rival: Option<usize>,
    pub note: String,
    /// Whether it compares measured time (CPU seconds): its count depends on the machine and its
    /// load, so the readings score leaves it out as it leaves out CPU-second cells.
    pub timing: bool,
}

impl Claim {
    fn new(kind: Kind, chapter: &str, statement: impl Into<String>, ours: (usize, usize)) -> Self {
        Claim {
            spec: String::new(),
            chapter: chapter.into(),
            grid: String::new(),
            kind,
            statement: statement.into(),
            ours,
            thesis: None,
            rival: None,
            note: String::new(),
            timing: false,
        }
    }

    /// A claim that must hold in every case.
    pub fn every(chapter: &str, statement: impl Into<String>, ours: (usize, usize)) -> Self {
        Self::new(Kind::Every, chapter, statement, ours)
    }

    /// A claim that holds in most cases.
    pub fn most(chapter: &str, statement: impl Into<String>, ours: (usize, usize)) -> Self {
        Self::new(Kind::Most, chapter, statement, ours)
    }

    /// "X is the best of several": X wins `ours.0` of `ours.1` cases, its best rival `rival`.
    pub fn best(
        chapter: &str,
        statement: impl Into<String>,
        ours: (usize, usize),
        rival: usize,
    ) -> Self {
        Claim { rival: Some(rival), ..Self::new(Kind::Best, chapter, statement, ours) }
    }

    pub fn on_grid(mut self, grid: impl ToString) -> Self {
        self.grid = grid.to_string();
        self
    }

    /// The source's own count over the same cells; a count over another number of cases (the
    /// source lacks some of this run's cells) is not comparable and is dropped.
    pub fn thesis(mut self, thesis: Option<(usize, usize)>) -> Self {
        self.thesis = thesis.filter(|t| t.1 > 0 && t.1 == self.ours.1);
        self
    }

    pub fn note(mut self, note: impl Into<String>) -> Self {
        self.note = note.into();
        self
    }

    /// Mark the claim as one about measured time ([`Claim::timing`]).
    pub fn timing(mut self) -> Self {
        self.timing = true;
        self
    }

    /// Whether the claim holds here (the verdict "holds").
    pub fn holds(&self) -> bool {
        self.verdict() == "holds"
    }

    /// The (successes, trials) the verdict judges: the cases, or for a best-of-several claim
    /// X's cases against its best rival's.
    fn trials(&self) -> (usize, usize) {
        match (self.kind, self.rival) {
            (Kind::Best, Some(r)) => (self.ours.0, self.ours.0 + r),
            _ => self.ours,
        }
    }

    /// The Wilson 95% interval of the judged share (None for an every-case claim).
    pub fn interval(&self) -> Option<(f64, f64)> {
        let (k, n) = self.trials();
        (self.kind != Kind::Every && n > 0).then(|| wilson(k, n, Z95))
    }

    pub fn verdict(&self) -> &'static str {
        if self.ours.1 == 0 {
            return "not checked";
        }
        match (self.kind, self.interval()) {
            (Kind::Every, _) if self.ours.0 == self.ours.1 => "holds",
            (Kind::Every, _) => "does not hold",
            (_, None) => "undecided",
            (_, Some((lo, _))) if lo > 0.5 => "holds",
            (_, Some((_, hi))) if hi < 0.5 => "does not hold",
            _ => "undecided",
        }
    }

    /// Whether this run's share agrees with the source's ("agrees" / "differs"), or "" without
    /// the source's count.
    pub fn agreement(&self) -> &'static str {
        match self.thesis {
            Some((a, b)) if self.ours.1 > 0 => {
                let (lo, hi) = difference(self.ours.0, self.ours.1, a, b, Z95);
                if lo <= 0.0 && 0.0 <= hi {
                    "agrees"
                } else {
                    "differs"
                }
            }
            _ => "",
        }
    }

    /// Whether this verdict reproduces the source: its share agrees with the source's own count
    /// where the source has one, else the claim (which the source states) holds.
    pub fn reproduces(&self) -> bool {
        match self.agreement() {
            "agrees" => true,
            "differs" => false,
            _ => self.holds(),
        }
    }
}

/// Whether a verdict reproduces the source only under calibration: the plan's does, the one
/// under the as-written readings does not (docs/readings.md, "The as-written readings").
pub(crate) fn calibration_only(plan: &Claim, as_written: &Claim) -> bool {
    plan.reproduces() && !as_written.reproduces()
}

/// The columns of `claims.csv`, which every chapter's report writes (and `reproduce` collects):
/// one row per (spec, grid, claim). `low_95`/`high_95` bound the judged share (empty for an
/// every-case claim); `best_rival_here` is filled for best-of-several claims only; `timing` is
/// `yes` for a claim about measured time.
pub(crate) const CSV_HEADER: [&str; 16] = [
    "spec",
    "chapter",
    "grid",
    "claim",
    "kind",
    "verdict",
    "holds_here",
    "checked_here",
    "low_95",
    "high_95",
    "best_rival_here",
    "holds_thesis",
    "checked_thesis",
    "agreement",
    "note",
    "timing",
];

fn csv_row(c: &Claim) -> Vec<String> {
    let (ht, ct) = c.thesis.map(|(a, b)| (a.to_string(), b.to_string())).unwrap_or_default();
    let (lo, hi) =
        c.interval().map(|(l, h)| (format!("{l:.4}"), format!("{h:.4}"))).unwrap_or_default();
    vec![
        c.spec.clone(),
        c.chapter.clone(),
        c.grid.clone(),
        c.statement.clone(),
        c.kind.name().into(),
        c.verdict().into(),
        c.ours.0.to_string(),
        c.ours.1.to_string(),
        lo,
        hi,
        c.rival.map(|r| r.to_string()).unwrap_or_default(),
        ht,
        ct,
        c.agreement().into(),
        c.note.clone(),
        if c.timing { "yes" } else { "no" }.into(),
    ]
}

/// Write `claims.csv` into `out` (the claims checked in at least one case, each without a spec
/// named taking `spec`) and return their markdown table (`with_spec`: a spec column).
pub(crate) fn write(
    out: &std::path::Path,
    spec: &str,
    claims: &[Claim],
    with_spec: bool,
) -> anyhow::Result<String> {
    let claims: Vec<Claim> = claims
        .iter()
        .filter(|c| c.ours.1 > 0)
        .map(|c| Claim {
            spec: if c.spec.is_empty() { spec.into() } else { c.spec.clone() },
            ..c.clone()
        })
        .collect();
    let rows: Vec<Vec<String>> = claims.iter().map(csv_row).collect();
    let header: Vec<String> = CSV_HEADER.iter().map(|h| h.to_string()).collect();
    crate::io::write_atomic(
        &out.join("claims.csv"),
        crate::io::csv_records(&header, &rows)?.as_bytes(),
    )?;
    Ok(markdown(&claims, with_spec))
}

/// The columns a plan's `claims.csv` adds to [`CSV_HEADER`]: each claim's count and verdict under
/// the as-written readings (empty where the plan did not run them) and whether its verdict
/// reproduces the source only under calibration.
pub(crate) const AS_WRITTEN_HEADER: [&str; 5] = [
    "verdict_as_written",
    "holds_as_written",
    "checked_as_written",
    "agreement_as_written",
    "calibration_only",
];

/// A plan's `claims.csv` in `out` (each claim beside its count under the as-written readings,
/// `None` where they did not run) and its markdown table with an "as written" column.
pub(crate) fn write_plan(
    out: &std::path::Path,
    claims: &[(Claim, Option<Claim>)],
) -> anyhow::Result<String> {
    let rows: Vec<Vec<String>> = claims
        .iter()
        .map(|(c, w)| {
            let mut row = csv_row(c);
            row.extend(match w {
                Some(w) => vec![
                    w.verdict().into(),
                    w.ours.0.to_string(),
                    w.ours.1.to_string(),
                    w.agreement().into(),
                    if calibration_only(c, w) { "yes" } else { "no" }.into(),
                ],
                None => vec![String::new(); AS_WRITTEN_HEADER.len()],
            });
            row
        })
        .collect();
    let header: Vec<String> =
        CSV_HEADER.iter().chain(&AS_WRITTEN_HEADER).map(|h| h.to_string()).collect();
    crate::io::write_atomic(
        &out.join("claims.csv"),
        crate::io::csv_records(&header, &rows)?.as_bytes(),
    )?;
    let plain: Vec<Claim> = claims.iter().map(|(c, _)| c.clone()).collect();
    let beside: Vec<Option<Claim>> = claims.iter().map(|(_, w)| w.clone()).collect();
    Ok(table(&plain, Some(&beside), true))
}

/// Claims read back from a `claims.csv` (for the combined report of `reproduce`).
pub(crate) fn read(path: &std::path::Path) -> anyhow::Result<Vec<Claim>> {
    let mut rd = csv::Reader::from_path(path).with_context(|| format!("{}", path.display()))?;
    let header = rd.headers().with_context(|| format!("{}", path.display()))?.clone();
    if header.iter().ne(CSV_HEADER.iter().copied()) {
        anyhow::bail!(
            "{}: not a claims table of this version (columns {})",
            path.display(),
            CSV_HEADER.join(",")
        );
    }
    let mut out = Vec::new();
    for (n, rec) in rd.records().enumerate() {
        let rec = rec.with_context(|| format!("{}", path.display()))?;
        let at = |k: usize| rec.get(k).unwrap_or("");
        let bad = |k: usize| {
            anyhow::anyhow!(
                "{}: line {}: column {} is not valid",
                path.display(),
                n + 2,
                CSV_HEADER[k]
            )
        };
        let num = |k: usize| -> anyhow::Result<usize> { at(k).parse().map_err(|_| bad(k)) };
        let opt = |k: usize| -> anyhow::Result<Option<usize>> {
            if at(k).is_empty() {
                Ok(None)
            } else {
                num(k).map(Some)
            }
        };
        let thesis = match (opt(11)?, opt(12)?) {
            (Some(a), Some(b)) => Some((a, b)),
            _ => None,
        };
        out.push(Claim {
            spec: at(0).into(),
            chapter: at(1).into(),
            grid: at(2).into(),
            statement: at(3).into(),
            kind: Kind::parse(at(4)).ok_or_else(|| bad(4))?,
            ours: (num(6)?, num(7)?),
            rival: opt(10)?,
            thesis,
            note: at(14).into(),
            timing: match at(15) {
                "yes" => true,
                "no" => false,
                _ => return Err(bad(15)),
            },
        });
    }
    Ok(out)
}

/// The verdict rule in one paragraph, for the reports that show claims.
pub(crate) const RULE: &str = "Verdicts (docs/statistics.md, \"Verdicts\"): a claim of kind *every* (soundness checks, and what a source states for every case) holds only in every case; a claim of kind *most* holds when the Wilson 95% interval of its share lies above 1/2, does not hold when it lies below, and is *undecided* otherwise; a *best*-of-several claim is judged the same way on its cases against its best rival's. *Agreement* with the source's own count (over the same cells) is Newcombe's 95% interval of the difference of the two shares holding 0.";

/// Markdown table of claims, after the rule (empty without claims).
pub(crate) fn markdown(claims: &[Claim], with_spec: bool) -> String {
    table(claims, None, with_spec)
}

/// The claims' markdown table; with `as_written`, a column of each claim's verdict under the
/// as-written readings (bold where it differs from the plan's, "-" where they did not run).
fn table(claims: &[Claim], as_written: Option<&[Option<Claim>]>, with_spec: bool) -> String {
    let mut s = String::new();
    if claims.is_empty() {
        return s;
    }
    let spec_col = if with_spec { "spec | " } else { "" };
    let (aw_col, aw_rule) = if as_written.is_some() { ("as written | ", "---|") } else { ("", "") };
    let _ = writeln!(s, "{RULE}\n\n| {spec_col}chapter | grid | claim | verdict here | {aw_col}here | 95% interval | source's own figures | agreement | note |\n|{}---|---|---|---|{aw_rule}---|---|---|---|---|", if with_spec { "---|" } else { "" });
    for (k, c) in claims.iter().enumerate() {
        let aw = match as_written.map(|w| w[k].as_ref()) {
            None => String::new(),
            Some(None) => "- | ".into(),
            Some(Some(w)) => {
                let text = format!("{} {}/{}", w.verdict(), w.ours.0, w.ours.1);
                let only = if calibration_only(c, w) { " (calibration only)" } else { "" };
                if w.verdict() != c.verdict() {
                    format!("**{text}**{only} | ")
                } else {
                    format!("{text}{only} | ")
                }
            }
        };
        let thesis = c.thesis.map(|(a, b)| format!("{a}/{b}")).unwrap_or_else(|| "-".into());
        let rival = c.rival.map(|r| format!(" (best rival {r})")).unwrap_or_default();
        let interval =
            c.interval().map(|(l, h)| format!("{l:.2}-{h:.2}")).unwrap_or_else(|| "-".into());
        let spec = if with_spec { format!("{} | ", c.spec) } else { String::new() };
        let grid = if c.grid.is_empty() { "all" } else { c.grid.as_str() };
        let _ = writeln!(
            s,
            "| {spec}{} | {grid} | {} | **{}** | {aw}{}/{}{rival} | {interval} | {thesis} | {} | {} |",
            c.chapter,
            c.statement,
            c.verdict(),
            c.ours.0,
            c.ours.1,
            c.agreement(),
            c.note
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plans_claims_show_the_as_written_verdict_and_what_holds_only_under_calibration() {
        let dir = tempfile::tempdir().unwrap();
        let plan = Claim::most("4", "A", (14, 15)).thesis(Some((15, 15)));
        let literal = Claim::most("4", "A", (1, 15)).thesis(Some((15, 15)));
        assert!(plan.reproduces() && !literal.reproduces());
        assert!(calibration_only(&plan, &literal) && !calibration_only(&literal, &plan));
        let bare = Claim::every("6", "B", (3, 3));
        assert!(bare.reproduces() && !Claim::every("6", "B", (2, 3)).reproduces());
        let rows = vec![
            (Claim { spec: "s".into(), ..plan.clone() }, Some(literal)),
            (Claim { spec: "s".into(), ..bare.clone() }, Some(bare)),
            (Claim { spec: "t".into(), ..plan }, None),
        ];
        let md = write_plan(dir.path(), &rows).unwrap();
        assert!(md.contains("| verdict here | as written | here |"), "{md}");
        assert!(md.contains("| **does not hold 1/15** (calibration only) | 14/15 |"), "{md}");
        assert!(md.contains("| holds 3/3 | 3/3 |") && md.contains("| - | 14/15 |"), "{md}");
        let text = std::fs::read_to_string(dir.path().join("claims.csv")).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].ends_with(",note,timing,verdict_as_written,holds_as_written,checked_as_written,agreement_as_written,calibration_only"), "{text}");
        assert!(lines[1].ends_with(",does not hold,1,15,differs,yes"), "{text}");
        assert!(lines[3].ends_with(",,,,,"), "{text}");
    }

    #[test]
    fn one_verdict_rule_for_every_kind() {
        // Every: only 100% holds.
        assert_eq!(Claim::every("5", "near", (280, 280)).verdict(), "holds");
        assert_eq!(Claim::every("5", "near", (279, 280)).verdict(), "does not hold");
        // Most: the Wilson interval against one half (7/10: 0.40-0.89, undecided).
        assert_eq!(Claim::most("6", "x", (7, 10)).verdict(), "undecided");
        assert_eq!(Claim::most("6", "x", (5, 10)).verdict(), "undecided");
        assert_eq!(Claim::most("6", "x", (122, 140)).verdict(), "holds");
        assert_eq!(Claim::most("6", "x", (1, 10)).verdict(), "does not hold");
        assert_eq!(Claim::most("6", "x", (0, 0)).verdict(), "not checked");
        // Best: X's cases against its best rival's (14 against 11 of 35: undecided).
        assert_eq!(Claim::best("5", "x", (14, 35), 11).verdict(), "undecided");
        assert_eq!(Claim::best("5", "x", (30, 35), 5).verdict(), "holds");
        assert_eq!(Claim::best("5", "x", (2, 35), 18).verdict(), "does not hold");
        // Agreement: 10/15 against the thesis' 15/15 differs, 118/140 against 118/140 agrees.
        assert_eq!(Claim::most("4", "x", (10, 15)).thesis(Some((15, 15))).agreement(), "differs");
        assert_eq!(
            Claim::most("5", "x", (118, 140)).thesis(Some((118, 140))).agreement(),
            "agrees"
        );
        assert_eq!(Claim::most("5", "x", (1, 2)).agreement(), "");
    }

    #[test]
    fn claims_round_trip_through_csv_one_row_per_spec_grid_and_claim() {
        let dir = tempfile::tempdir().unwrap();
        let claims = vec![
            Claim::most("4", "DNSOM has the lowest TE, \"always\"", (10, 15))
                .thesis(Some((15, 15)))
                .note("a, b"),
            Claim::every("6", "x", (3, 3)).on_grid("20x20"),
            Claim::best("5", "exponential is the best", (12, 35), 13)
                .on_grid("18x30")
                .thesis(Some((14, 35))),
            Claim::every("6", "never checked", (0, 0)),
        ];
        let md = write(dir.path(), "ch5_same", &claims, false).unwrap();
        assert!(md.contains("**undecided**") && md.contains("**holds**") && md.contains("Wilson"));
        assert!(!md.contains("never checked"), "a claim checked in no case is left out");
        let back = read(&dir.path().join("claims.csv")).unwrap();
        assert_eq!(back.len(), 3);
        assert!(back.iter().all(|c| c.spec == "ch5_same"));
        assert_eq!((back[1].grid.as_str(), back[1].kind), ("20x20", Kind::Every));
        assert_eq!(
            (back[2].ours, back[2].rival, back[2].thesis, back[2].verdict()),
            ((12, 35), Some(13), Some((14, 35)), "undecided")
        );
        assert_eq!(back[0].statement, claims[0].statement);
        assert_eq!((back[0].thesis, back[0].agreement()), (Some((15, 15)), "differs"));
        // A file of another layout is refused by name.
        std::fs::write(dir.path().join("old.csv"), "chapter,claim\n4,x\n").unwrap();
        let e = read(&dir.path().join("old.csv")).unwrap_err().to_string();
        assert!(e.contains("old.csv") && e.contains("not a claims table"), "{e}");
    }
}
