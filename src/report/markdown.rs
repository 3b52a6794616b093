//! Small Markdown builders shared by the report sections.

use std::fmt::Write;

/// A Markdown table from a header and rows of cells.
pub(crate) fn table(header: &[String], rows: &[Vec<String>]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "| {} |", header.join(" | "));
    let _ = writeln!(s, "|{}", "---|".repeat(header.len()));
    for r in rows {
        let _ = writeln!(s, "| {} |", r.join(" | "));
    }
    s
}

/// A number with `d` decimals, or "-" when absent.
pub(crate) fn num(v: Option<f64>, d: usize) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.d$}"),
        _ => "-".into(),
    }
}

/// "ours (thesis)" for side-by-side cells.
pub(crate) fn beside(ours: Option<f64>, thesis: Option<f64>, d: usize) -> String {
    match thesis {
        Some(_) => format!("{} ({})", num(ours, d), num(thesis, d)),
        None => num(ours, d),
    }
}

/// Median of the finite values (None when there are none).
pub(crate) fn median(values: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) })
}

/// Geometric mean of positive values (None when empty).
pub(crate) fn geometric_mean(values: &[f64]) -> Option<f64> {
    let v: Vec<f64> = values.iter().copied().filter(|x| *x > 0.0 && x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    Some((v.iter().map(|x| x.ln()).sum::<f64>() / v.len() as f64).exp())
}
