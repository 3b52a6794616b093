//! Parameterisation of a grid (thesis Eq. 2.7, 2.8 per row and column, averaged by Eq. 5.1, 5.2).

use crate::geom::{self, Point3};
use serde::{Deserialize, Serialize};
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
        self.alpha_with(EXPONENTIAL_ALPHA)
    }

    /// Eq. 2.8's alpha with the exponential method's taken as `exponential` (Section 2.3.2 sets it
    /// to 0.8; a named reading, `ParamReading::exponential_alpha`).
    pub fn alpha_with(self, exponential: f64) -> Option<f64> {
        match self {
            Self::Uniform => None,
            Self::ChordLength => Some(1.0),
            Self::Centripetal => Some(0.5),
            Self::Exponential => Some(exponential),
        }
    }
}

/// Section 2.3.2: "Exponential method was proposed in [88] by setting the power factor, alpha in
/// Equation 2.8 to 0.8".
pub(crate) const EXPONENTIAL_ALPHA: f64 = 0.8;

/// The range `exponential_alpha` may take, (0, 1]: alpha -> 0 tends to the uniform method (Eq.
/// 2.7), 1 is chord length.
pub(crate) const EXPONENTIAL_ALPHA_RANGE: (f64, f64) = (0.0, 1.0);

/// Which grid lines give a surface's data parameters (Section 5.2.2.1; a named reading,
/// docs/readings.md).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default, Serialize, Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum ParamRows {
    /// Eq. 5.1, 5.2: u is the mean over every column's polyline, v over every row's ("the average
    /// parameters of each row and column").
    #[default]
    All,
    /// The parameters of the middle column (u) and middle row (v) alone, index ny / 2 and nx / 2.
    Middle,
}

impl ParamRows {
    pub const ALL: [ParamRows; 2] = [ParamRows::All, ParamRows::Middle];

    /// The spec value.
    pub fn name(self) -> &'static str {
        match self {
            ParamRows::All => "all",
            ParamRows::Middle => "middle",
        }
    }
}

/// The parameterisation's named readings. `Default` is the thesis plan's (Eq. 2.8 with 0.8 for
/// the exponential method, Eq. 5.1/5.2 over all rows and columns).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamReading {
    /// Eq. 2.8's alpha of the exponential method.
    pub exponential_alpha: f64,
    pub rows: ParamRows,
}

impl Default for ParamReading {
    fn default() -> Self {
        ParamReading { exponential_alpha: EXPONENTIAL_ALPHA, rows: ParamRows::All }
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
        // One spelling per value, in a spec and on the command line alike.
        match s {
            "uniform" => Ok(Self::Uniform),
            "chord_length" => Ok(Self::ChordLength),
            "centripetal" => Ok(Self::Centripetal),
            "exponential" => Ok(Self::Exponential),
            _ => Err(format!("unknown parameterisation `{s}` (expected uniform, chord_length, centripetal or exponential)")),
        }
    }
}

/// Parameters of one polyline: t_0 = 0, t_n = 1, t_k = sum_{i<=k} |Q_i - Q_{i-1}|^alpha / total
/// (Eq. 2.8), or k/n (Eq. 2.7). A polyline of zero total length falls back to uniform.
pub(crate) fn polyline_params(points: &[Point3], method: Parameterisation) -> Vec<f64> {
    polyline_params_alpha(points, method.alpha())
}

/// [`polyline_params`] with Eq. 2.8's alpha given (None: Eq. 2.7).
pub(crate) fn polyline_params_alpha(points: &[Point3], alpha: Option<f64>) -> Vec<f64> {
    let n = points.len();
    if n < 2 {
        return vec![0.0; n];
    }
    let uniform = || (0..n).map(|k| k as f64 / (n - 1) as f64).collect::<Vec<f64>>();
    let Some(alpha) = alpha else { return uniform() };
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
pub(crate) fn grid_params(
    view: &[Point3],
    nx: usize,
    ny: usize,
    method: Parameterisation,
) -> (Vec<f64>, Vec<f64>) {
    grid_params_with(view, nx, ny, method, &ParamReading::default())
}

/// [`grid_params`] under the named readings: Eq. 2.8's exponential alpha, and which columns
/// (rows) give u (v): the mean over all of them (Eq. 5.1, 5.2) or the middle one alone.
pub(crate) fn grid_params_with(
    view: &[Point3],
    nx: usize,
    ny: usize,
    method: Parameterisation,
    reading: &ParamReading,
) -> (Vec<f64>, Vec<f64>) {
    let alpha = method.alpha_with(reading.exponential_alpha);
    let (cols, rows) = match reading.rows {
        ParamRows::All => (0..ny, 0..nx),
        ParamRows::Middle => (ny / 2..ny / 2 + 1, nx / 2..nx / 2 + 1),
    };
    let (n_cols, n_rows) = (cols.len() as f64, rows.len() as f64);
    let mut u = vec![0.0; nx];
    for j in cols {
        let col: Vec<Point3> = (0..nx).map(|i| view[i * ny + j]).collect();
        for (acc, t) in u.iter_mut().zip(polyline_params_alpha(&col, alpha)) {
            *acc += t;
        }
    }
    let mut v = vec![0.0; ny];
    for i in rows {
        for (acc, t) in v.iter_mut().zip(polyline_params_alpha(&view[i * ny..(i + 1) * ny], alpha))
        {
            *acc += t;
        }
    }
    u.iter_mut().for_each(|x| *x /= n_cols);
    v.iter_mut().for_each(|x| *x /= n_rows);
    (u, v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_spelling_per_value_in_specs_and_on_the_command_line() {
        use crate::spline::Approach;
        for (ok, want) in [
            ("chord_length", Parameterisation::ChordLength),
            ("uniform", Parameterisation::Uniform),
        ] {
            assert_eq!(ok.parse::<Parameterisation>(), Ok(want));
            assert_eq!(Parameterisation::try_from(ok.to_string()), Ok(want));
        }
        for alias in ["chordal", "chord", "Chord-Length", "chord length", "Uniform", "CENTRIPETAL"]
        {
            let e = alias.parse::<Parameterisation>().unwrap_err();
            assert!(e.contains("uniform, chord_length, centripetal or exponential"), "{e}");
            assert!(Parameterisation::try_from(alias.to_string()).is_err(), "{alias}");
        }
        for (ok, want) in [
            ("A", Approach::Conventional),
            ("conventional", Approach::Conventional),
            ("B", Approach::Improved),
            ("improved", Approach::Improved),
        ] {
            assert_eq!(ok.parse::<Approach>(), Ok(want));
        }
        for alias in ["a", "b", "Improved", "CONVENTIONAL"] {
            assert!(alias.parse::<Approach>().is_err(), "{alias}");
            assert!(Approach::try_from(alias.to_string()).is_err(), "{alias}");
        }
    }

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
        // The middle column (j = ny / 2 = 1) alone: spacing 1, 1, so u = 0, 0.5, 1.
        let middle = ParamReading { rows: ParamRows::Middle, ..ParamReading::default() };
        let (u, v) = grid_params_with(&view, 3, 2, Parameterisation::ChordLength, &middle);
        assert_eq!((u, v), (vec![0.0, 0.5, 1.0], vec![0.0, 1.0]));
    }

    /// Eq. 2.8 with alpha = 0.8 on the seed-002 polyline, by hand; alpha 1 and 0.5 are the chord
    /// length and centripetal methods, and the default reading is bit-identical to `grid_params`.
    #[test]
    fn exponential_alpha_reading() {
        let q = [[0.0, 0.0, 0.0], [1.0, 2.0, 0.0], [3.0, 4.0, 0.0], [4.0, 0.0, 0.0]];
        let d: Vec<f64> = [5f64, 8.0, 17.0].iter().map(|x| x.sqrt().powf(0.8)).collect();
        let e = polyline_params(&q, Parameterisation::Exponential);
        assert!((e[1] - d[0] / (d[0] + d[1] + d[2])).abs() < 1e-15, "{e:?}");
        let view: Vec<Point3> = (0..12)
            .map(|k| [(k / 4) as f64, ((k % 4) as f64).powi(2), (k as f64 * 0.7).sin()])
            .collect();
        for (alpha, same) in
            [(1.0, Parameterisation::ChordLength), (0.5, Parameterisation::Centripetal)]
        {
            let r = ParamReading { exponential_alpha: alpha, ..ParamReading::default() };
            assert_eq!(
                grid_params_with(&view, 3, 4, Parameterisation::Exponential, &r),
                grid_params(&view, 3, 4, same)
            );
        }
        assert_eq!(
            grid_params_with(&view, 3, 4, Parameterisation::Exponential, &ParamReading::default()),
            grid_params(&view, 3, 4, Parameterisation::Exponential)
        );
    }
}
