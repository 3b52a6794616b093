//! Wavefront OBJ as a point set: the `v x y z [w]` lines are the points (a weight `w` or vertex
//! colours after x y z are ignored); every other line (`vn`, `vt`, `f`, `o`, `g`, ...) and `#`
//! comments are skipped. Non-finite coordinates are refused by line. OBJ has no counts, so the
//! points grow with the lines read, bounded by the file.

use super::DataError;
use crate::geom::Point3;

/// Parse an OBJ file's bytes into its vertex positions.
pub fn parse_obj(bytes: &[u8]) -> Result<Vec<Point3>, DataError> {
    let text = String::from_utf8_lossy(bytes);
    let mut points = Vec::new();
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let mut w = line.split_whitespace();
        if w.next() != Some("v") {
            continue;
        }
        let ctx = format!("line {}", n + 1);
        let vals: Vec<&str> = w.take(3).collect();
        if vals.len() < 3 {
            return Err(DataError::parse(
                ctx,
                format!("a vertex needs `v x y z`, got `{}`", line.trim()),
            ));
        }
        points.push(super::finite_point(&vals, &ctx)?);
    }
    if points.is_empty() {
        return Err(DataError::Invalid("no vertex (`v x y z`) lines".into()));
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertices_only() {
        let t = "# made by hand\nmtllib a.mtl\no quad\nv 0 0 0\nv 1.5 0 0 1.0\nvn 0 0 1\nvt 0.5 0.5\nv 1 1 0 0.2 0.3 0.4\nv\t0 1 -2e-3 # tab\nf 1 2 3 4\nvp 0.1\n";
        let p = parse_obj(t.as_bytes()).unwrap();
        assert_eq!(p, vec![[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, -2e-3]]);
    }

    #[test]
    fn bad_vertices_are_refused_by_line() {
        let e = parse_obj(b"v 0 0 0\nv 1 NaN 0\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("NaN"), "{e}");
        let e = parse_obj(b"v 0 0 0\n\nv 1 2\n").unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("v x y z"), "{e}");
        let e = parse_obj(b"v 0 0 1e999\n").unwrap_err().to_string();
        assert!(e.contains("line 1") && e.contains("1e999"), "{e}");
        let e = parse_obj(b"vn 0 0 1\nf 1 2 3\n").unwrap_err().to_string();
        assert!(e.contains("no vertex"), "{e}");
    }
}
