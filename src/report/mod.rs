//! The report toolkit every family writes with: Markdown tables, PNG charts, claims, the
//! published reference tables and drift. It names no family and knows nothing of the engine.

pub mod claims;
pub mod drift;
pub mod html;
pub mod markdown;
pub mod plots;
pub mod reference;
pub mod score;
pub mod views3d;

/// The distinct items in order of first appearance.
pub fn ordered<T: PartialEq + Clone>(items: impl Iterator<Item = T>) -> Vec<T> {
    let mut out = Vec::new();
    for x in items {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}
