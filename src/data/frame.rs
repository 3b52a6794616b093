//! The frame of a data set: how its points were scaled before use (the spec's `normalise`), so
//! that anything made in the normalised coordinates (a DNSOM map, a fitted surface) can be taken
//! back to the data's own coordinates. Chapter 4 writes it beside each saved map as
//! `<map>.frame.toml`; `somnurbs fit` reads it. Pure: text in, text out.

use super::{DataError, Normalise};
use crate::geom::Point3;
use serde::{Deserialize, Serialize};

/// Data = `offset + scale * normalised`, axis by axis (x, y, z). Every scale is finite and above
/// 0; an axis of zero range (mapped to 0 by the normalisation) has scale 1, so its normalised 0
/// maps back to its one value, the offset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Frame {
    /// The data set's name (a built-in's, a file's stem).
    pub dataset: String,
    /// Where the points came from: the file as it was read (relative to the working folder when
    /// the spec's folder was), or `generated` for a built-in generator.
    pub source: String,
    /// The normalisation the spec asked for.
    pub normalise: Normalise,
    pub offset: [f64; 3],
    pub scale: [f64; 3],
    /// The data's bounding box in their own coordinates, [min, max] per axis (x, y, z); what
    /// counts as near the data is measured against it (`families::maps::near_bound`). Frames
    /// written before it was kept lack it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data_box: Option<[[f64; 3]; 2]>,
}

/// The `source` of a generated data set.
pub(crate) const GENERATED: &str = "generated";

impl Frame {
    /// The frame `normalise` will apply to `points` (the same bounding box and ranges as
    /// [`super::normalise_min_max`] and [`super::normalise_uniform`]).
    pub fn of(normalise: Normalise, points: &[Point3], dataset: &str, source: &str) -> Frame {
        let (offset, scale) = match (normalise, crate::geom::bounding_box(points)) {
            (Normalise::None, _) | (_, None) => ([0.0; 3], [1.0; 3]),
            (Normalise::PerAxis, Some((lo, hi))) => {
                let range = [0, 1, 2].map(|a| hi[a] - lo[a]);
                (lo, range.map(|r| if r > 0.0 { r } else { 1.0 }))
            }
            (Normalise::Uniform, Some((lo, hi))) => {
                let range = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
                (lo, [if range > 0.0 { range } else { 1.0 }; 3])
            }
        };
        let data_box = crate::geom::bounding_box(points).map(|(lo, hi)| [lo, hi]);
        Frame {
            dataset: dataset.to_string(),
            source: source.to_string(),
            normalise,
            offset,
            scale,
            data_box,
        }
    }

    /// A point of the normalised coordinates in the data's own.
    pub fn to_data(&self, p: Point3) -> Point3 {
        crate::geom::affine(self.offset, self.scale, p)
    }

    /// The file's text: a comment line, then the fields.
    pub fn to_toml(&self, map: &str) -> Result<String, DataError> {
        let body = toml::to_string(self)
            .map_err(|e| DataError::Invalid(format!("frame of {map}: {e}")))?;
        Ok(format!(
            "# The frame of {map}: data = offset + scale * map, per axis (x, y, z).\n{body}"
        ))
    }

    /// Parse a frame file's text; every offset must be finite, every scale finite and above 0
    /// (a zero scale would send every exported point of that axis to the offset). An error names
    /// the key and the axis.
    pub fn parse(text: &str) -> Result<Frame, DataError> {
        let f: Frame = toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1)
                .map(|l| format!("line {l}"))
                .unwrap_or_else(|| "frame".into());
            DataError::parse(line, e.message().to_string())
        })?;
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            let (offset, scale) = (f.offset[a], f.scale[a]);
            if !offset.is_finite() {
                return Err(DataError::Invalid(format!(
                    "offset: the {axis} offset is {offset}; a frame's offsets must be finite \
                     numbers (data = offset + scale * map)"
                )));
            }
            if !(scale.is_finite() && scale > 0.0) {
                return Err(DataError::Invalid(format!(
                    "scale: the {axis} scale is {scale}; a frame's scales must be finite and above \
                     0 (data = offset + scale * map; 1 for a flat axis)"
                )));
            }
        }
        if let Some([lo, hi]) = f.data_box {
            if !(lo.iter().chain(&hi).all(|v| v.is_finite()) && (0..3).all(|a| lo[a] <= hi[a])) {
                return Err(DataError::Invalid(format!(
                    "data_box: {lo:?} to {hi:?} is no box; a frame's data_box is [min, max] per \
                     axis, finite, min <= max"
                )));
            }
        }
        Ok(f)
    }

    /// The longest side of the data's bounding box in the map's coordinates (None: the frame
    /// does not keep the box, or the data are one point).
    pub(crate) fn longest_side_in_map(&self) -> Option<f64> {
        let [lo, hi] = self.data_box?;
        let side = (0..3).map(|a| (hi[a] - lo[a]) / self.scale[a]).fold(0.0, f64::max);
        (side > 0.0).then_some(side)
    }

    /// One phrase for the exported files: where the coordinates come from.
    pub fn describe(&self) -> String {
        if self.source == GENERATED {
            format!("the coordinates of the generated data set {}", self.dataset)
        } else {
            format!("the data's own coordinates, from {}", self.source)
        }
    }
}

/// The frame file beside a map: `X.csv` (or its compressed copy `X.csv.gz`) -> `X.frame.toml`
/// (any other name: `.frame.toml` added).
pub(crate) fn sidecar(map: &std::path::Path) -> std::path::PathBuf {
    let name = map.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let stem = name.strip_suffix(".gz").unwrap_or(&name);
    let stem = stem.strip_suffix(".csv").unwrap_or(stem);
    map.with_file_name(format!("{stem}.frame.toml"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud() -> Vec<Point3> {
        vec![[-3.0, 10.0, 0.0], [5.0, 11.0, 100.0], [1.0, 10.5, 7.0], [0.25, 10.0, 3.0]]
    }

    #[test]
    fn the_frame_inverts_every_normalisation() {
        for mode in [Normalise::PerAxis, Normalise::Uniform, Normalise::None] {
            let raw = cloud();
            let frame = Frame::of(mode, &raw, "c", "c.xyz");
            let mut n = raw.clone();
            mode.apply(&mut n);
            for (p, q) in raw.iter().zip(&n) {
                let back = frame.to_data(*q);
                for a in 0..3 {
                    assert!((back[a] - p[a]).abs() <= 1e-12 * (1.0 + p[a].abs()), "{mode:?}");
                }
            }
        }
        let f = Frame::of(Normalise::PerAxis, &cloud(), "c", "c.xyz");
        assert_eq!((f.offset, f.scale), ([-3.0, 10.0, 0.0], [8.0, 1.0, 100.0]));
        let u = Frame::of(Normalise::Uniform, &cloud(), "c", "c.xyz");
        assert_eq!(u.scale, [100.0; 3]);
        // A flat axis has scale 1 (a frame the parser takes) and maps back to its one value.
        let flat = vec![[0.0, 2.0, 1.0], [1.0, 2.0, 3.0]];
        let f = Frame::of(Normalise::PerAxis, &flat, "f", GENERATED);
        assert_eq!(f.scale, [1.0, 1.0, 2.0]);
        assert_eq!(f.to_data([0.5, 0.0, 0.5]), [0.5, 2.0, 2.0]);
        assert_eq!(Frame::parse(&f.to_toml("f.csv").unwrap()).unwrap(), f);
    }

    #[test]
    fn toml_round_trip_is_exact_and_bad_frames_are_refused() {
        let f = Frame::of(
            Normalise::PerAxis,
            &[[0.1, -1e-7, 3.0], [0.7, 2.0 / 3.0, 1e9]],
            "d",
            "x.off",
        );
        let text = f.to_toml("dnsom_d_6x6.csv").unwrap();
        assert!(text.starts_with("# The frame of dnsom_d_6x6.csv"), "{text}");
        assert_eq!(Frame::parse(&text).unwrap(), f);
        let e = Frame::parse(&text.replace("per_axis", "cube")).unwrap_err().to_string();
        assert!(e.contains("line") && e.contains("cube"), "{e}");
        let e = Frame::parse(&format!("{text}units = \"mm\"\n")).unwrap_err().to_string();
        assert!(e.contains("line 8") && e.contains("units"), "{e}");
        let with = |key: &str, line: &str| -> String {
            let lines: Vec<&str> =
                text.lines().map(|l| if l.starts_with(key) { line } else { l }).collect();
            match Frame::parse(&lines.join("\n")) {
                Ok(f) => panic!("{line}: taken as {f:?}"),
                Err(e) => e.to_string(),
            }
        };
        let e = with("data_box", "data_box = [[0.0, 0.0, 2.0], [1.0, 1.0, 1.0]]");
        assert!(e.contains("data_box") && e.contains("min <= max"), "{e}");
        for (line, want) in [
            ("scale = [-2.0, 1.0, 1.0]", "scale: the x scale is -2;"),
            ("scale = [0, 0, 0]", "scale: the x scale is 0;"),
            ("scale = [1.0, 0.0, 1.0]", "scale: the y scale is 0;"),
            ("scale = [1.0, 1.0, nan]", "scale: the z scale is NaN;"),
            ("scale = [1.0, inf, 1.0]", "scale: the y scale is inf;"),
        ] {
            let e = with("scale", line);
            assert!(e.contains(want) && e.contains("finite and above 0"), "{line}: {e}");
        }
        let e = with("offset", "offset = [0.0, -inf, 1.0]");
        assert!(e.contains("offset: the y offset is -inf;"), "{e}");
        assert_eq!(
            sidecar(std::path::Path::new("maps/dnsom_a_6x6.csv")),
            std::path::Path::new("maps/dnsom_a_6x6.frame.toml")
        );
        assert_eq!(
            sidecar(std::path::Path::new("maps/dnsom_a_6x6.csv.gz")),
            std::path::Path::new("maps/dnsom_a_6x6.frame.toml")
        );
    }
}
