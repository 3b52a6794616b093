//! Qualitative claims of the thesis, each checked on the thesis' own published numbers and on a
//! reproduction's, with the counts behind the verdict.

use std::fmt::Write;

#[derive(Debug, Clone)]
pub struct Claim {
    pub chapter: String,
    pub statement: String,
    /// (cases where it holds, cases checked) on the reproduction.
    pub ours: (usize, usize),
    /// The same count on the thesis' published figures, when they allow it.
    pub thesis: Option<(usize, usize)>,
    pub note: String,
}

impl Claim {
    pub fn holds(&self) -> bool {
        self.ours.1 > 0 && self.ours.0 == self.ours.1
    }

    pub fn verdict(&self) -> &'static str {
        match self.ours {
            (_, 0) => "not checked",
            (a, b) if a == b => "holds",
            (a, b) if 2 * a > b => "mostly holds",
            _ => "does not hold",
        }
    }
}

/// Markdown table of claims.
pub fn markdown(claims: &[Claim]) -> String {
    let mut s = String::from("| chapter | claim | verdict here | here | thesis' own figures | note |\n|---|---|---|---|---|---|\n");
    for c in claims {
        let thesis = c.thesis.map(|(a, b)| format!("{a}/{b}")).unwrap_or_else(|| "-".into());
        let _ = writeln!(s, "| {} | {} | **{}** | {}/{} | {} | {} |", c.chapter, c.statement, c.verdict(), c.ours.0, c.ours.1, thesis, c.note);
    }
    s
}
