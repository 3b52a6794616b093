//! OFF point sets (Geomview/Princeton Object File Format, as CGAL and the Princeton Shape
//! Benchmark write it): an `OFF` line (or `COFF`, `NOFF`, `CNOFF`, `STOFF`, ...; optional), the
//! counts `nv nf [ne]` (on the keyword's line or the next), then `nv` vertex lines `x y z` whose
//! further values (normals, colours, texture coordinates) are ignored. Faces are not read. `#`
//! starts a comment; blank lines are skipped. The vertex count is checked against the bytes the
//! file has left before anything is allocated; non-finite coordinates are refused by line.

use super::DataError;
use crate::geom::Point3;

/// The fewest bytes a vertex line can take: `0 0 0` and its newline.
const MIN_VERTEX_BYTES: usize = 6;

/// The keyword of the first line, if it is one: `[ST][C][N][4][n]OFF` (the 4 and n variants,
/// homogeneous and n-dimensional vertices, and `BINARY` files are refused).
fn keyword(word: &str, ctx: &str) -> Result<bool, DataError> {
    let Some(prefix) = word.strip_suffix("OFF") else { return Ok(false) };
    let mut rest = prefix.strip_prefix("ST").unwrap_or(prefix);
    rest = rest.strip_prefix('C').unwrap_or(rest);
    rest = rest.strip_prefix('N').unwrap_or(rest);
    if rest.contains('4') || rest.contains('n') {
        return Err(DataError::parse(
            ctx,
            format!("`{word}`: only 3-D vertices are read (OFF, COFF, NOFF, CNOFF, STOFF)"),
        ));
    }
    if !rest.is_empty() {
        return Err(DataError::parse(ctx, format!("`{word}` is not an OFF keyword")));
    }
    Ok(true)
}

/// Parse an OFF file's bytes into its vertices.
pub fn parse_off(bytes: &[u8]) -> Result<Vec<Point3>, DataError> {
    let text = String::from_utf8_lossy(bytes);
    // Each line's number, its text without comment, and the bytes after it.
    let mut lines = text
        .split_inclusive('\n')
        .scan(0usize, |end, l| {
            *end += l.len();
            Some((l, *end))
        })
        .enumerate()
        .map(|(n, (l, end))| (n + 1, l.split('#').next().unwrap_or("").trim(), end))
        .filter(|(_, l, _)| !l.is_empty());
    let (first_n, first, first_end) =
        lines.next().ok_or_else(|| DataError::parse("line 1", "empty file (no OFF header)"))?;
    let first_words: Vec<&str> = first.split_whitespace().collect();
    let ctx = format!("line {first_n}");
    let (count_n, counts, count_end) = if keyword(first_words[0], &ctx)? {
        if first_words.get(1) == Some(&"BINARY") {
            return Err(DataError::parse(ctx, "binary OFF is not read (write it as text)"));
        }
        if first_words.len() > 1 {
            (first_n, first_words[1..].to_vec(), first_end)
        } else {
            let (n, l, end) = lines.next().ok_or_else(|| {
                DataError::parse(ctx, "the file ends before the counts line `nv nf ne`")
            })?;
            (n, l.split_whitespace().collect(), end)
        }
    } else {
        (first_n, first_words, first_end)
    };
    let ctx = format!("line {count_n}");
    if !(2..=3).contains(&counts.len()) {
        return Err(DataError::parse(
            ctx,
            format!("expected the counts `nv nf ne`, got `{}`", counts.join(" ")),
        ));
    }
    let nv: usize = counts[0].parse().map_err(|_| {
        DataError::parse(ctx.clone(), format!("`{}` is not a vertex count", counts[0]))
    })?;
    for c in &counts[1..] {
        c.parse::<usize>().map_err(|_| {
            DataError::parse(ctx.clone(), format!("`{c}` is not a face or edge count"))
        })?;
    }
    let left = bytes.len().saturating_sub(count_end);
    if nv.checked_mul(MIN_VERTEX_BYTES).is_none_or(|need| need > left) {
        return Err(DataError::parse(
            ctx,
            format!("the header says {nv} vertices, more than the {left} bytes after it can hold"),
        ));
    }
    let mut points = Vec::with_capacity(nv);
    for k in 0..nv {
        let (n, line, _) = lines.next().ok_or_else(|| {
            DataError::parse(
                format!("vertex {}", k + 1),
                format!("the file ends after {k} of the {nv} vertices"),
            )
        })?;
        let ctx = format!("line {n}");
        let w: Vec<&str> = line.split_whitespace().collect();
        if w.len() < 3 {
            return Err(DataError::parse(ctx, format!("a vertex needs x y z, got `{line}`")));
        }
        points.push(super::finite_point(&w, &ctx)?);
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CUBE: &str = "OFF\n# a unit cube\n\n8 6 12\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1 # last\n4 0 1 2 3\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6\n4 0 3 7 4\n4 1 2 6 5\n";

    #[test]
    fn vertices_of_off_coff_and_noff() {
        let p = parse_off(CUBE.as_bytes()).unwrap();
        assert_eq!(p.len(), 8);
        assert_eq!((p[1], p[7]), ([1.0, 0.0, 0.0], [0.0, 1.0, 1.0]));
        let coff =
            "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0.5 0 0 255 255\n3 0 1 2\n";
        assert_eq!(parse_off(coff.as_bytes()).unwrap()[2], [0.0, 1.0, 0.5]);
        let noff = "NOFF 3 0 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n";
        assert_eq!(parse_off(noff.as_bytes()).unwrap().len(), 3);
        // No keyword, no face lines, no edge count: still the vertices.
        assert_eq!(parse_off(b"3 0\n0 0 0\n1 0 0\n0 1 0\n").unwrap().len(), 3);
        assert_eq!(
            parse_off(b"CNOFF\r\n1 0 0\r\n2 3 4 0 0 1 9 9 9\r\n").unwrap(),
            vec![[2.0, 3.0, 4.0]]
        );
    }

    #[test]
    fn bad_counts_and_values_are_refused_by_line() {
        let t = std::time::Instant::now();
        let e = parse_off(b"OFF\n# huge\n1000000000000 0 0\n0 0 0\n").unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("1000000000000 vertices"), "{e}");
        let e = parse_off(b"OFF\n99999999999999999999 0 0\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("vertex count"), "{e}");
        let e = parse_off(b"OFF\n18446744073709551615 0 0\n0 0 0\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("bytes"), "{e}");
        assert!(t.elapsed().as_secs() < 1);
        let e = parse_off(b"OFF\n3 1 0\n0.0 0.0 0.0\n1.0 0.0 0.0\n").unwrap_err().to_string();
        assert!(e.contains("vertex 3") && e.contains("2 of the 3"), "{e}");
        let e = parse_off(b"OFF\n3 1\n0 0 0\n1 nan 0\n0 1 0\n").unwrap_err().to_string();
        assert!(e.contains("line 4") && e.contains("nan"), "{e}");
        let e = parse_off(b"OFF\n3 1\n0 0 0\n1 inf 0\n0 1 0\n").unwrap_err().to_string();
        assert!(e.contains("line 4") && e.contains("inf"), "{e}");
        let e = parse_off(b"OFF\n3 1\n0.0 0 0\n1 0\n0.0 1 0\n").unwrap_err().to_string();
        assert!(e.contains("line 4") && e.contains("x y z"), "{e}");
        for (bad, says) in [
            ("4OFF\n1 0 0\n0 0 0 1\n", "3-D"),
            ("OFF BINARY\n", "binary"),
            ("XOFF\n1 0 0\n0 0 0\n", "not an OFF keyword"),
            ("OFF\n1 2 3 4\n0 0 0\n", "counts"),
            ("OFF\n", "counts line"),
            ("", "empty"),
            ("OFF\n1 x 0\n0 0 0\n", "face or edge count"),
        ] {
            let e = parse_off(bad.as_bytes()).unwrap_err().to_string();
            assert!(e.contains(says), "{bad:?}: {e}");
        }
    }
}
