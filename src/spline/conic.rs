//! Seed 002 curves: generated 2-D outlines (shapes drawn from lines and circular arcs, sampled at
//! a stated spacing, in place of the paper's scanned letters), SAM06 corner detection (Sarfraz
//! 2008; L, D, R), chord-length parameters, and the conic (rational quadratic Bezier) segment
//! problem solved by the optimisers: between two consecutive corners the outline is split at its
//! middle data point (the paper's "bi-conic" scheme, Figures 4.7/4.11) and each half is one conic
//! with its end points on the data; the variables are the middle control point b1 and the weight w,
//! the objective the sum of squared distances at the chord-length parameters. Pure: no I/O.

#![allow(clippy::needless_range_loop)] // index loops over 3x3 nets and coordinates read clearer

use super::rational_bezier::conic_point;
use crate::optim::Problem;

pub(crate) type P2 = [f64; 2];

/// Walk a closed path of pieces, sampling one point every `spacing` of arc length.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Piece {
    Line {
        from: P2,
        to: P2,
    },
    /// Arc of a circle: centre, radius, start angle, signed sweep (radians).
    Arc {
        centre: P2,
        radius: f64,
        start: f64,
        sweep: f64,
    },
}

impl Piece {
    fn length(&self) -> f64 {
        match *self {
            Piece::Line { from, to } => {
                ((to[0] - from[0]).powi(2) + (to[1] - from[1]).powi(2)).sqrt()
            }
            Piece::Arc { radius, sweep, .. } => radius * sweep.abs(),
        }
    }
    fn at(&self, s: f64) -> P2 {
        match *self {
            Piece::Line { from, to } => {
                let t = s / self.length();
                [from[0] + t * (to[0] - from[0]), from[1] + t * (to[1] - from[1])]
            }
            Piece::Arc { centre, radius, start, sweep } => {
                let a = start + sweep * s / self.length();
                [centre[0] + radius * a.cos(), centre[1] + radius * a.sin()]
            }
        }
    }
}

/// Sample a closed path at arc-length steps of (about) `spacing`: the total length is divided
/// into round(length / spacing) equal steps; the first point is the start of the first piece.
pub(crate) fn sample_closed(pieces: &[Piece], spacing: f64) -> Vec<P2> {
    let total: f64 = pieces.iter().map(Piece::length).sum();
    let n = (total / spacing).round().max(3.0) as usize;
    let h = total / n as f64;
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let mut s = k as f64 * h;
        let mut idx = 0;
        while idx + 1 < pieces.len() && s > pieces[idx].length() {
            s -= pieces[idx].length();
            idx += 1;
        }
        out.push(pieces[idx].at(s.min(pieces[idx].length())));
    }
    out
}

/// The generated outlines: name, pieces, and the true corner positions.
pub(crate) fn outline(name: &str) -> Option<(Vec<Piece>, Vec<P2>)> {
    let line = |a: P2, b: P2| Piece::Line { from: a, to: b };
    Some(match name {
        // A 60 x 60 square, counter-clockwise from (0,0).
        "square" => {
            let c = [[0.0, 0.0], [60.0, 0.0], [60.0, 60.0], [0.0, 60.0]];
            ((0..4).map(|i| line(c[i], c[(i + 1) % 4])).collect(), c.to_vec())
        }
        // Letter D, 80 high: a stem, two 20-long bars and a half circle of radius 40.
        "letter_d" => {
            let pieces = vec![
                line([0.0, 0.0], [20.0, 0.0]),
                Piece::Arc {
                    centre: [20.0, 40.0],
                    radius: 40.0,
                    start: -std::f64::consts::FRAC_PI_2,
                    sweep: std::f64::consts::PI,
                },
                line([20.0, 80.0], [0.0, 80.0]),
                line([0.0, 80.0], [0.0, 0.0]),
            ];
            (pieces, vec![[0.0, 0.0], [0.0, 80.0]])
        }
        // Letter P-like "bullet": a 100-high stem, and a bowl (half circle of radius 25 between
        // two 15-long bars) on its upper half, joined back to the stem; corners at the foot, the
        // top, the bowl's lower join with the stem and the bottom right of the foot.
        "letter_p" => {
            let pieces = vec![
                line([0.0, 0.0], [20.0, 0.0]),
                line([20.0, 0.0], [20.0, 50.0]),
                line([20.0, 50.0], [35.0, 50.0]),
                Piece::Arc {
                    centre: [35.0, 75.0],
                    radius: 25.0,
                    start: -std::f64::consts::FRAC_PI_2,
                    sweep: std::f64::consts::PI,
                },
                line([35.0, 100.0], [0.0, 100.0]),
                line([0.0, 100.0], [0.0, 0.0]),
            ];
            (pieces, vec![[0.0, 0.0], [20.0, 0.0], [20.0, 50.0], [0.0, 100.0]])
        }
        _ => return None,
    })
}

pub(crate) const OUTLINES: [&str; 3] = ["square", "letter_d", "letter_p"];

/// Perpendicular distance of p from the straight line through a and b.
fn line_distance(p: P2, a: P2, b: P2) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len = (dx * dx + dy * dy).sqrt();
    if len == 0.0 {
        return ((p[0] - a[0]).powi(2) + (p[1] - a[1]).powi(2)).sqrt();
    }
    ((p[0] - a[0]) * dy - (p[1] - a[1]) * dx).abs() / len
}

/// SAM06 corner detection on a closed contour: first pass, for every i the point j strictly
/// between P_i and P_{i+L} (cyclic) farthest from the chord is a candidate when that distance
/// exceeds `d`, keeping its largest distance; second pass, a candidate survives when no other
/// candidate within `r` points on either side has a larger distance (ties: the lower index
/// wins). Returns the corner indices in increasing order.
pub(crate) fn sam06(points: &[P2], l: usize, d: f64, r: usize) -> Vec<usize> {
    let n = points.len();
    if n < 3 || l < 2 {
        return Vec::new();
    }
    let mut dist = vec![f64::NEG_INFINITY; n];
    for i in 0..n {
        let k = (i + l) % n;
        let mut best = (0usize, f64::NEG_INFINITY);
        for s in 1..l {
            let j = (i + s) % n;
            let dj = line_distance(points[j], points[i], points[k]);
            if dj > best.1 {
                best = (j, dj);
            }
        }
        if best.1 > d && best.1 > dist[best.0] {
            dist[best.0] = best.1;
        }
    }
    let cands: Vec<usize> = (0..n).filter(|&j| dist[j] > f64::NEG_INFINITY).collect();
    cands
        .iter()
        .copied()
        .filter(|&j| {
            cands.iter().all(|&q| {
                if q == j {
                    return true;
                }
                let gap = (q + n - j) % n;
                let gap = gap.min(n - gap);
                gap > r || dist[q] < dist[j] || (dist[q] == dist[j] && q > j)
            })
        })
        .collect()
}

/// Chord-length parameters t_0 = 0, t_k = (sum of chords up to k) / total, t_n = 1.
pub(crate) fn chord_length_params(points: &[P2]) -> Vec<f64> {
    let mut t = vec![0.0; points.len()];
    for k in 1..points.len() {
        t[k] = t[k - 1]
            + ((points[k][0] - points[k - 1][0]).powi(2)
                + (points[k][1] - points[k - 1][1]).powi(2))
            .sqrt();
    }
    let total = *t.last().unwrap_or(&0.0);
    if total > 0.0 {
        for v in &mut t {
            *v /= total;
        }
    }
    t
}

/// The pieces of a closed contour between consecutive corners, each split at its middle data
/// point into two runs of points (both ends included). With no corner the contour is cut at
/// point 0.
pub(crate) fn conic_runs(points: &[P2], corners: &[usize]) -> Vec<Vec<P2>> {
    let n = points.len();
    let cuts: Vec<usize> = if corners.is_empty() { vec![0] } else { corners.to_vec() };
    let mut out = Vec::new();
    for (c, &a) in cuts.iter().enumerate() {
        let b = if c + 1 < cuts.len() { cuts[c + 1] } else { cuts[0] + n };
        let seg: Vec<P2> = (a..=b).map(|i| points[i % n]).collect();
        if seg.len() < 5 {
            out.push(seg);
            continue;
        }
        // Middle data point: index len/2 for an odd count (the centre), (len-1)/2 for an even one.
        let mid = (seg.len() - 1) / 2;
        out.push(seg[..=mid].to_vec());
        out.push(seg[mid..].to_vec());
    }
    out
}

/// One conic with fixed ends b0 = first point, b2 = last point; variables (b1x, b1y, w).
pub(crate) struct ConicProblem {
    pub(crate) points: Vec<P2>,
    pub(crate) t: Vec<f64>,
    x0: Vec<f64>,
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl ConicProblem {
    /// Start: w = 1 and b1 the least-squares optimum for w = 1 (closed form, the residual is
    /// linear in b1 for fixed w); box: the run's bounding box widened by `margin` times its larger
    /// side, w in [w_lo, w_hi].
    pub(crate) fn new(points: Vec<P2>, margin: f64, w_lo: f64, w_hi: f64) -> ConicProblem {
        let t = chord_length_params(&points);
        let b1 = Self::best_b1(&points, &t, 1.0);
        let (mut mn, mut mx) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &points {
            for k in 0..2 {
                mn[k] = mn[k].min(p[k]);
                mx[k] = mx[k].max(p[k]);
            }
        }
        let ext = (mx[0] - mn[0]).max(mx[1] - mn[1]).max(1e-9);
        let lo = vec![mn[0] - margin * ext, mn[1] - margin * ext, w_lo];
        let hi = vec![mx[0] + margin * ext, mx[1] + margin * ext, w_hi];
        let x0 =
            vec![b1[0].clamp(lo[0], hi[0]), b1[1].clamp(lo[1], hi[1]), 1.0f64.clamp(w_lo, w_hi)];
        ConicProblem { points, t, x0, lo, hi }
    }

    /// Least-squares b1 for a fixed w: minimise sum |a_k + c_k b1|^2 with
    /// a_k = (B0 b0 + B2 b2)/den - D_k, c_k = w B1 / den.
    pub(crate) fn best_b1(points: &[P2], t: &[f64], w: f64) -> P2 {
        let (b0, b2) = (points[0], points[points.len() - 1]);
        let (mut num, mut den_sum) = ([0.0; 2], 0.0);
        for (p, &tk) in points.iter().zip(t) {
            let bb = super::rational_bezier::bernstein2(tk);
            let den = bb[0] + w * bb[1] + bb[2];
            let c = w * bb[1] / den;
            for k in 0..2 {
                let a = (bb[0] * b0[k] + bb[2] * b2[k]) / den - p[k];
                num[k] -= c * a;
            }
            den_sum += c * c;
        }
        if den_sum == 0.0 {
            return [0.5 * (b0[0] + b2[0]), 0.5 * (b0[1] + b2[1])];
        }
        [num[0] / den_sum, num[1] / den_sum]
    }

    pub(crate) fn control(&self, x: &[f64]) -> ([P2; 3], f64) {
        ([self.points[0], [x[0], x[1]], self.points[self.points.len() - 1]], x[2])
    }
}

impl Problem for ConicProblem {
    fn dim(&self) -> usize {
        3
    }
    fn initial_point(&self) -> &[f64] {
        &self.x0
    }
    fn bounds(&self) -> (&[f64], &[f64]) {
        (&self.lo, &self.hi)
    }
    fn fitness(&self, x: &[f64]) -> f64 {
        let (b, w) = self.control(x);
        self.points
            .iter()
            .zip(&self.t)
            .map(|(p, &t)| {
                let q = conic_point(&b, w, t);
                (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn near(p: P2, q: P2, tol: f64) -> bool {
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt() <= tol
    }

    #[test]
    fn chord_length_matches_the_worked_example() {
        // Section 2.3: D = (0,0), (1,2), (3,4), (4,0) -> 0, 0.2434, 0.5512, 1.
        let t = chord_length_params(&[[0.0, 0.0], [1.0, 2.0], [3.0, 4.0], [4.0, 0.0]]);
        let total = 5f64.sqrt() + 8f64.sqrt() + 17f64.sqrt();
        assert_eq!(t[0], 0.0);
        assert!((t[1] - 5f64.sqrt() / total).abs() < 1e-15 && (t[1] - 0.2434).abs() < 5e-5);
        assert!(
            (t[2] - (5f64.sqrt() + 8f64.sqrt()) / total).abs() < 1e-15
                && (t[2] - 0.5512).abs() < 5e-5
        );
        assert_eq!(t[3], 1.0);
    }

    #[test]
    fn sam06_finds_exactly_the_corners_of_generated_outlines() {
        for name in OUTLINES {
            let (pieces, truth) = outline(name).unwrap();
            let pts = sample_closed(&pieces, 1.0);
            let found = sam06(&pts, 14, 2.6, 14);
            assert_eq!(
                found.len(),
                truth.len(),
                "{name}: found {:?}",
                found.iter().map(|&i| pts[i]).collect::<Vec<_>>()
            );
            for c in &truth {
                assert!(
                    found.iter().any(|&i| near(pts[i], *c, 1.0)),
                    "{name}: corner {c:?} not found"
                );
            }
        }
    }

    #[test]
    fn conic_problem_recovers_an_exact_circular_arc() {
        // Points on a 120-degree arc of radius 10, sampled uniformly in angle: the exact conic is
        // b1 at the tangents' intersection, w = cos(60 deg). With the conic's own parameters the
        // closed-form least-squares b1 at the exact w is the exact b1 (zero residual).
        let theta = std::f64::consts::PI / 3.0;
        let b = [
            [10.0 * theta.cos(), -10.0 * theta.sin()],
            [10.0 / theta.cos(), 0.0],
            [10.0 * theta.cos(), 10.0 * theta.sin()],
        ];
        let ts: Vec<f64> = (0..=40).map(|k| k as f64 / 40.0).collect();
        let pts: Vec<P2> = ts.iter().map(|&t| conic_point(&b, theta.cos(), t)).collect();
        let b1 = ConicProblem::best_b1(&pts, &ts, theta.cos());
        assert!(near(b1, b[1], 1e-10), "{b1:?}");
        let p = ConicProblem::new(pts.clone(), 0.5, 0.01, 10.0);
        let x = [b[1][0], b[1][1], theta.cos()];
        let direct: f64 = pts
            .iter()
            .zip(&p.t)
            .map(|(q, &t)| {
                let r = conic_point(&b, theta.cos(), t);
                (r[0] - q[0]).powi(2) + (r[1] - q[1]).powi(2)
            })
            .sum();
        assert!((p.fitness(&x) - direct).abs() < 1e-12);
    }

    #[test]
    fn straight_runs_fit_exactly_from_the_start() {
        let pts: Vec<P2> = (0..=20).map(|k| [k as f64, 2.0 * k as f64]).collect();
        let p = ConicProblem::new(pts, 0.1, 0.01, 10.0);
        assert!(p.fitness(p.initial_point()) < 1e-20);
    }
}
