//! Data sets: deterministic generators for the thesis' primitives, loaders for point files
//! (PLY, STL, XYZ/CSV), and the thesis' per-axis min-max normalisation. Pure apart from
//! `registry`, the one place that reads files.

pub mod cylinder;
pub mod generators;
pub mod grid_csv;
pub mod ply;
pub mod registry;
pub mod stl;
pub mod xyz;

use crate::geom::Point3;
use thiserror::Error;

/// A named point cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct PointCloud {
    pub name: String,
    pub points: Vec<Point3>,
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

impl DataError {
    pub fn parse(context: impl Into<String>, message: impl Into<String>) -> DataError {
        DataError::Parse { context: context.into(), message: message.into() }
    }

    /// Prefix the error with the file it came from.
    pub fn in_file(self, path: &str) -> DataError {
        match self {
            DataError::Parse { context, message } => DataError::Parse { context: format!("{path}: {context}"), message },
            DataError::Invalid(m) => DataError::Invalid(format!("{path}: {m}")),
            other => other,
        }
    }
}

/// Per-axis min-max normalisation to [0, 1], as the thesis did; an axis with zero range maps to 0.
pub fn normalise_min_max(points: &mut [Point3]) {
    let Some((lo, hi)) = crate::geom::bounding_box(points) else { return };
    for p in points.iter_mut() {
        for a in 0..3 {
            let range = hi[a] - lo[a];
            p[a] = if range > 0.0 { (p[a] - lo[a]) / range } else { 0.0 };
        }
    }
}

/// Refuse non-finite coordinates (naming the point and axis) and clouds of fewer than `min_points`.
pub fn validate(points: &[Point3], min_points: usize) -> Result<(), DataError> {
    for (k, p) in points.iter().enumerate() {
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            if !p[a].is_finite() {
                return Err(DataError::Invalid(format!("point {} has a non-finite {axis} ({})", k + 1, p[a])));
            }
        }
    }
    if points.len() < min_points {
        return Err(DataError::Invalid(format!("{} points, at least {min_points} needed", points.len())));
    }
    Ok(())
}

/// Refuse a cloud of fewer points than the map trained on it has neurons: units would be left
/// with no data of their own, so the map could not organise over the surface. `entry` names the
/// data set as the spec wrote it (its file).
pub fn require_points(entry: &str, points: usize, neurons: usize, map: &str) -> Result<(), DataError> {
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
    fn validation_names_point_and_axis() {
        let e = validate(&[[0.0; 3], [0.0, f64::NAN, 0.0]], 1).unwrap_err().to_string();
        assert!(e.contains("point 2") && e.contains(" y "), "{e}");
        assert!(validate(&[[0.0; 3]; 3], 4).unwrap_err().to_string().contains("at least 4"));
    }
}
