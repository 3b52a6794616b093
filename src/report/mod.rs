//! The report toolkit every family writes with: Markdown tables, PNG charts, claims, the
//! published reference tables and drift. It names no family and knows nothing of the engine.

pub(crate) mod claims;
pub(crate) mod drift;
pub(crate) mod html;
pub(crate) mod markdown;
pub(crate) mod plots;
pub(crate) mod reference;
pub(crate) mod score;
pub(crate) mod views3d;
pub use html::{PLOTLY_JS, PLOTLY_PATH};
pub use reference::lookup;

/// The distinct items in order of first appearance.
pub(crate) fn ordered<T: PartialEq + Clone>(items: impl Iterator<Item = T>) -> Vec<T> {
    let mut out = Vec::new();
    for x in items {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}

/// Say that a picture could not be drawn (a report goes on without it), through
/// [`crate::notice`].
pub(crate) fn picture_skipped(err: &dyn std::fmt::Display) {
    crate::notice::emit(&format!("somnurbs: warning: picture skipped: {err}"));
}
