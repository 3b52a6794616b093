//! Parameterisation of a grid (thesis Eq. 2.7, 2.8 per row and column, averaged by Eq. 5.1, 5.2).

use crate::geom::{self, Point3};
use std::fmt;
use std::str::FromStr;

/// The four parameterisation methods of Chapter 5 (in a spec by name, as [`FromStr`] reads it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum Parameterisation {
    Uniform,
    ChordLength,
    Centripetal,
    Exponential,
}

impl Parameterisation {
    pub const ALL: [Parameterisation; 4] =
        [Self::Uniform, Self::ChordLength, Self::Centripetal, Self::Exponential];

    /// Column stem in the thesis' Appendix E/F CSV.
    pub fn name(self) -> &'static str {
        match self {
            Self::Uniform => "uniform",
            Self::ChordLength => "chord_length",
            Self::Centripetal => "centripetal",
            Self::Exponential => "exponential",
        }
    }

    /// Power factor alpha of Eq. 2.8 (None: uniform, Eq. 2.7).
    pub fn alpha(self) -> Option<f64> {
        match self {
            Self::Uniform => None,
            Self::ChordLength => Some(1.0),
            Self::Centripetal => Some(0.5),
            Self::Exponential => Some(0.8),
        }
    }
}

impl fmt::Display for Parameterisation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl TryFrom<String> for Parameterisation {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl FromStr for Parameterisation {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().replace(['-', ' '], "_").as_str() {
            "uniform" => Ok(Self::Uniform),
            "chord_length" | "chord" | "chordal" => Ok(Self::ChordLength),
            "centripetal" => Ok(Self::Centripetal),
            "exponential" => Ok(Self::Exponential),
            _ => Err(format!("unknown parameterisation `{s}` (expected uniform, chord_length, centripetal or exponential)")),
        }
    }
}

/// Parameters of one polyline: t_0 = 0, t_n = 1, t_k = sum_{i<=k} |Q_i - Q_{i-1}|^alpha / total
/// (Eq. 2.8), or k/n (Eq. 2.7). A polyline of zero total length falls back to uniform.
pub fn polyline_params(points: &[Point3], method: Parameterisation) -> Vec<f64> {
    let n = points.len();
    if n < 2 {
        return vec![0.0; n];
    }
    let uniform = || (0..n).map(|k| k as f64 / (n - 1) as f64).collect::<Vec<f64>>();
    let Some(alpha) = method.alpha() else { return uniform() };
    let steps: Vec<f64> = points.windows(2).map(|w| geom::dist(w[0], w[1]).powf(alpha)).collect();
    let total: f64 = steps.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return uniform();
    }
    let mut t = Vec::with_capacity(n);
    let mut acc = 0.0;
    t.push(0.0);
    for s in &steps[..n - 2] {
        acc += s;
        t.push(acc / total);
    }
    t.push(1.0);
    t
}

/// Averaged parameters of a row-major `nx x ny` view: u (length nx) along i, the mean over the ny
/// columns j of each column's polyline parameters (Eq. 5.1); v (length ny) along j, the mean over
/// the nx rows (Eq. 5.2).
pub fn grid_params(
    view: &[Point3],
    nx: usize,
    ny: usize,
    method: Parameterisation,
) -> (Vec<f64>, Vec<f64>) {
    let mut u = vec![0.0; nx];
    for j in 0..ny {
        let col: Vec<Point3> = (0..nx).map(|i| view[i * ny + j]).collect();
        for (acc, t) in u.iter_mut().zip(polyline_params(&col, method)) {
            *acc += t;
        }
    }
    let mut v = vec![0.0; ny];
    for i in 0..nx {
        for (acc, t) in v.iter_mut().zip(polyline_params(&view[i * ny..(i + 1) * ny], method)) {
            *acc += t;
        }
    }
    u.iter_mut().for_each(|x| *x /= ny as f64);
    v.iter_mut().for_each(|x| *x /= nx as f64);
    (u, v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chord_length_example_of_seed_002() {
        let q = [[0.0, 0.0, 0.0], [1.0, 2.0, 0.0], [3.0, 4.0, 0.0], [4.0, 0.0, 0.0]];
        let t = polyline_params(&q, Parameterisation::ChordLength);
        for (a, b) in t.iter().zip([0.0, 0.2434, 0.5512, 1.0]) {
            assert!((a - b).abs() < 1e-4, "{t:?}");
        }
        let c = polyline_params(&q, Parameterisation::Centripetal);
        let d: Vec<f64> =
            [5f64.sqrt(), 8f64.sqrt(), 17f64.sqrt()].iter().map(|x| x.sqrt()).collect();
        let tot: f64 = d.iter().sum();
        assert!((c[1] - d[0] / tot).abs() < 1e-15 && (c[2] - (d[0] + d[1]) / tot).abs() < 1e-15);
        assert_eq!(
            polyline_params(&q, Parameterisation::Uniform),
            vec![0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0]
        );
    }

    #[test]
    fn degenerate_polyline_is_uniform_and_grid_averages() {
        assert_eq!(
            polyline_params(&[[1.0; 3]; 3], Parameterisation::ChordLength),
            vec![0.0, 0.5, 1.0]
        );
        // A 3 x 2 grid whose two columns have different spacing: u is their mean.
        let view = [
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [4.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
        ];
        let (u, v) = grid_params(&view, 3, 2, Parameterisation::ChordLength);
        assert!((u[1] - (0.25 + 0.5) / 2.0).abs() < 1e-15, "{u:?}");
        assert_eq!(v, vec![0.0, 1.0]);
    }
}
