//! The cylinder data of seed 004 (Chaurasiya & Agarwal 2013, section II.A) and its pre-processing.
//!
//! The paper divides space into a 0.1 x 0.1 x 0.1 grid, puts every grid point into the surface
//! equation and keeps the points "for which the function value is zero or less than a specified
//! accuracy" on the curved face: 3876 points for radius 5, height 5 and accuracy 0.1. Read here as
//! |x^2 + y^2 - r^2| <= accuracy on the lattice (i step, j step, k step) with 0 <= z <= height:
//! on a 0.1 lattice that is |i^2 + j^2 - 2500| <= 10, which holds for exactly 76 (x, y) per level
//! (no lattice point has |x^2 + y^2 - 25| in (0.09, 0.12)), times 51 levels z = 0, 0.1, ..., 5:
//! exactly the paper's 3876. The radial distance of these points to the cylinder is up to
//! accuracy / (2 r) = 0.01 (RMS about 0.006), a floor under any fit's RMS error.
//! Pre-processing (the paper's sorting): rings by height, each in increasing angle atan2(y, x) in
//! [0, 2 pi).

use crate::geom::Point3;

/// Ring-organised data: rings bottom to top, each in angular order (see [`sort_into_rings`]); the closed fit of `spline::closed` reads it.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RingData {
    pub(crate) rings: Vec<Vec<Point3>>,
}

impl RingData {
    pub(crate) fn n_points(&self) -> usize {
        self.rings.iter().map(|r| r.len()).sum()
    }

    pub(crate) fn points(&self) -> impl Iterator<Item = &Point3> {
        self.rings.iter().flatten()
    }

    /// Eq. 8 on a closed ring: cumulative chord over the perimeter (closing chord included) times
    /// `n_around`, so u runs over [0, n_around).
    pub(crate) fn ring_parameters(ring: &[Point3], n_around: usize) -> Vec<f64> {
        let m = ring.len();
        let chord = |a: usize, b: usize| crate::geom::dist(ring[a], ring[b]);
        let total: f64 = (0..m).map(|g| chord(g, (g + 1) % m)).sum();
        let mut acc = 0.0;
        let mut out = Vec::with_capacity(m);
        for g in 0..m {
            if g > 0 {
                acc += chord(g - 1, g);
            }
            out.push(if total > 0.0 { acc / total * n_around as f64 } else { 0.0 });
        }
        out
    }

    /// Eq. 8 along the rings (chords between ring centroids), in [0, 1].
    pub(crate) fn row_parameters(&self) -> Vec<f64> {
        let centroid = |r: &[Point3]| {
            let n = r.len().max(1) as f64;
            let s = r.iter().fold([0.0; 3], |a, p| crate::geom::add(a, *p));
            crate::geom::scale(s, 1.0 / n)
        };
        let c: Vec<Point3> = self.rings.iter().map(|r| centroid(r)).collect();
        let mut acc = vec![0.0];
        for k in 1..c.len() {
            acc.push(acc[k - 1] + crate::geom::dist(c[k - 1], c[k]));
        }
        let total = *acc.last().unwrap_or(&0.0);
        acc.iter().map(|a| if total > 0.0 { a / total } else { 0.0 }).collect()
    }
}

/// Lattice points of step `step` with |x^2 + y^2 - radius^2| <= accuracy and 0 <= z <= height,
/// level by level from z = 0, each level in lattice order (x, then y). Integer lattice indices
/// keep the test exact up to rounding of the inputs.
pub(crate) fn lattice_cylinder(radius: f64, height: f64, step: f64, accuracy: f64) -> Vec<Point3> {
    let reach = ((radius + accuracy.sqrt() + step) / step).ceil() as i64;
    let levels = (height / step + 1e-9).floor() as i64;
    let mut ring = Vec::new();
    for i in -reach..=reach {
        for j in -reach..=reach {
            let (x, y) = (i as f64 * step, j as f64 * step);
            if (x * x + y * y - radius * radius).abs() <= accuracy * (1.0 + 1e-12) {
                ring.push((x, y));
            }
        }
    }
    (0..=levels).flat_map(|k| ring.iter().map(move |&(x, y)| [x, y, k as f64 * step])).collect()
}

/// Sort points into rings of equal height (heights equal to within `tol`), bottom to top, each
/// ring in increasing angle about the z axis (from the positive x axis, in [0, 2 pi)).
pub(crate) fn sort_into_rings(points: &[Point3], tol: f64) -> RingData {
    let mut pts = points.to_vec();
    pts.sort_by(|a, b| a[2].total_cmp(&b[2]));
    let mut rings: Vec<Vec<Point3>> = Vec::new();
    for p in pts {
        match rings.last_mut() {
            Some(r) if (p[2] - r[0][2]).abs() <= tol => r.push(p),
            _ => rings.push(vec![p]),
        }
    }
    let angle = |p: &Point3| p[1].atan2(p[0]).rem_euclid(2.0 * std::f64::consts::PI);
    for r in &mut rings {
        r.sort_by(|a, b| angle(a).total_cmp(&angle(b)));
    }
    RingData { rings }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_rule_gives_exactly_3876_points() {
        let pts = lattice_cylinder(5.0, 5.0, 0.1, 0.1);
        assert_eq!(pts.len(), 3876);
        let data = sort_into_rings(&pts, 1e-6);
        assert_eq!(data.rings.len(), 51);
        assert!(data.rings.iter().all(|r| r.len() == 76));
        // Within 0.01 of the radius, and nothing changes between accuracy 0.09 and 0.11.
        for p in &pts {
            assert!(((p[0] * p[0] + p[1] * p[1]).sqrt() - 5.0).abs() <= 0.0101);
        }
        assert_eq!(lattice_cylinder(5.0, 5.0, 0.1, 0.09).len(), 3876);
        assert_eq!(lattice_cylinder(5.0, 5.0, 0.1, 0.11).len(), 3876);
        assert_eq!(lattice_cylinder(5.0, 5.0, 0.1, 0.05).len(), 52 * 51);
    }

    #[test]
    fn rings_are_in_angular_order_and_heights_ascend() {
        let data = sort_into_rings(&lattice_cylinder(5.0, 5.0, 0.1, 0.1), 1e-6);
        for (k, r) in data.rings.iter().enumerate() {
            assert!(r.iter().all(|p| (p[2] - k as f64 * 0.1).abs() < 1e-9));
            let a: Vec<f64> =
                r.iter().map(|p| p[1].atan2(p[0]).rem_euclid(2.0 * std::f64::consts::PI)).collect();
            assert!(a.windows(2).all(|w| w[0] < w[1]), "ring {k}");
        }
        assert_eq!(data.rings[0][0], [5.0, 0.0, 0.0]);
    }
}
