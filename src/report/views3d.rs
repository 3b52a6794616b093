//! Interactive 3-D views for report.html: a run writes the geometry it wants shown into
//! `views3d.js` in its folder (point sets and surfaces evaluated on a grid), and the HTML page
//! draws them with the vendored plotting library. The file is a script, not JSON, so a page
//! opened from the file system can load it (browsers refuse `fetch` of `file://`).
//!
//! Coordinates are display data (the results are the records and tables): each array is written
//! as 16-bit steps between its least and greatest value, in base64 (`q(...)`, `g(...)` for a
//! surface's rows), which the script expands when the page loads: a step is 1/65534 of the
//! array's extent (about 5 significant digits), in a third of the characters of decimal numbers.
//! A surface's grid is thinned to at most [`MAX_SIDE`] rows and columns (always keeping the first
//! and last).

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

/// The step a value is written at: 0 is the array's least value, [`STEPS`] its greatest.
const STEPS: u16 = 65534;
/// The step written for no value (a break between polylines, or a non-finite value).
const NONE: u16 = u16::MAX;

/// The expansion of `q` and `g` (the page's copy of [`quantised`]'s inverse).
const DECODE_JS: &str = "function q(s, lo, hi) { var b = atob(s), n = b.length >> 1, d = (hi - lo) / 65534, out = new Array(n); for (var i = 0; i < n; i++) { var k = b.charCodeAt(2 * i) | (b.charCodeAt(2 * i + 1) << 8); out[i] = k === 65535 ? null : lo + d * k; } return out; }\nfunction g(s, lo, hi, cols) { var v = q(s, lo, hi), rows = []; for (var i = 0; i < v.length; i += cols) rows.push(v.slice(i, i + cols)); return rows; }\n";

/// `values` as the page's `q` reads them: the base64 of each value's step (little-endian u16) and
/// the least and greatest finite value (0 and 0 when there is none).
fn quantised(values: &[Option<f64>]) -> (String, f64, f64) {
    let finite = || values.iter().flatten().copied().filter(|v| v.is_finite());
    let lo = finite().fold(f64::INFINITY, f64::min);
    let hi = finite().fold(f64::NEG_INFINITY, f64::max);
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (0.0, 0.0) };
    let step = (hi - lo) / f64::from(STEPS);
    let bytes: Vec<u8> = values
        .iter()
        .map(|v| match v {
            Some(v) if v.is_finite() && step > 0.0 => {
                ((v - lo) / step).round().clamp(0.0, f64::from(STEPS)) as u16
            }
            Some(v) if v.is_finite() => 0,
            _ => NONE,
        })
        .flat_map(u16::to_le_bytes)
        .collect();
    (crate::experiment::packed::encode(&bytes), lo, hi)
}

/// A flat array as the script's `q(...)` call.
fn flat(values: &[Option<f64>]) -> String {
    let (text, lo, hi) = quantised(values);
    format!("q(\"{text}\",{lo:?},{hi:?})")
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

fn coords(points: impl Iterator<Item = Point3>, c: usize) -> String {
    flat(&points.map(|p| Some(p[c])).collect::<Vec<_>>())
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
            let lc = |c: usize| flat(&line_pts.iter().map(|p| p.map(|p| p[c])).collect::<Vec<_>>());
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
                let v: Vec<Option<f64>> = ri
                    .iter()
                    .flat_map(|&i| ci.iter().map(move |&j| Some(points[i * cols + j][c])))
                    .collect();
                let (text, lo, hi) = quantised(&v);
                format!("g(\"{text}\",{lo:?},{hi:?},{})", ci.len())
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
    let mut s = String::from("// somnurbs 3-D views (report.html draws them)\n(function () {\n");
    s.push_str(DECODE_JS);
    s.push_str("(window.somnurbsViews = window.somnurbsViews || []).push({folder: document.currentScript ? document.currentScript.getAttribute(\"data-folder\") : \"\", views: [\n");
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
    s.push_str("]});\n})();\n");
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

    /// The values `q` gives back in the page for one `quantised` array (its JavaScript, in Rust).
    fn expanded(text: &str, lo: f64, hi: f64) -> Vec<Option<f64>> {
        let bytes = crate::experiment::packed::decode(text).unwrap();
        let d = (hi - lo) / 65534.0;
        bytes
            .chunks_exact(2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .map(|k| (k != 65535).then(|| lo + d * f64::from(k)))
            .collect()
    }

    #[test]
    fn coordinates_come_back_within_half_a_step_of_the_extent() {
        let values =
            vec![Some(0.990165232195145), None, Some(-12.3456789), Some(3.5), Some(f64::NAN)];
        let (text, lo, hi) = quantised(&values);
        assert_eq!((lo, hi), (-12.3456789, 3.5));
        let back = expanded(&text, lo, hi);
        assert_eq!(back.len(), values.len());
        assert_eq!((back[1], back[4]), (None, None), "breaks and non-finite values stay gaps");
        let half = (hi - lo) / 65534.0 / 2.0;
        for (v, b) in values.iter().zip(&back).filter(|(v, _)| v.is_some_and(f64::is_finite)) {
            assert!((v.unwrap() - b.unwrap()).abs() <= half * 1.000001, "{v:?} -> {b:?}");
        }
        assert_eq!((back[2], back[3]), (Some(lo), Some(hi)), "the ends are exact");
        // One value, or all equal: every step 0, the value itself.
        let (text, lo, hi) = quantised(&[Some(2.5), Some(2.5)]);
        assert_eq!(expanded(&text, lo, hi), vec![Some(2.5), Some(2.5)]);
        // About a third of the characters of 6-digit decimals (9 or more a number with its comma).
        let many: Vec<Option<f64>> = (0..900).map(|k| Some((k as f64 * 0.37).sin())).collect();
        assert!(flat(&many).len() * 3 < 900 * 9, "{}", flat(&many).len());
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
        let x = flat(&[Some(0.0), Some(3.0)]);
        assert_eq!(x, "q(\"AAD+/w==\",0.0,3.0)");
        assert!(
            s.contains(&format!("\"x\":{x},\"y\":q(")) && s.contains(&format!("\"lx\":{x}")),
            "{s}"
        );
        assert!(s.contains("\"z\":g(\"AAAAAAAA/v8=\",0.0,0.5,2)"), "{s}");
        assert!(s.starts_with("// somnurbs 3-D views") && s.ends_with("]});\n})();\n"), "{s}");
    }
}
