//! Axis ranges, tick positions and tick labels computed here rather than by plotters.
//!
//! Why: the fitness values of the thesis' optimisers agree to six or seven significant digits
//! (e.g. 14.742461 .. 14.742488), and plotters' defaults then print identical labels, while its
//! logarithmic axis shows no tick at all inside one decade. Here the range is padded relative to
//! its own width, ticks are "nice" multiples (1, 2, 2.5, 5 x 10^e) of a step chosen for the
//! padded width, and every label carries exactly the digits that step needs, so neighbouring
//! labels always differ. A log axis is drawn as a linear axis over log10 of the values with ticks
//! placed here (powers of ten, or nice linear ticks when the data span less than a decade).

/// Values beyond this magnitude are treated like non-finite ones (plotters maps through i32
/// pixels and f64 spans; |v| <= 1e300 keeps every difference finite).
pub(crate) const MAX_ABS: f64 = 1e300;

/// True for a value a chart can place: finite and within [`MAX_ABS`].
pub(crate) fn plottable(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_ABS
}

/// Minimum and maximum of the plottable values (None when there are none).
pub(crate) fn extent<I: IntoIterator<Item = f64>>(values: I) -> Option<(f64, f64)> {
    values.into_iter().filter(|v| plottable(*v)).fold(None, |acc, v| match acc {
        None => Some((v, v)),
        Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
    })
}

/// One chart axis in plot space (log10 of the values for a log axis) with its ticks and labels.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Axis {
    /// Lower end of the padded range, plot space.
    pub(crate) lo: f64,
    /// Upper end of the padded range, plot space.
    pub(crate) hi: f64,
    /// Tick positions, plot space, increasing.
    pub(crate) ticks: Vec<f64>,
    /// One label per tick.
    pub(crate) labels: Vec<String>,
    /// Whether plot space is log10 of the values.
    pub(crate) log: bool,
}

/// The nice step (1, 2, 2.5 or 5 times a power of ten) nearest to `raw` on a log scale, with
/// its decimal exponent and the number of decimals its multiples need. A step of exactly 2.5 is
/// not offered (it would put ".5" on integer data such as control-net sizes or generations);
/// 25, 250, 0.25 ... are.
fn nice_step(raw: f64) -> (f64, i32, usize) {
    let e = raw.log10().floor() as i32;
    let f = raw / 10f64.powi(e);
    let cands: &[f64] = if e == 0 { &[1.0, 2.0, 5.0, 10.0] } else { &[1.0, 2.0, 2.5, 5.0, 10.0] };
    let nf = cands
        .iter()
        .copied()
        .min_by(|a, b| (a / f).ln().abs().total_cmp(&(b / f).ln().abs()))
        .unwrap_or(1.0);
    let (nf, e) = if nf == 10.0 { (1.0, e + 1) } else { (nf, e) };
    let decimals = (-e + i32::from(nf == 2.5)).max(0) as usize;
    (nf * 10f64.powi(e), e, decimals)
}

/// Labels for ticks that are multiples of a step with decimal exponent `e` (and `extra` digit for
/// a 2.5 step): fixed notation for magnitudes in [1e-3, 1e6), scientific beyond, always with
/// enough digits for neighbouring ticks to differ.
fn linear_labels(ticks: &[f64], step: f64, e: i32, decimals: usize, extra: bool) -> Vec<String> {
    let m = ticks.iter().fold(0.0f64, |a, t| a.max(t.abs()));
    let sci = m >= 1e6 || (m > 0.0 && m < 1e-3);
    ticks
        .iter()
        .map(|&t| {
            let t = if t.abs() < step * 1e-6 { 0.0 } else { t };
            if t == 0.0 && sci {
                "0".to_string()
            } else if sci {
                let digits =
                    (m.log10().floor() as i32 - e + i32::from(extra)).clamp(0, 15) as usize;
                format!("{:.*e}", digits, t)
            } else {
                format!("{:.*}", decimals.min(17), t)
            }
        })
        .collect()
}

/// Nice ticks covering [lo, hi] with about `target` intervals.
fn linear_ticks(lo: f64, hi: f64, target: usize) -> (Vec<f64>, Vec<String>) {
    let raw = (hi / 2.0 - lo / 2.0) * 2.0 / target.max(1) as f64;
    let (step, e, decimals) = nice_step(raw);
    let k0 = (lo / step - 1e-9).ceil();
    let k1 = (hi / step + 1e-9).floor();
    let mut ticks = Vec::new();
    let mut k = k0;
    while k <= k1 && ticks.len() < 64 {
        ticks.push(k * step);
        k += 1.0;
    }
    let extra = (step / 10f64.powi(e) - 2.5).abs() < 1e-9;
    let labels = linear_labels(&ticks, step, e, decimals, extra);
    (ticks, labels)
}

impl Axis {
    /// A linear axis over [min, max] (min <= max, both plottable): padded by 5 % of the width on
    /// each side, or by 0.1 % of the magnitude (1 when zero) when the values are equal to 11
    /// significant digits.
    pub(crate) fn linear(min: f64, max: f64, target: usize) -> Axis {
        let mid = min / 2.0 + max / 2.0;
        let half = max / 2.0 - min / 2.0;
        let m = min.abs().max(max.abs());
        let half = if half <= m * 0.5e-11 {
            if m > 0.0 {
                m * 1e-3
            } else {
                1.0
            }
        } else {
            half * 1.1
        };
        let lo = (mid - half).max(-f64::MAX);
        let hi = (mid + half).min(f64::MAX);
        let (ticks, labels) = linear_ticks(lo, hi, target);
        Axis { lo, hi, ticks, labels, log: false }
    }

    /// A log10 axis over [min, max] (0 < min <= max): powers of ten (with 2x and 5x when fewer
    /// than three decades are shown), or nice linear ticks when the span is under one decade.
    /// None when `min` is not positive.
    pub(crate) fn log10(min: f64, max: f64, target: usize) -> Option<Axis> {
        if !(min > 0.0 && max >= min && max.is_finite()) {
            return None;
        }
        let (a, b) = (min.log10(), max.log10());
        let half = (b - a) / 2.0;
        let mid = (a + b) / 2.0;
        let half = if half < 1e-12 { 0.005 } else { half * 1.1 };
        let (lo, hi) = (mid - half, mid + half);
        let (ticks, labels) = if hi - lo >= 1.0 {
            let (k0, k1) = (lo.ceil() as i32, hi.floor() as i32);
            let count = (k1 - k0 + 1).max(1) as usize;
            let stride = count.div_ceil(target.max(1)).max(1);
            let mut vals: Vec<(f64, i32, f64)> = Vec::new();
            for k in (k0 - 1)..=k1 {
                let mults: &[f64] = if count < 3 { &[1.0, 2.0, 5.0] } else { &[1.0] };
                for &mlt in mults {
                    if mlt == 1.0 && (k - k0).rem_euclid(stride as i32) != 0 {
                        continue;
                    }
                    let v = mlt * 10f64.powi(k);
                    let l = v.log10();
                    if l >= lo - 1e-12 && l <= hi + 1e-12 {
                        vals.push((l, k, mlt));
                    }
                }
            }
            vals.sort_by(|x, y| x.0.total_cmp(&y.0));
            let labels = vals
                .iter()
                .map(|&(_, k, mlt)| {
                    if (-3..=5).contains(&k) {
                        format!("{:.*}", (-k).max(0) as usize, mlt * 10f64.powi(k))
                    } else {
                        format!("{}e{}", mlt as i64, k)
                    }
                })
                .collect();
            (vals.iter().map(|v| v.0).collect(), labels)
        } else {
            let (vt, labels) = linear_ticks(10f64.powf(lo), 10f64.powf(hi), target);
            let keep: Vec<usize> = (0..vt.len()).filter(|&i| vt[i] > 0.0).collect();
            (
                keep.iter().map(|&i| vt[i].log10()).collect(),
                keep.iter().map(|&i| labels[i].clone()).collect(),
            )
        };
        Some(Axis { lo, hi, ticks, labels, log: true })
    }

    /// A value in plot space, or None when it cannot be drawn (non-finite, or not positive on a
    /// log axis).
    pub(crate) fn to_plot(&self, v: f64) -> Option<f64> {
        if !plottable(v) {
            return None;
        }
        if self.log {
            (v > 0.0).then(|| v.log10())
        } else {
            Some(v)
        }
    }

    /// The label of the tick nearest to `t` (plot space), for plotters' label formatter.
    pub(crate) fn label_at(&self, t: f64) -> String {
        self.ticks
            .iter()
            .zip(&self.labels)
            .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
            .map(|(_, l)| l.clone())
            .unwrap_or_default()
    }

    /// The longest label (for sizing the label area).
    pub(crate) fn widest_label(&self) -> &str {
        self.labels.iter().max_by_key(|l| l.chars().count()).map(|s| s.as_str()).unwrap_or("0")
    }
}

/// An [`Axis`] is itself a plotters coordinate: linear over [lo, hi] in plot space, with exactly
/// its own ticks as key points (no light lines).
impl plotters::coord::ranged1d::Ranged for Axis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let span = self.hi - self.lo;
        let actual = (limit.1 - limit.0) as f64;
        if span <= 0.0 || !value.is_finite() {
            return limit.0;
        }
        // Clamped so far-off values cannot overflow i32 pixel coordinates.
        let t = ((value - self.lo) / span).clamp(-4.0, 5.0);
        limit.0 + (actual * t + 1e-3).floor() as i32
    }

    fn key_points<H: plotters::coord::ranged1d::KeyPointHint>(&self, hint: H) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_distinct(labels: &[String]) {
        for i in 1..labels.len() {
            assert_ne!(labels[i - 1], labels[i], "repeated label in {labels:?}");
        }
    }

    #[test]
    fn narrow_range_gets_distinct_labels_inside_padded_range() {
        let a = Axis::linear(14.742461, 14.742488, 6);
        assert!(a.lo < 14.742461 && a.hi > 14.742488);
        assert!(a.hi - a.lo < 1e-4, "padding relative to width, got {} .. {}", a.lo, a.hi);
        assert!(a.ticks.len() >= 3, "{a:?}");
        assert_distinct(&a.labels);
        assert!(
            a.labels.iter().all(|l| l.starts_with("14.7424") || l.starts_with("14.7425")),
            "{a:?}"
        );
        for (t, l) in a.ticks.iter().zip(&a.labels) {
            assert!(t >= &a.lo && t <= &a.hi);
            assert!((l.parse::<f64>().unwrap() - t).abs() < 1e-9);
        }
    }

    #[test]
    fn equal_values_are_padded_by_magnitude() {
        let a = Axis::linear(5.0, 5.0, 5);
        assert!((a.lo - 4.995).abs() < 1e-12 && (a.hi - 5.005).abs() < 1e-12, "{a:?}");
        assert_distinct(&a.labels);
        let z = Axis::linear(0.0, 0.0, 5);
        assert_eq!((z.lo, z.hi), (-1.0, 1.0));
        assert!(z.labels.contains(&"0.0".to_string()), "{z:?}");
    }

    #[test]
    fn integer_data_avoid_half_steps() {
        let a = Axis::linear(4.0, 19.0, 8);
        assert!(a.labels.iter().all(|l| !l.contains('.')), "{a:?}");
    }

    #[test]
    fn ordinary_range_has_round_labels() {
        // Padded to -5..105: raw step 22 -> 20; padded -4.5..94.5: raw 19.8 -> 20.
        let a = Axis::linear(0.0, 100.0, 5);
        assert_eq!(a.labels, vec!["0", "20", "40", "60", "80", "100"]);
        let c = Axis::linear(0.0, 90.0, 5);
        assert_eq!(c.labels, vec!["0", "20", "40", "60", "80"]);
        // Padded -0.05..1.05: raw 0.275 -> 0.25; zero gets the same decimals as its neighbours.
        let b = Axis::linear(0.0, 1.0, 4);
        assert_eq!(b.labels, vec!["0.00", "0.25", "0.50", "0.75", "1.00"]);
        let d = Axis::linear(0.0, 1.0, 2);
        assert_eq!(d.labels, vec!["0.0", "0.5", "1.0"]);
    }

    #[test]
    fn tiny_and_huge_magnitudes_use_scientific_labels() {
        let a = Axis::linear(1e-7, 5e-7, 4);
        assert!(a.labels.iter().all(|l| l == "0" || l.contains('e')), "{a:?}");
        assert_distinct(&a.labels);
        let b = Axis::linear(2.0e7, 2.0e7 + 3.0, 5);
        assert!(b.labels.iter().all(|l| l.contains('e')), "{b:?}");
        assert_distinct(&b.labels);
    }

    #[test]
    fn log_axis_over_decades_uses_powers_of_ten() {
        let a = Axis::log10(1e-4, 10.0, 6).unwrap();
        assert!(
            a.labels.contains(&"0.001".to_string()) && a.labels.contains(&"1".to_string()),
            "{a:?}"
        );
        for t in &a.ticks {
            assert!((t - t.round()).abs() < 1e-12, "power-of-ten ticks only: {a:?}");
        }
        let w = Axis::log10(1e-12, 1e3, 6).unwrap();
        assert!(w.labels.iter().any(|l| l.contains("e-")), "{w:?}");
        assert!(w.ticks.len() <= 8, "{w:?}");
    }

    #[test]
    fn log_axis_inside_one_decade_still_has_ticks() {
        let a = Axis::log10(14.742461, 14.742488, 6).unwrap();
        assert!(a.ticks.len() >= 3, "{a:?}");
        assert_distinct(&a.labels);
        assert!(a.lo < 14.742461f64.log10() && a.hi > 14.742488f64.log10());
        let b = Axis::log10(2.0, 7.0, 5).unwrap();
        assert!(b.ticks.len() >= 3, "{b:?}");
    }

    #[test]
    fn log_axis_rejects_non_positive() {
        assert!(Axis::log10(0.0, 1.0, 5).is_none());
        assert!(Axis::log10(-1.0, 1.0, 5).is_none());
        let a = Axis::log10(1.0, 10.0, 5).unwrap();
        assert_eq!(a.to_plot(-3.0), None);
        assert_eq!(a.to_plot(f64::NAN), None);
        assert_eq!(a.to_plot(100.0), Some(2.0));
    }

    #[test]
    fn extent_ignores_non_finite() {
        assert_eq!(
            extent([f64::NAN, 2.0, f64::INFINITY, -1.0, f64::NEG_INFINITY]),
            Some((-1.0, 2.0))
        );
        assert_eq!(extent([f64::NAN]), None);
        assert_eq!(extent([1e301, 3.0]), Some((3.0, 3.0)));
    }
}
