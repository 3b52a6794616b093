//! Interactive 3-D views for report.html: a run writes the geometry it wants shown into
//! `views3d.js` in its folder (point sets and surfaces evaluated on a grid), and the HTML page
//! draws them with the vendored plotting library. The file is a script, not JSON, so a page
//! opened from the file system can load it (browsers refuse `fetch` of `file://`).
//!
//! Coordinates are written with 6 significant digits; a surface's grid is thinned to at most
//! [`MAX_SIDE`] rows and columns (always keeping the first and last), which keeps a quick
//! reproduction's folder small.

use crate::geom::Point3;
use crate::io::write_atomic;
use anyhow::Result;
use std::fmt::Write;
use std::path::Path;

/// The file a run writes beside its REPORT.md.
pub(crate) const FILE: &str = "views3d.js";

/// The most rows (or columns) of a surface grid written out.
pub(crate) const MAX_SIDE: usize = 30;

/// A colour as `#rrggbb`.
pub(crate) fn hex(c: plotters::style::RGBColor) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

/// One drawable: a point set (optionally joined into polylines) or a surface on a grid.
#[derive(Debug, Clone)]
pub(crate) enum Trace {
    /// Markers at `points`; each of `lines` (indices into `points`) is drawn as a polyline.
    Points { label: String, colour: String, points: Vec<Point3>, lines: Vec<Vec<usize>> },
    /// A surface through `points`, row-major with `rows` x `cols`.
    Surface { label: String, colour: String, rows: usize, cols: usize, points: Vec<Point3> },
}

/// One view: a title and what it draws.
#[derive(Debug, Clone)]
pub(crate) struct View {
    pub(crate) title: String,
    pub(crate) traces: Vec<Trace>,
}

/// A number with 6 significant digits, as a JavaScript literal (`null` if not finite).
fn num(x: f64) -> String {
    if !x.is_finite() {
        return "null".into();
    }
    let r: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    if r != 0.0 && (r.abs() >= 1e6 || r.abs() < 1e-4) {
        format!("{r:e}")
    } else {
        format!("{r}")
    }
}

fn string(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into())
}

/// Indices 0..n thinned to at most `max`, keeping the first and the last.
pub(crate) fn thin(n: usize, max: usize) -> Vec<usize> {
    if n <= max || max < 2 {
        return (0..n).collect();
    }
    let mut idx: Vec<usize> = (0..max).map(|k| (k * (n - 1) + (max - 1) / 2) / (max - 1)).collect();
    idx.dedup();
    idx
}

/// A row-major `rows x cols` grid thinned to at most `side` rows and columns (first and last
/// kept), for views shown in numbers: (points, rows, cols).
pub(crate) fn coarse(
    points: &[Point3],
    rows: usize,
    cols: usize,
    side: usize,
) -> (Vec<Point3>, usize, usize) {
    let (ri, ci) = (thin(rows, side), thin(cols, side));
    let pts = ri.iter().flat_map(|&i| ci.iter().map(move |&j| points[i * cols + j])).collect();
    (pts, ri.len(), ci.len())
}

fn coords(points: impl Iterator<Item = Point3> + Clone, c: usize) -> String {
    let v: Vec<String> = points.map(|p| num(p[c])).collect();
    format!("[{}]", v.join(","))
}

fn trace_js(t: &Trace) -> String {
    match t {
        Trace::Points { label, colour, points, lines } => {
            // Polylines as one array with null breaks between them.
            let mut line_pts: Vec<Option<Point3>> = Vec::new();
            for l in lines {
                if !line_pts.is_empty() {
                    line_pts.push(None);
                }
                line_pts.extend(l.iter().map(|&i| points.get(i).copied()));
            }
            let lc = |c: usize| {
                format!(
                    "[{}]",
                    line_pts
                        .iter()
                        .map(|p| p.map(|p| num(p[c])).unwrap_or_else(|| "null".into()))
                        .collect::<Vec<_>>()
                        .join(",")
                )
            };
            format!(
                "{{\"kind\":\"points\",\"label\":{},\"colour\":{},\"x\":{},\"y\":{},\"z\":{},\"lx\":{},\"ly\":{},\"lz\":{}}}",
                string(label),
                string(colour),
                coords(points.iter().copied(), 0),
                coords(points.iter().copied(), 1),
                coords(points.iter().copied(), 2),
                lc(0),
                lc(1),
                lc(2)
            )
        }
        Trace::Surface { label, colour, rows, cols, points } => {
            let (ri, ci) = (thin(*rows, MAX_SIDE), thin(*cols, MAX_SIDE));
            let grid = |c: usize| {
                let rows: Vec<String> = ri
                    .iter()
                    .map(|&i| coords(ci.iter().map(|&j| points[i * cols + j]), c))
                    .collect();
                format!("[{}]", rows.join(","))
            };
            format!(
                "{{\"kind\":\"surface\",\"label\":{},\"colour\":{},\"x\":{},\"y\":{},\"z\":{}}}",
                string(label),
                string(colour),
                grid(0),
                grid(1),
                grid(2)
            )
        }
    }
}

/// The script text: it appends this folder's views to `window.somnurbsViews`, tagged with the
/// `data-folder` of the script element that loaded it.
pub(crate) fn script(views: &[View]) -> String {
    let mut s = String::from("// somnurbs 3-D views (report.html draws them)\n(window.somnurbsViews = window.somnurbsViews || []).push({folder: document.currentScript ? document.currentScript.getAttribute(\"data-folder\") : \"\", views: [\n");
    for (k, v) in views.iter().enumerate() {
        let traces: Vec<String> = v.traces.iter().map(trace_js).collect();
        let _ = writeln!(
            s,
            "{{\"title\":{},\"traces\":[{}]}}{}",
            string(&v.title),
            traces.join(","),
            if k + 1 < views.len() { "," } else { "" }
        );
    }
    s.push_str("]});\n");
    s
}

/// Write `views3d.js` into `out` (nothing when there are no views).
pub(crate) fn write(out: &Path, views: &[View]) -> Result<()> {
    if views.is_empty() {
        return Ok(());
    }
    write_atomic(&out.join(FILE), script(views).as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_have_six_significant_digits() {
        assert_eq!(num(0.990165232195145), "0.990165");
        assert_eq!(num(-12.3456789), "-12.3457");
        assert_eq!(num(1.5e9), "1.5e9");
        assert_eq!(num(2.0e-7), "2e-7");
        assert_eq!(num(f64::NAN), "null");
        assert_eq!(num(0.0), "0");
    }

    #[test]
    fn thinning_keeps_the_ends_and_the_limit() {
        assert_eq!(thin(5, 10), vec![0, 1, 2, 3, 4]);
        let t = thin(301, 120);
        assert_eq!(t.len(), 120);
        assert_eq!((t[0], *t.last().unwrap()), (0, 300));
        assert!(t.windows(2).all(|w| w[1] > w[0]));
    }

    #[test]
    fn script_holds_every_trace() {
        let v = View {
            title: "t \"q\"".into(),
            traces: vec![
                Trace::Points {
                    label: "map".into(),
                    colour: "#112233".into(),
                    points: vec![[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]],
                    lines: vec![vec![0, 1]],
                },
                Trace::Surface {
                    label: "s".into(),
                    colour: "#445566".into(),
                    rows: 2,
                    cols: 2,
                    points: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.5]],
                },
            ],
        };
        let s = script(&[v]);
        assert!(s.contains("\"title\":\"t \\\"q\\\"\""), "{s}");
        assert!(s.contains("\"x\":[0,3],\"y\":[1,4],\"z\":[2,5],\"lx\":[0,3]"), "{s}");
        assert!(s.contains("\"z\":[[0,0],[0,0.5]]"), "{s}");
    }
}
