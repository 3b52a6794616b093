//! 3-D points as plain `[f64; 3]` arrays: the one geometric type shared by every module.

/// A point (or vector) in 3-D space.
pub type Point3 = [f64; 3];

/// `offset + scale * p`, per axis: a data set's normalisation undone (its frame).
#[inline]
pub(crate) fn affine(offset: Point3, scale: Point3, p: Point3) -> Point3 {
    [0, 1, 2].map(|a| offset[a] + scale[a] * p[a])
}

#[inline]
pub(crate) fn sub(a: Point3, b: Point3) -> Point3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn add(a: Point3, b: Point3) -> Point3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline]
pub(crate) fn scale(a: Point3, s: f64) -> Point3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
pub(crate) fn dot(a: Point3, b: Point3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn cross(a: Point3, b: Point3) -> Point3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

#[inline]
pub(crate) fn norm(a: Point3) -> f64 {
    dot(a, a).sqrt()
}

/// Squared Euclidean distance.
#[inline]
pub(crate) fn dist2(a: Point3, b: Point3) -> f64 {
    let d = sub(a, b);
    dot(d, d)
}

/// Euclidean distance.
#[inline]
pub(crate) fn dist(a: Point3, b: Point3) -> f64 {
    dist2(a, b).sqrt()
}

/// Per-axis minimum and maximum of a point set (None when empty).
pub(crate) fn bounding_box(points: &[Point3]) -> Option<(Point3, Point3)> {
    let first = *points.first()?;
    let mut lo = first;
    let mut hi = first;
    for p in points {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    Some((lo, hi))
}
