//! The thesis' primitive data sets, generated deterministically (SPEC section 1), and the
//! cylinder of seed 004 and the open surfaces of seed 001.

use crate::geom::Point3;
use serde::Deserialize;
use std::collections::HashSet;
use std::f64::consts::PI;

/// Cube: every point of a 36 x 36 lattice (step 1/35) on each face of the unit cube, shared edge
/// and corner points once: 6*36^2 - 12*36 + 8 = 7352 points. Each face is walked quad by quad
/// (rows from the top, corners (a, b+1), (a, b), (a+1, b), (a+1, b+1)), which reproduces the
/// thesis' first points (0,0,1), (0,0,0.97143), (0.02858,0,0.97143), (0.02858,0,1), (0.05715,0,0.97143).
pub(crate) fn cube() -> Vec<Point3> {
    const N: i32 = 35;
    let mut seen = HashSet::new();
    let mut out = Vec::with_capacity(7352);
    // Each face maps lattice (a, b) to integer coordinates (x, y, z); faces y=0 first.
    let faces: [fn(i32, i32) -> [i32; 3]; 6] = [
        |a, b| [a, 0, b],
        |a, b| [a, N, b],
        |a, b| [0, a, b],
        |a, b| [N, a, b],
        |a, b| [a, b, 0],
        |a, b| [a, b, N],
    ];
    for face in faces {
        for b in (0..N).rev() {
            for a in 0..N {
                for (da, db) in [(0, 1), (0, 0), (1, 0), (1, 1)] {
                    let c = face(a + da, b + db);
                    if seen.insert(c) {
                        out.push([
                            c[0] as f64 / N as f64,
                            c[1] as f64 / N as f64,
                            c[2] as f64 / N as f64,
                        ]);
                    }
                }
            }
        }
    }
    out
}

/// Sphere: centre (.5,.5,.5), radius .5: the pole (.5,1,.5), 59 rings at 3-degree polar steps of
/// 120 points at 3-degree azimuth steps (x = .5 - r sin phi, z = .5 - r cos phi), the pole (.5,0,.5):
/// 7082 points; the thesis' first points (0.5, 0.999315, 0.473830), (0.498630, 0.999315, 0.473865).
pub(crate) fn sphere() -> Vec<Point3> {
    let mut out = vec![[0.5, 1.0, 0.5]];
    for k in 1..60 {
        let theta = (3.0 * k as f64).to_radians();
        let (y, r) = (0.5 + 0.5 * theta.cos(), 0.5 * theta.sin());
        for m in 0..120 {
            let phi = (3.0 * m as f64).to_radians();
            out.push([0.5 - r * phi.sin(), y, 0.5 - r * phi.cos()]);
        }
    }
    out.push([0.5, 0.0, 0.5]);
    out
}

/// Points of a surface of revolution about the y axis: the pole, `rings` of (y, r) with `per_ring`
/// points from azimuth 0 (x = .5 + r cos phi, z = .5 - r sin phi), the other pole.
fn revolution(top: f64, rings: &[(f64, f64)], per_ring: usize, bottom: f64) -> Vec<Point3> {
    let mut out = vec![[0.5, top, 0.5]];
    for &(y, r) in rings {
        for m in 0..per_ring {
            let phi = 2.0 * PI * m as f64 / per_ring as f64;
            out.push([0.5 + r * phi.cos(), y, 0.5 - r * phi.sin()]);
        }
    }
    out.push([0.5, bottom, 0.5]);
    out
}

/// The spindle's profile, the radius of ring k at t = k/152 (spec key `som.spindle_profile`; the
/// thesis gives only the point count and, in Table 3.1, the first points, Section 3.2.2).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpindleProfile {
    /// r = .5 sin(pi t)^2.
    Sin2,
    /// r = .5 sin(pi t): Table 3.1's rounded pole; Appendix B's QE (docs/readings.md).
    #[default]
    Sin,
    /// r = .5 (1 - |1 - 2t|): a double cone in t.
    Cone,
}

/// Where the spindle's rings sit along its axis (spec key `som.spindle_rings`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpindleRings {
    /// y = .5 + .5 cos(pi t), as the sphere's rings (with `sin` the spindle is the sphere).
    #[default]
    Cos,
    /// y = 1 - t: evenly spaced along the axis (with `sin` a lemon, with `cone` a double cone).
    Uniform,
}

impl SpindleProfile {
    pub const NAMES: [&'static str; 3] = ["sin2", "sin", "cone"];

    fn radius(self, t: f64) -> f64 {
        match self {
            SpindleProfile::Sin2 => 0.5 * (PI * t).sin().powi(2),
            SpindleProfile::Sin => 0.5 * (PI * t).sin(),
            SpindleProfile::Cone => 0.5 * (1.0 - (1.0 - 2.0 * t).abs()),
        }
    }
}

impl SpindleRings {
    pub const NAMES: [&'static str; 2] = ["cos", "uniform"];

    fn height(self, t: f64) -> f64 {
        match self {
            SpindleRings::Cos => 0.5 + 0.5 * (PI * t).cos(),
            SpindleRings::Uniform => 1.0 - t,
        }
    }
}

/// Spindle: 151 rings k = 1..151 at t = k/152, y = .5 + .5 cos(pi t), radius .5 sin(pi t)^2, 50
/// points a ring (7.2-degree steps), plus both poles: 7552 points. (The thesis' exact profile is
/// unknown; counts and ring layout match, its first points do not.)
#[cfg(test)]
pub(crate) fn spindle() -> Vec<Point3> {
    spindle_with(SpindleProfile::default(), SpindleRings::default())
}

/// [`spindle`] with another profile or ring placement (the same 151 rings of 50 points).
pub(crate) fn spindle_with(profile: SpindleProfile, rings: SpindleRings) -> Vec<Point3> {
    let rings: Vec<(f64, f64)> = (1..=151)
        .map(|k| {
            let t = k as f64 / 152.0;
            (rings.height(t), profile.radius(t))
        })
        .collect();
    revolution(1.0, &rings, 50, 0.0)
}

/// Cylinder length of the oil tank: chosen so that, after normalisation, the first dome ring lies
/// at y = 0.999462 as in the thesis' Table 3.1.
pub(crate) const OILTANK_CYLINDER_LENGTH: f64 = 0.611;

/// Oil tank: a capsule of a cylinder of radius .5 and two spherical-cap domes of sphere radius .78;
/// each dome has 19 rings at polar angles k asin(.5/.78)/19, k = 1..19; 61 cylinder rings evenly
/// spaced strictly between the two dome-edge rings; 60 points a ring (6-degree steps); plus both
/// poles: 99*60 + 2 = 5942 points.
pub(crate) fn oiltank() -> Vec<Point3> {
    const R: f64 = 0.78;
    let edge = (0.5 / R).asin();
    let cap = R * (1.0 - edge.cos());
    let half = OILTANK_CYLINDER_LENGTH / 2.0;
    let top = half + cap;
    let mut rings = Vec::new();
    for k in 1..=19 {
        let a = k as f64 * edge / 19.0;
        rings.push((top - R * (1.0 - a.cos()), R * a.sin()));
    }
    for k in 1..=61 {
        rings.push((half - OILTANK_CYLINDER_LENGTH * k as f64 / 62.0, 0.5));
    }
    for k in (1..=19).rev() {
        let a = k as f64 * edge / 19.0;
        rings.push((-top + R * (1.0 - a.cos()), R * a.sin()));
    }
    let mut pts = revolution(top, &rings, 60, -top);
    super::normalise_min_max(&mut pts);
    pts
}

/// Cylinder of seed 004: radius 5, height 5, 51 rings z = 0, 0.1, ..., 5 of 76 points: 3876 points.
pub(crate) fn cylinder() -> Vec<Point3> {
    let mut out = Vec::with_capacity(51 * 76);
    for k in 0..=50 {
        let z = k as f64 * 0.1;
        for m in 0..76 {
            let phi = 2.0 * PI * m as f64 / 76.0;
            out.push([5.0 * phi.cos(), 5.0 * phi.sin(), z]);
        }
    }
    out
}

/// Upper unit hemisphere (open surface, seed 001): the pole and 30 rings at 3-degree polar steps
/// down to the equator, 120 points a ring: 3601 points.
pub(crate) fn semi_sphere() -> Vec<Point3> {
    let mut out = vec![[0.0, 0.0, 1.0]];
    for k in 1..=30 {
        let theta = (3.0 * k as f64).to_radians();
        for m in 0..120 {
            let phi = (3.0 * m as f64).to_radians();
            out.push([theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]);
        }
    }
    out
}

/// Saddle z = x^2 - y^2 on a 60 x 60 lattice over [-1, 1]^2 (open surface, seed 001): 3600 points.
pub(crate) fn saddle() -> Vec<Point3> {
    let mut out = Vec::with_capacity(3600);
    for i in 0..60 {
        for j in 0..60 {
            let (x, y) = (-1.0 + 2.0 * i as f64 / 59.0, -1.0 + 2.0 * j as f64 / 59.0);
            out.push([x, y, x * x - y * y]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Point3, b: Point3, tol: f64) -> bool {
        (0..3).all(|k| (a[k] - b[k]).abs() <= tol)
    }

    #[test]
    fn counts() {
        assert_eq!(cube().len(), 7352);
        assert_eq!(sphere().len(), 7082);
        assert_eq!(spindle().len(), 7552);
        assert_eq!(oiltank().len(), 5942);
        assert_eq!(cylinder().len(), 3876);
        assert_eq!(semi_sphere().len(), 3601);
        assert_eq!(saddle().len(), 3600);
    }

    #[test]
    fn spindle_readings_lie_on_their_closed_form_profiles() {
        let radius = |p: Point3| ((p[0] - 0.5).powi(2) + (p[2] - 0.5).powi(2)).sqrt();
        let all = |profile, rings| spindle_with(profile, rings);
        // sin2 on cosine rings: the parabola r = 2 y (1 - y) (sin^2 = 1 - cos^2, y = .5 + .5 cos).
        for p in all(SpindleProfile::Sin2, SpindleRings::Cos) {
            assert!((radius(p) - 2.0 * p[1] * (1.0 - p[1])).abs() < 1e-12, "{p:?}");
        }
        // The default, sin on cosine rings: the sphere of radius .5 about (.5, .5, .5).
        assert_eq!(spindle(), all(SpindleProfile::Sin, SpindleRings::Cos));
        for p in spindle() {
            assert!((radius(p).hypot(p[1] - 0.5) - 0.5).abs() < 1e-12, "{p:?}");
        }
        // cone on uniform rings: the double cone r + |y - .5| = .5.
        for p in all(SpindleProfile::Cone, SpindleRings::Uniform) {
            assert!((radius(p) + (p[1] - 0.5).abs() - 0.5).abs() < 1e-12, "{p:?}");
        }
        // sin on uniform rings: the lemon r = .5 sin(pi (1 - y)).
        for p in all(SpindleProfile::Sin, SpindleRings::Uniform) {
            assert!((radius(p) - 0.5 * (PI * (1.0 - p[1])).sin()).abs() < 1e-12, "{p:?}");
        }
        for profile in [SpindleProfile::Sin2, SpindleProfile::Sin, SpindleProfile::Cone] {
            for rings in [SpindleRings::Cos, SpindleRings::Uniform] {
                let pts = all(profile, rings);
                assert_eq!(pts.len(), 7552);
                // Widest ring (t = 76/152 = 1/2) of radius .5: x spans [0, 1] before normalising.
                assert!(pts.iter().any(|p| (p[0] - 1.0).abs() < 1e-12), "{profile:?} {rings:?}");
            }
        }
    }

    #[test]
    fn thesis_first_points_table_3_1() {
        let c = cube();
        let want = [
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 0.971430],
            [0.028580, 0.0, 0.971430],
            [0.028580, 0.0, 1.0],
            [0.057150, 0.0, 0.971430],
        ];
        for (k, w) in want.iter().enumerate() {
            assert!(close(c[k], *w, 2e-5), "cube point {k}: {:?}", c[k]);
        }
        let s = sphere();
        let want = [
            [0.5, 1.0, 0.5],
            [0.5, 0.999315, 0.473830],
            [0.498630, 0.999315, 0.473865],
            [0.497265, 0.999315, 0.473975],
            [0.495905, 0.999315, 0.474155],
        ];
        for (k, w) in want.iter().enumerate() {
            assert!(close(s[k], *w, 5e-6), "sphere point {k}: {:?}", s[k]);
        }
        let o = oiltank();
        assert!(close(o[0], [0.5, 1.0, 0.5], 1e-12));
        assert!((o[1][1] - 0.999462).abs() < 2e-6, "oiltank first ring y {}", o[1][1]);
    }

    #[test]
    fn primitives_lie_in_the_unit_cube_with_no_duplicates() {
        for (name, pts) in
            [("cube", cube()), ("sphere", sphere()), ("spindle", spindle()), ("oiltank", oiltank())]
        {
            let (lo, hi) = crate::geom::bounding_box(&pts).unwrap();
            for a in 0..3 {
                assert!(
                    lo[a] >= -1e-12 && hi[a] <= 1.0 + 1e-12 && hi[a] - lo[a] > 0.99,
                    "{name} axis {a}: {lo:?} {hi:?}"
                );
            }
            let keys: HashSet<[i64; 3]> =
                pts.iter().map(|p| p.map(|v| (v * 1e9).round() as i64)).collect();
            assert_eq!(keys.len(), pts.len(), "{name} has duplicate points");
        }
    }

    #[test]
    fn sphere_and_cylinder_points_on_their_surfaces() {
        for p in sphere() {
            assert!((crate::geom::dist(p, [0.5; 3]) - 0.5).abs() < 1e-12);
        }
        for p in cylinder() {
            assert!(((p[0] * p[0] + p[1] * p[1]).sqrt() - 5.0).abs() < 1e-12);
        }
    }
}
