//! Data sets: deterministic generators for the thesis' primitives, loaders for point files
//! (PLY, STL, OFF, OBJ, XYZ/CSV), the thesis' per-axis min-max normalisation and the frame that
//! undoes it. Pure apart from `registry`, the one place that reads files.

pub(crate) mod cylinder;
pub(crate) mod frame;
pub(crate) mod generators;
pub(crate) mod grid_csv;
pub mod obj;
pub mod off;
pub mod ply;
pub(crate) mod registry;
pub mod stl;
pub mod xyz;

use crate::geom::Point3;
pub use registry::{clone_data_dir, load_dataset};
use thiserror::Error;

/// A named point cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCloud {
    pub name: String,
    pub points: Vec<Point3>,
    /// How `points` were normalised from the data's own coordinates.
    pub frame: frame::Frame,
}

/// What can be wrong with data; messages name the file, line or element at fault.
#[derive(Debug, Error)]
pub enum DataError {
    #[error("{path}: data file not found. {hint}")]
    Missing { path: String, hint: String },
    #[error("{path}: {source}")]
    Io { path: String, source: std::io::Error },
    #[error("{context}: {message}")]
    Parse { context: String, message: String },
    #[error("{0}")]
    Invalid(String),
}

/// The point of the first three of `words` (x, y, z), each a finite number; an error names `ctx`
/// (the file's line) and the word at fault.
pub(crate) fn finite_point(words: &[&str], ctx: &str) -> Result<Point3, DataError> {
    let mut p = [0.0; 3];
    for (a, v) in p.iter_mut().enumerate() {
        let w = words.get(a).copied().unwrap_or("");
        *v = w.parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| {
            DataError::parse(ctx.to_string(), format!("`{w}` is not a finite number"))
        })?;
    }
    Ok(p)
}

impl DataError {
    pub fn parse(context: impl Into<String>, message: impl Into<String>) -> DataError {
        DataError::Parse { context: context.into(), message: message.into() }
    }

    /// Prefix the error with the file it came from.
    pub fn in_file(self, path: &str) -> DataError {
        match self {
            DataError::Parse { context, message } => {
                DataError::Parse { context: format!("{path}: {context}"), message }
            }
            DataError::Invalid(m) => DataError::Invalid(format!("{path}: {m}")),
            other => other,
        }
    }
}

/// How a data set's points are scaled before use (a spec's `normalise`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Normalise {
    /// Each axis min-max to [0, 1] (the thesis: a 40:25:15 ellipsoid becomes a unit cube's sphere).
    #[default]
    PerAxis,
    /// One scale for all axes: the longest axis to [0, 1], the others in proportion (aspect ratios kept).
    Uniform,
    /// The file's coordinates as they are.
    None,
}

impl Normalise {
    /// A sentence for the report.
    pub fn describe(self) -> &'static str {
        match self {
            Normalise::PerAxis => "normalised per axis to [0, 1] (the thesis' reading)",
            Normalise::Uniform => "normalised uniformly (the longest axis to [0, 1], one scale for all axes, so aspect ratios are kept)",
            Normalise::None => "not normalised (the files' own coordinates)",
        }
    }

    /// Scale `points` in place.
    pub fn apply(self, points: &mut [Point3]) {
        match self {
            Normalise::PerAxis => normalise_min_max(points),
            Normalise::Uniform => normalise_uniform(points),
            Normalise::None => {}
        }
    }
}

/// Uniform min-max normalisation: every axis shifted to start at 0 and divided by the largest
/// axis range, so the longest axis spans [0, 1] and the shape's proportions are kept.
pub(crate) fn normalise_uniform(points: &mut [Point3]) {
    let Some((lo, hi)) = crate::geom::bounding_box(points) else { return };
    let range = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
    for p in points.iter_mut() {
        for a in 0..3 {
            p[a] = if range > 0.0 { (p[a] - lo[a]) / range } else { 0.0 };
        }
    }
}

/// Per-axis min-max normalisation to [0, 1], as the thesis did; an axis with zero range maps to 0.
pub(crate) fn normalise_min_max(points: &mut [Point3]) {
    let Some((lo, hi)) = crate::geom::bounding_box(points) else { return };
    for p in points.iter_mut() {
        for a in 0..3 {
            let range = hi[a] - lo[a];
            p[a] = if range > 0.0 { (p[a] - lo[a]) / range } else { 0.0 };
        }
    }
}

/// Largest coordinate magnitude of a point file: beyond it the squared distances of the
/// parameterisation and the least-squares fit lose the data's own scale (1e300 made the normal
/// equations singular), so such a file is refused when it is read (docs/specs.md, "Own data").
pub(crate) const MAX_COORDINATE: f64 = 1e15;

/// Why a coordinate read from a file is refused (non-finite, or beyond [`MAX_COORDINATE`]).
pub(crate) fn coordinate_problem(axis: &str, v: f64) -> Option<String> {
    if !v.is_finite() {
        Some(format!("a non-finite {axis} ({v})"))
    } else if v.abs() > MAX_COORDINATE {
        Some(format!("{axis} = {v:e}, beyond the limit |{axis}| <= {MAX_COORDINATE:e}"))
    } else {
        None
    }
}

/// Refuse non-finite coordinates and coordinates beyond [`MAX_COORDINATE`] (naming the point and
/// axis) and clouds of fewer than `min_points`.
pub(crate) fn validate(points: &[Point3], min_points: usize) -> Result<(), DataError> {
    for (k, p) in points.iter().enumerate() {
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            if let Some(why) = coordinate_problem(axis, p[a]) {
                return Err(DataError::Invalid(format!("point {} has {why}", k + 1)));
            }
        }
    }
    if points.len() < min_points {
        return Err(DataError::Invalid(format!(
            "{} points, at least {min_points} needed",
            points.len()
        )));
    }
    Ok(())
}

/// Refuse a cloud of fewer points than the map trained on it has neurons: units would be left
/// with no data of their own, so the map could not organise over the surface. `entry` names the
/// data set as the spec wrote it (its file).
pub(crate) fn require_points(
    entry: &str,
    points: usize,
    neurons: usize,
    map: &str,
) -> Result<(), DataError> {
    if points < neurons {
        return Err(DataError::Invalid(format!("data set `{entry}`: {points} points, fewer than the {neurons} neurons of the {map} map trained on it (use a smaller grid or more points)")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalisation_maps_each_axis_to_unit_range() {
        let mut p = vec![[1.0, -2.0, 5.0], [3.0, 2.0, 5.0], [2.0, 0.0, 5.0]];
        normalise_min_max(&mut p);
        assert_eq!(p, vec![[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.5, 0.5, 0.0]]);
    }

    #[test]
    fn uniform_normalisation_keeps_aspect_ratios() {
        let mut p = vec![[0.0, 0.0, 0.0], [40.0, 25.0, 15.0], [-40.0, -25.0, -15.0]];
        Normalise::Uniform.apply(&mut p);
        let (lo, hi) = crate::geom::bounding_box(&p).unwrap();
        let ext: Vec<f64> = (0..3).map(|a| hi[a] - lo[a]).collect();
        assert_eq!(ext, vec![1.0, 0.625, 0.375]);
        let mut q = p.clone();
        Normalise::None.apply(&mut q);
        assert_eq!(p, q);
        Normalise::PerAxis.apply(&mut q);
        assert_eq!(q[1], [1.0, 1.0, 1.0]);
    }

    #[test]
    fn validation_names_point_and_axis() {
        let e = validate(&[[0.0; 3], [0.0, f64::NAN, 0.0]], 1).unwrap_err().to_string();
        assert!(e.contains("point 2") && e.contains(" y "), "{e}");
        assert!(validate(&[[0.0; 3]; 3], 4).unwrap_err().to_string().contains("at least 4"));
    }
}
