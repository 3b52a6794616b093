//! STL reader (ascii and binary) and area-weighted sampling of points on the triangles.

use super::DataError;
use crate::geom::{self, Point3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Parse an STL file into triangles. Binary is recognised by its size (84 + 50 n bytes), since some
/// binary files also begin with the word `solid`.
pub fn parse_stl(bytes: &[u8]) -> Result<Vec<[Point3; 3]>, DataError> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if bytes.len() == 84 + 50 * n {
            let f = |o: usize| {
                f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as f64
            };
            return Ok((0..n)
                .map(|t| {
                    let o = 84 + 50 * t + 12;
                    [0, 1, 2].map(|v| [f(o + 12 * v), f(o + 12 * v + 4), f(o + 12 * v + 8)])
                })
                .collect());
        }
    }
    let text = std::str::from_utf8(bytes).map_err(|_| {
        DataError::parse(
            "STL",
            "neither binary STL (size does not match its triangle count) nor text",
        )
    })?;
    if !text.trim_start().starts_with("solid") {
        return Err(DataError::parse(
            "line 1",
            "not an STL file (no `solid` and the size does not fit binary STL)",
        ));
    }
    let mut tris = Vec::new();
    let mut current: Vec<Point3> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let w: Vec<&str> = line.split_whitespace().collect();
        if w.first() == Some(&"vertex") {
            let ctx = format!("line {}", n + 1);
            let mut v = [0.0; 3];
            for k in 0..3 {
                let s = w
                    .get(k + 1)
                    .ok_or_else(|| DataError::parse(ctx.clone(), "vertex needs three numbers"))?;
                v[k] = s
                    .parse()
                    .map_err(|_| DataError::parse(ctx.clone(), format!("`{s}` is not a number")))?;
            }
            current.push(v);
        } else if w.first() == Some(&"endloop") {
            if current.len() != 3 {
                return Err(DataError::parse(
                    format!("line {}", n + 1),
                    format!("a facet has {} vertices, 3 expected", current.len()),
                ));
            }
            tris.push([current[0], current[1], current[2]]);
            current.clear();
        }
    }
    Ok(tris)
}

fn area(t: &[Point3; 3]) -> f64 {
    0.5 * geom::norm(geom::cross(geom::sub(t[1], t[0]), geom::sub(t[2], t[0])))
}

/// `n` points uniformly distributed over the surface: a triangle is chosen with probability
/// proportional to its area (cumulative areas, binary search), then a uniform point in it
/// (the sqrt trick: P = (1 - sqrt r1) A + sqrt r1 (1 - r2) B + sqrt r1 r2 C). Zero-area triangles
/// are never chosen.
pub fn sample_surface(
    triangles: &[[Point3; 3]],
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<Point3>, DataError> {
    let mut cum = Vec::with_capacity(triangles.len());
    let mut total = 0.0;
    for t in triangles {
        let a = area(t);
        total += if a.is_finite() { a } else { 0.0 };
        cum.push(total);
    }
    if total.is_nan() || total <= 0.0 {
        return Err(DataError::Invalid(
            "the mesh has no triangle of positive area to sample".into(),
        ));
    }
    Ok((0..n)
        .map(|_| {
            let target = rng.gen::<f64>() * total;
            let k = cum.partition_point(|&c| c <= target).min(triangles.len() - 1);
            let t = &triangles[k];
            let (r1, r2): (f64, f64) = (rng.gen(), rng.gen());
            let s = r1.sqrt();
            let (wa, wb, wc) = (1.0 - s, s * (1.0 - r2), s * r2);
            [0, 1, 2].map(|a| wa * t[0][a] + wb * t[1][a] + wc * t[2][a])
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn tris() -> Vec<[Point3; 3]> {
        // Areas 1 and 3 (right triangles in the z = 0 and x = 5 planes).
        vec![
            [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[5.0, 0.0, 0.0], [5.0, 3.0, 0.0], [5.0, 0.0, 2.0]],
        ]
    }

    fn binary(t: &[[Point3; 3]]) -> Vec<u8> {
        let mut b = vec![b's'; 80];
        b.extend((t.len() as u32).to_le_bytes());
        for tri in t {
            b.extend([0u8; 12]);
            for v in tri {
                for c in v {
                    b.extend((*c as f32).to_le_bytes());
                }
            }
            b.extend([0u8; 2]);
        }
        b
    }

    #[test]
    fn ascii_and_binary_agree() {
        let mut a = String::from("solid test\n");
        for t in tris() {
            a.push_str("facet normal 0 0 1\nouter loop\n");
            for v in t {
                a.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
            }
            a.push_str("endloop\nendfacet\n");
        }
        a.push_str("endsolid test\n");
        assert_eq!(parse_stl(a.as_bytes()).unwrap(), tris());
        assert_eq!(parse_stl(&binary(&tris())).unwrap(), tris());
        let e = parse_stl(b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zero\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 4") && e.contains("zero"), "{e}");
    }

    #[test]
    fn sampling_is_area_weighted_and_on_the_triangles() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let pts = sample_surface(&tris(), 20_000, &mut rng).unwrap();
        let second = pts.iter().filter(|p| p[0] > 2.5).count() as f64 / 20_000.0;
        assert!((second - 0.75).abs() < 0.02, "share on the larger triangle {second}");
        for p in &pts {
            if p[0] > 2.5 {
                assert!((p[0] - 5.0).abs() < 1e-12);
                assert!(p[1] >= 0.0 && p[2] >= 0.0 && p[1] / 3.0 + p[2] / 2.0 <= 1.0 + 1e-12);
            } else {
                assert!(
                    p[2] == 0.0 && p[0] >= 0.0 && p[1] >= 0.0 && p[0] / 2.0 + p[1] <= 1.0 + 1e-12
                );
            }
        }
        let degenerate = vec![[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]];
        assert!(sample_surface(&degenerate, 5, &mut rng).is_err());
    }
}
