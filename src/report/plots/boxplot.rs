//! Box plots of final fitness (or CPU time, surface error) per optimiser over the repeats of a
//! cell: the distribution behind the thesis' AVG/MIN/MAX columns (Appendices K-N).
//!
//! Quartiles are Hyndman & Fan type 7 (linear interpolation at h = (n-1)p, R's default
//! `quantile`), whiskers reach the most extreme observation within 1.5 IQR of the box (Tukey),
//! and observations beyond are drawn as outliers. The y axis comes from [`super::scale`], so
//! groups agreeing to seven digits still get distinct tick labels.

use super::scale::{extent, plottable, Axis};
use super::style;
use super::{render_png, DrawError, PlotError};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Five-number summary with Tukey whiskers and outliers of the finite values of one group.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BoxStats {
    /// Number of finite values used.
    pub(crate) n: usize,
    pub(crate) q1: f64,
    pub(crate) median: f64,
    pub(crate) q3: f64,
    /// Smallest value >= q1 - 1.5 IQR.
    pub(crate) lower_whisker: f64,
    /// Largest value <= q3 + 1.5 IQR.
    pub(crate) upper_whisker: f64,
    /// Values outside the whiskers, ascending.
    pub(crate) outliers: Vec<f64>,
}

/// Type-7 quantile of ascending `sorted` (non-empty), p in [0, 1].
pub(crate) fn quantile_type7(sorted: &[f64], p: f64) -> f64 {
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    sorted[lo] + (h - lo as f64) * (sorted[hi] - sorted[lo])
}

impl BoxStats {
    /// Summary of the plottable values in `values` (None when there are none).
    pub(crate) fn from_values(values: &[f64]) -> Option<BoxStats> {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| plottable(*x)).collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        let (q1, median, q3) =
            (quantile_type7(&v, 0.25), quantile_type7(&v, 0.5), quantile_type7(&v, 0.75));
        let iqr = q3 - q1;
        let (lf, uf) = (q1 - 1.5 * iqr, q3 + 1.5 * iqr);
        let inside = |x: &&f64| **x >= lf && **x <= uf;
        // The quartiles lie inside the fences, so some value always does.
        let lower_whisker = v.iter().find(inside).copied().unwrap_or(q1);
        let upper_whisker = v.iter().rev().find(inside).copied().unwrap_or(q3);
        let outliers = v.iter().copied().filter(|x| *x < lf || *x > uf).collect();
        Some(BoxStats { n: v.len(), q1, median, q3, lower_whisker, upper_whisker, outliers })
    }
}

/// Picture size for `n_groups` boxes: [`style::CHART_SIZE`], widened beyond 11 groups so each
/// keeps ~70 px.
pub(crate) fn box_plot_size(n_groups: usize) -> (u32, u32) {
    let w = (160 + 70 * n_groups.min(200)) as u32;
    (style::CHART_SIZE.0.max(w), style::CHART_SIZE.1)
}

/// Writes one box per group (name, values) to `path`; non-finite values are left out (the count
/// used is printed under each name). An error when no group has a finite value.
pub(crate) fn box_plot_png(
    path: &Path,
    title: &str,
    y_label: &str,
    groups: &[(String, Vec<f64>)],
    levels: &[Level],
) -> Result<(), PlotError> {
    let stats: Vec<Option<BoxStats>> =
        groups.iter().map(|(_, v)| BoxStats::from_values(v)).collect();
    let (lo, hi) = extent(
        stats
            .iter()
            .flatten()
            .flat_map(|s| {
                [s.lower_whisker, s.upper_whisker].into_iter().chain(s.outliers.iter().copied())
            })
            .chain(levels.iter().map(|l| l.y)),
    )
    .ok_or_else(|| {
        PlotError::input(path, format!("none of the {} groups has a finite value", groups.len()))
    })?;
    let y_axis = Axis::linear(lo, hi, 7);
    render_png(path, box_plot_size(groups.len()), |root| {
        draw_box_plot(root, title, y_label, groups, &stats, &y_axis, levels)
    })
}

/// A reference level across a box plot (where every run started, a certified optimum), so a
/// box that ends above it shows as such; `key` picks its colour ([`style::optimiser_colour`]).
#[derive(Debug, Clone)]
pub(crate) struct Level {
    pub(crate) key: &'static str,
    pub(crate) label: String,
    pub(crate) y: f64,
}

fn draw_box_plot(
    root: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    title: &str,
    y_label: &str,
    groups: &[(String, Vec<f64>)],
    stats: &[Option<BoxStats>],
    y_axis: &Axis,
    levels: &[Level],
) -> Result<(), DrawError> {
    let label_font = style::text(style::LABEL_PX);
    let small_font = style::text(12.0).color(&style::GREY);
    let y_label_w = style::text_width(root, y_axis.widest_label(), &label_font)?;
    let k = groups.len() as f64;
    let mut chart = ChartBuilder::on(root)
        .margin(14)
        .caption(title, style::bold(style::TITLE_PX))
        .x_label_area_size(48)
        .y_label_area_size(y_label_w + 42)
        .build_cartesian_2d(0.5..k + 0.5, y_axis.clone())?;
    let yf = |v: &f64| y_axis.label_at(*v);
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc(y_label)
        .axis_desc_style(style::text(style::AXIS_DESC_PX))
        .label_style(label_font.clone())
        .bold_line_style(style::GRID)
        .light_line_style(TRANSPARENT)
        .x_label_formatter(&|_| String::new())
        .y_label_formatter(&yf)
        .draw()?;

    // The reference levels first, dashed under the boxes, each named at its right end.
    for l in levels {
        let colour = style::optimiser_colour(l.key).unwrap_or(style::GREY);
        let steps = 40;
        let dashes = (0..steps).step_by(2).map(|i| {
            let x = |j: usize| 0.5 + k * j as f64 / steps as f64;
            PathElement::new(vec![(x(i), l.y), (x(i + 1), l.y)], colour.stroke_width(2))
        });
        chart.draw_series(dashes)?;
        let (px, py) = chart.backend_coord(&(k + 0.5, l.y));
        root.draw(&Text::new(
            l.label.clone(),
            (px - 4, py - 4),
            style::text(12.0).color(&colour).pos(Pos::new(HPos::Right, VPos::Bottom)),
        ))?;
    }
    let slot_px =
        chart.backend_coord(&(1.5, y_axis.lo)).0 - chart.backend_coord(&(0.5, y_axis.lo)).0;
    let names: Vec<&str> = groups.iter().map(|(n, _)| n.as_str()).collect();
    for (i, ((name, _), st)) in groups.iter().zip(stats).enumerate() {
        let x = i as f64 + 1.0;
        let colour = style::series_colour(name, &names);
        if let Some(s) = st {
            let (l, r) = (x - 0.25, x + 0.25);
            chart.draw_series([
                Rectangle::new([(l, s.q3), (r, s.q1)], colour.mix(0.25).filled()),
                Rectangle::new([(l, s.q3), (r, s.q1)], colour.stroke_width(2)),
            ])?;
            chart.draw_series([
                PathElement::new(vec![(x, s.q3), (x, s.upper_whisker)], colour.stroke_width(2)),
                PathElement::new(vec![(x, s.q1), (x, s.lower_whisker)], colour.stroke_width(2)),
                PathElement::new(
                    vec![(x - 0.12, s.upper_whisker), (x + 0.12, s.upper_whisker)],
                    colour.stroke_width(2),
                ),
                PathElement::new(
                    vec![(x - 0.12, s.lower_whisker), (x + 0.12, s.lower_whisker)],
                    colour.stroke_width(2),
                ),
                PathElement::new(vec![(l, s.median), (r, s.median)], style::BLACK.stroke_width(3)),
            ])?;
            chart.draw_series(
                s.outliers.iter().map(|&o| Circle::new((x, o), 4, colour.stroke_width(2))),
            )?;
        }
        // Group name and count under the axis, cut to the slot width.
        let (px, py) = chart.backend_coord(&(x, y_axis.lo));
        let max_chars = ((slot_px - 6) / 8).max(3) as usize;
        let name = style::truncate(name, max_chars);
        root.draw(&Text::new(
            name,
            (px, py + 10),
            label_font.clone().pos(Pos::new(HPos::Center, VPos::Top)),
        ))?;
        let count = match st {
            Some(s) => format!("n = {}", s.n),
            None => "no data".to_string(),
        };
        root.draw(&Text::new(
            count,
            (px, py + 28),
            small_font.clone().pos(Pos::new(HPos::Center, VPos::Top)),
        ))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::*;

    #[test]
    fn type7_quartiles_match_r_quantile() {
        // R: quantile(1:10) -> 3.25, 5.5, 7.75; quantile(c(7,15,36,39,40,41)) -> 20.25, 37.5, 39.75.
        let a: Vec<f64> = (1..=10).map(f64::from).collect();
        let s = BoxStats::from_values(&a).unwrap();
        assert_eq!((s.q1, s.median, s.q3), (3.25, 5.5, 7.75));
        let s = BoxStats::from_values(&[41.0, 7.0, 36.0, 15.0, 40.0, 39.0]).unwrap();
        assert_eq!((s.q1, s.median, s.q3), (20.25, 37.5, 39.75));
    }

    #[test]
    fn tukey_whiskers_and_outliers() {
        // 1..10 and 50: q1 = 3.5, q3 = 8.5, fences -4 and 16: 50 is the only outlier.
        let mut v: Vec<f64> = (1..=10).map(f64::from).collect();
        v.push(50.0);
        let s = BoxStats::from_values(&v).unwrap();
        assert_eq!((s.q1, s.q3), (3.5, 8.5));
        assert_eq!((s.lower_whisker, s.upper_whisker), (1.0, 10.0));
        assert_eq!(s.outliers, vec![50.0]);
        let one = BoxStats::from_values(&[2.0]).unwrap();
        assert_eq!(
            (one.q1, one.median, one.q3, one.lower_whisker, one.upper_whisker),
            (2.0, 2.0, 2.0, 2.0, 2.0)
        );
    }

    #[test]
    fn non_finite_values_are_ignored() {
        let s =
            BoxStats::from_values(&[f64::NAN, 1.0, f64::INFINITY, 3.0, f64::NEG_INFINITY]).unwrap();
        assert_eq!(s.n, 2);
        assert_eq!(s.median, 2.0);
        assert!(BoxStats::from_values(&[f64::NAN]).is_none());
    }

    #[test]
    fn box_plot_writes_png_of_computed_size() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("box.png");
        let g = vec![
            ("ga".to_string(), vec![14.742470, 14.742475, 14.742481, 14.742466, 14.742488]),
            ("de".to_string(), vec![14.742461, 14.742462, 14.742461, 14.742463, f64::NAN]),
            ("empty".to_string(), vec![f64::NAN]),
        ];
        box_plot_png(&p, "Final fitness", "fitness", &g, &[]).unwrap();
        assert_eq!(png_size(&p), box_plot_size(3));
        assert_eq!(listing(dir.path()), vec!["box.png".to_string()]);
        assert_eq!(box_plot_size(20).0, 160 + 70 * 20);
    }

    /// Pixels of `colour` in a PNG written by the plots (palette or RGB).
    fn count_colour(path: &Path, colour: RGBColor) -> usize {
        let mut dec = png::Decoder::new(std::fs::File::open(path).unwrap());
        dec.set_transformations(png::Transformations::EXPAND);
        let mut reader = dec.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        let step = info.color_type.samples();
        buf[..info.buffer_size()]
            .chunks(step)
            .filter(|p| p[0] == colour.0 && p[1] == colour.1 && p[2] == colour.2)
            .count()
    }

    #[test]
    fn a_reference_level_is_drawn_even_above_every_box() {
        let dir = tempfile::tempdir().unwrap();
        let g = vec![("de".to_string(), vec![1.0, 1.1, 1.2]), ("pso".to_string(), vec![1.3, 1.4])];
        let (plain, with) = (dir.path().join("plain.png"), dir.path().join("with.png"));
        box_plot_png(&plain, "t", "y", &g, &[]).unwrap();
        let b = Level { key: "b", label: "B 2.0".into(), y: 2.0 };
        box_plot_png(&with, "t", "y", &g, &[b]).unwrap();
        let grey = style::optimiser_colour("b").unwrap();
        let (n0, n1) = (count_colour(&plain, grey), count_colour(&with, grey));
        assert!(n1 > n0 + 200, "the level B = 2.0 adds {} grey pixels", n1 as i64 - n0 as i64);
    }

    #[test]
    fn box_plot_errors_name_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nobox.png");
        let e = box_plot_png(&p, "t", "y", &[("a".into(), vec![f64::NAN])], &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("nobox.png"), "{e}");
        let q = missing_folder_path(dir.path());
        let e = box_plot_png(&q, "t", "y", &[("a".into(), vec![1.0, 2.0])], &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains(&q.display().to_string()), "{e}");
        assert!(listing(dir.path()).is_empty());
    }
}
