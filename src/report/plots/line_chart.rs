//! Line charts with optional quartile bands: surface error against control-net size, and
//! convergence curves (median best fitness against evaluations, with the inter-quartile band
//! over the repeats), optionally on a log y axis.
//!
//! Why the care with values: traces contain NaN/inf when a run diverges or has not started, and
//! log axes cannot show zeros; such points are dropped and the line is broken there rather than
//! bridged, so no value is invented. Axes come from [`super::scale`] (readable on ranges as
//! narrow as the thesis' seven-digit fitness agreement). The legend sits outside the plot, on
//! the right, so it can never hide a curve.

use super::scale::{extent, Axis};
use super::style;
use super::{render_png, DrawError, PlotError};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// One curve: `points` (x, y) in drawing order, and optionally a band of (x, lower, upper)
/// drawn as a translucent area (e.g. the quartiles over repeats around the median).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Series {
    pub(crate) label: String,
    pub(crate) colour: RGBColor,
    pub(crate) points: Vec<(f64, f64)>,
    pub(crate) band: Option<Vec<(f64, f64, f64)>>,
}

/// Maximal runs of consecutive items for which `f` gives a value (a break wherever it gives None).
pub(crate) fn runs<T, U>(items: &[T], f: impl Fn(&T) -> Option<U>) -> Vec<Vec<U>> {
    let mut out = Vec::new();
    let mut cur = Vec::new();
    for it in items {
        match f(it) {
            Some(u) => cur.push(u),
            None => {
                if !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
            }
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Longest legend label, in characters.
const LEGEND_CHARS: usize = 36;
/// Series with at most this many points also get a marker on every point.
const MARKER_LIMIT: usize = 40;

/// Writes a line chart of `series` to `path` ([`style::CHART_SIZE`] pixels). Non-finite points
/// (and, with `log_y`, non-positive y) are left out; it is an error only when no point at all
/// can be drawn.
pub(crate) fn line_chart_png(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_y: bool,
) -> Result<(), PlotError> {
    let (x_ext, y_axis) = axes(path, series, log_y)?;
    render_png(path, style::CHART_SIZE, |root| {
        draw_line_chart(root, title, x_label, y_label, series, x_ext, &y_axis).map(|_| ())
    })
}

/// A line chart of points in a plane (an outline, a top view) with equal scales on both axes,
/// so a circle is drawn round: the shorter data range is widened about its centre until a unit
/// takes as many pixels across as up.
pub(crate) fn xy_chart_png(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), PlotError> {
    // The data's extents; Axis::linear pads both by the same factor, keeping the aspect.
    let (x_ext, y_ext) = extents(path, series, false)?;
    render_png(path, style::CHART_SIZE, |root| {
        // Measure the plotting area, widen one range to its aspect and draw again (the y labels'
        // width can move the area by a few pixels, so until it stays put).
        let draw = |xe: (f64, f64), ye: (f64, f64)| {
            let y_axis = Axis::linear(ye.0, ye.1, 7);
            draw_line_chart(root, title, x_label, y_label, series, xe, &y_axis)
        };
        let mut dims = draw(x_ext, y_ext)?;
        for _ in 0..3 {
            let (xe, ye) = equal_scale(x_ext, y_ext, dims);
            root.fill(&WHITE)?;
            let now = draw(xe, ye)?;
            if now == dims {
                break;
            }
            dims = now;
        }
        Ok(())
    })
}

/// The extents widened so that one unit takes as many pixels in x as in y on a plotting area of
/// `dims` pixels (the longer range per pixel is kept; the other is centred).
fn equal_scale(x: (f64, f64), y: (f64, f64), dims: (u32, u32)) -> ((f64, f64), (f64, f64)) {
    let (w, h) = (f64::from(dims.0.max(1)), f64::from(dims.1.max(1)));
    let per_px = ((x.1 - x.0) / w).max((y.1 - y.0) / h);
    let widen = |e: (f64, f64), px: f64| {
        let (mid, half) = (e.0 / 2.0 + e.1 / 2.0, per_px * px / 2.0);
        (mid - half, mid + half)
    };
    (widen(x, w), widen(y, h))
}

/// Size of one panel of [`small_multiples_png`].
pub(crate) const SMALL_PANEL: (u32, u32) = (600, 400);
/// Height of the title band of [`small_multiples_png`].
const SMALL_HEADER_PX: u32 = 44;

/// Small multiples: one line chart per `(caption, series)` panel, `cols` per row, on one shared
/// x range and y axis (so panels compare at a glance), under one page title. For many curves
/// that overlap on one chart (e.g. four parameterisations x two approaches).
pub(crate) fn small_multiples_png(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    panels: &[(String, Vec<Series>)],
    cols: usize,
    log_y: bool,
) -> Result<(), PlotError> {
    let all: Vec<Series> = panels.iter().flat_map(|p| p.1.iter().cloned()).collect();
    let (x_ext, y_axis) = axes(path, &all, log_y)?;
    let cols = cols.clamp(1, panels.len().max(1));
    let rows = panels.len().div_ceil(cols) as u32;
    let size = (SMALL_PANEL.0 * cols as u32, SMALL_PANEL.1 * rows + SMALL_HEADER_PX);
    render_png(path, size, |root| {
        let (header, body) = root.split_vertically(SMALL_HEADER_PX);
        header.draw_text(
            title,
            &style::bold(style::TITLE_PX).pos(Pos::new(HPos::Center, VPos::Top)),
            (size.0 as i32 / 2, 10),
        )?;
        let cells = body.split_evenly((rows as usize, cols));
        for (cell, (caption, series)) in cells.iter().zip(panels) {
            draw_line_chart(cell, caption, x_label, y_label, series, x_ext, &y_axis)?;
        }
        Ok(())
    })
}

/// The x extent and the y axis that show every drawable point of `series`.
fn axes(path: &Path, series: &[Series], log_y: bool) -> Result<((f64, f64), Axis), PlotError> {
    let (x_ext, y_ext) = extents(path, series, log_y)?;
    let y_axis = if log_y {
        Axis::log10(y_ext.0, y_ext.1, 7)
            .ok_or_else(|| PlotError::input(path, "log axis without positive values"))?
    } else {
        Axis::linear(y_ext.0, y_ext.1, 7)
    };
    Ok((x_ext, y_axis))
}

/// A (least, greatest) range of values.
type Span = (f64, f64);

/// The x and y extents of every drawable point of `series` (an error naming `path` without one).
fn extents(path: &Path, series: &[Series], log_y: bool) -> Result<(Span, Span), PlotError> {
    let ok_y = |y: f64| if log_y { y > 0.0 } else { true };
    let xs = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0).chain(s.band.iter().flatten().map(|b| b.0)));
    let ys = series.iter().flat_map(|s| {
        s.points
            .iter()
            .filter(|p| p.0.is_finite())
            .map(|p| p.1)
            .chain(s.band.iter().flatten().filter(|b| b.0.is_finite()).flat_map(|b| [b.1, b.2]))
    });
    match (extent(xs), extent(ys.filter(|y| ok_y(*y)))) {
        (Some(x), Some(y)) => Ok((x, y)),
        _ => Err(PlotError::input(
            path,
            format!(
                "no drawable point in {} series (all values non-finite{})",
                series.len(),
                if log_y { " or not positive on the log axis" } else { "" }
            ),
        )),
    }
}

/// A linear x axis with at most 8 ticks, fewer until their labels fit in 60 % of `plot_w`.
fn fit_x_axis(
    root: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    x_ext: (f64, f64),
    plot_w: i32,
    label_font: &TextStyle<'static>,
) -> Result<Axis, DrawError> {
    let mut x_axis = Axis::linear(x_ext.0, x_ext.1, 8);
    for target in (2..8).rev() {
        let w = style::text_width(root, x_axis.widest_label(), label_font)? + 16;
        if w * x_axis.ticks.len() as i32 <= plot_w * 6 / 10 {
            break;
        }
        x_axis = Axis::linear(x_ext.0, x_ext.1, target);
    }
    Ok(x_axis)
}

fn draw_line_chart(
    root: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    x_ext: (f64, f64),
    y_axis: &Axis,
) -> Result<(u32, u32), DrawError> {
    let label_font = style::text(style::LABEL_PX);
    let names: Vec<String> = series
        .iter()
        .map(|s| {
            let drawable =
                s.points.iter().any(|p| y_axis.to_plot(p.1).is_some() && p.0.is_finite());
            let name = style::truncate(&s.label, LEGEND_CHARS);
            if drawable {
                name
            } else {
                format!("{name} (no data)")
            }
        })
        .collect();
    let mut legend_w = 0;
    for n in &names {
        legend_w = legend_w.max(style::text_width(root, n, &label_font)?);
    }
    let legend_w = if series.is_empty() { 0 } else { legend_w + 60 };
    let (chart_area, legend_area) =
        root.split_horizontally(root.dim_in_pixel().0 as i32 - legend_w);

    let y_label_w = style::text_width(root, y_axis.widest_label(), &label_font)?;
    // Fewer x ticks until their labels fit in 60 % of the plot width.
    let plot_w = chart_area.dim_in_pixel().0 as i32 - y_label_w - 80;
    let x_axis = fit_x_axis(root, x_ext, plot_w, &label_font)?;

    let mut chart = ChartBuilder::on(&chart_area)
        .margin(12)
        .caption(title, style::bold(style::TITLE_PX))
        .x_label_area_size(52)
        .y_label_area_size(y_label_w + 42)
        .build_cartesian_2d(x_axis.clone(), y_axis.clone())?;
    let xf = |v: &f64| x_axis.label_at(*v);
    let yf = |v: &f64| y_axis.label_at(*v);
    let y_desc = if y_axis.log { format!("{y_label} (log scale)") } else { y_label.to_string() };
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_desc)
        .axis_desc_style(style::text(style::AXIS_DESC_PX))
        .label_style(label_font.clone())
        .bold_line_style(style::GRID)
        .light_line_style(TRANSPARENT)
        .x_label_formatter(&xf)
        .y_label_formatter(&yf)
        .draw()?;

    let x_of = |x: f64| x_axis.to_plot(x);
    let y_of = |y: f64| y_axis.to_plot(y);
    // Bands first, so every line stays visible on top of every band.
    for s in series {
        if let Some(band) = &s.band {
            for run in runs(band, |&(x, lo, hi)| Some((x_of(x)?, y_of(lo)?, y_of(hi)?))) {
                if run.len() < 2 {
                    continue;
                }
                let mut poly: Vec<(f64, f64)> = run.iter().map(|&(x, _, hi)| (x, hi)).collect();
                poly.extend(run.iter().rev().map(|&(x, lo, _)| (x, lo)));
                chart.draw_series(std::iter::once(Polygon::new(
                    poly,
                    s.colour.mix(0.18).filled(),
                )))?;
                // Thin edges make the band readable where it is only a pixel wide.
                for edge in [
                    run.iter().map(|r| (r.0, r.2)).collect::<Vec<_>>(),
                    run.iter().map(|r| (r.0, r.1)).collect(),
                ] {
                    chart.draw_series(std::iter::once(PathElement::new(
                        edge,
                        s.colour.mix(0.35).stroke_width(1),
                    )))?;
                }
            }
        }
    }
    for s in series {
        let pts = runs(&s.points, |&(x, y)| Some((x_of(x)?, y_of(y)?)));
        for run in &pts {
            chart.draw_series(std::iter::once(PathElement::new(
                run.clone(),
                s.colour.stroke_width(2),
            )))?;
        }
        let n: usize = pts.iter().map(|r| r.len()).sum();
        if n <= MARKER_LIMIT {
            chart
                .draw_series(pts.iter().flatten().map(|&p| Circle::new(p, 3, s.colour.filled())))?;
        }
    }

    // Legend, top-aligned with the plot.
    let top = chart.plotting_area().get_base_pixel().1 - root.get_base_pixel().1;
    draw_legend(&legend_area, series, &names, top, &label_font)?;
    Ok(chart.plotting_area().dim_in_pixel())
}

/// The legend: per series a swatch (band patch behind a line) and its label, from `top` down.
fn draw_legend(
    legend_area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    series: &[Series],
    names: &[String],
    top: i32,
    label_font: &TextStyle<'static>,
) -> Result<(), DrawError> {
    let row_h = 24;
    for (i, (s, name)) in series.iter().zip(names).enumerate() {
        let y = top + 8 + i as i32 * row_h;
        let x = 8;
        if s.band.is_some() {
            legend_area.draw(&Rectangle::new(
                [(x, y - 7), (x + 26, y + 7)],
                s.colour.mix(0.18).filled(),
            ))?;
        }
        legend_area.draw(&PathElement::new(vec![(x, y), (x + 26, y)], s.colour.stroke_width(2)))?;
        legend_area.draw(&Text::new(
            name.clone(),
            (x + 34, y),
            label_font.clone().pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::*;

    #[test]
    fn equal_scale_widens_the_shorter_range_about_its_centre() {
        // x: 10 units over 200 px (0.05 per px); y: 1 unit over 100 px -> 5 units about 0.5.
        let (x, y) = equal_scale((0.0, 10.0), (0.0, 1.0), (200, 100));
        assert_eq!(x, (0.0, 10.0));
        assert!((y.0 + 2.0).abs() < 1e-12 && (y.1 - 3.0).abs() < 1e-12, "{y:?}");
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("xy.png");
        let circle: Vec<(f64, f64)> = (0..=64)
            .map(|k| k as f64 / 64.0 * std::f64::consts::TAU)
            .map(|t| (t.cos(), 0.2 * t.sin()))
            .collect();
        let s = Series { label: "ellipse".into(), colour: style::BLUE, points: circle, band: None };
        xy_chart_png(&p, "equal axes", "x", "y", &[s]).unwrap();
        assert_eq!(png_size(&p), style::CHART_SIZE);
    }

    fn conv(label: &str, colour: RGBColor, scale: f64) -> Series {
        let pts: Vec<(f64, f64)> = (0..50)
            .map(|i| (i as f64 * 40.0, 14.742461 + scale * 1e-6 * (-(i as f64) / 10.0).exp()))
            .collect();
        let band = pts.iter().map(|&(x, y)| (x, y - 2e-7, y + 3e-7)).collect();
        Series { label: label.into(), colour, points: pts, band: Some(band) }
    }

    #[test]
    fn runs_break_at_missing_values() {
        let v = [1.0, f64::NAN, 2.0, 3.0, f64::INFINITY];
        let r = runs(&v, |x| x.is_finite().then_some(*x));
        assert_eq!(r, vec![vec![1.0], vec![2.0, 3.0]]);
    }

    #[test]
    fn line_chart_writes_png_of_chart_size() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("conv.png");
        let s = [conv("DE", style::BLUE, 27.0), conv("GA", style::ORANGE, 20.0)];
        line_chart_png(&p, "Convergence", "evaluations", "best fitness", &s, false).unwrap();
        assert_eq!(png_size(&p), style::CHART_SIZE);
        line_chart_png(&p, "Convergence", "evaluations", "best fitness", &s, true).unwrap();
        assert_eq!(png_size(&p), style::CHART_SIZE);
        assert_eq!(listing(dir.path()), vec!["conv.png".to_string()]);
    }

    #[test]
    fn nan_and_inf_are_dropped_not_fatal() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nan.png");
        let mut s = conv("PSO", style::GREEN, 10.0);
        s.points[3].1 = f64::NAN;
        s.points[7].1 = f64::INFINITY;
        s.points[9].0 = f64::NEG_INFINITY;
        if let Some(b) = s.band.as_mut() {
            b[4].1 = f64::NAN;
            b[5].2 = f64::INFINITY;
        }
        let all_nan = Series {
            label: "broken".into(),
            colour: style::PURPLE,
            points: vec![(1.0, f64::NAN); 5],
            band: None,
        };
        line_chart_png(&p, "NaN", "x", "y", &[s.clone(), all_nan.clone()], false).unwrap();
        // Log axis: zeros and negatives are dropped too.
        s.points[10].1 = 0.0;
        s.points[11].1 = -1.0;
        line_chart_png(&p, "NaN", "x", "y", &[s, all_nan], true).unwrap();
        assert_eq!(png_size(&p), style::CHART_SIZE);
    }

    #[test]
    fn nothing_drawable_is_an_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("empty.png");
        let s = Series {
            label: "a".into(),
            colour: style::BLUE,
            points: vec![(0.0, f64::NAN)],
            band: None,
        };
        let e = line_chart_png(&p, "t", "x", "y", &[s], false).unwrap_err().to_string();
        assert!(e.contains("empty.png"), "{e}");
        let z = Series {
            label: "a".into(),
            colour: style::BLUE,
            points: vec![(0.0, 0.0), (1.0, -2.0)],
            band: None,
        };
        let e = line_chart_png(&p, "t", "x", "y", &[z], true).unwrap_err().to_string();
        assert!(e.contains("empty.png") && e.contains("log"), "{e}");
        let e = line_chart_png(&p, "t", "x", "y", &[], false).unwrap_err().to_string();
        assert!(e.contains("empty.png"), "{e}");
        assert!(listing(dir.path()).is_empty());
    }

    #[test]
    fn missing_folder_names_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = missing_folder_path(dir.path());
        let e = line_chart_png(&p, "t", "x", "y", &[conv("DE", style::BLUE, 1.0)], false)
            .unwrap_err()
            .to_string();
        assert!(e.contains(&p.display().to_string()), "{e}");
        assert!(listing(dir.path()).is_empty());
    }

    #[test]
    fn single_point_and_constant_series_draw() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("one.png");
        let s = Series {
            label: "B".into(),
            colour: style::GREY,
            points: vec![(5.0, 14.7)],
            band: None,
        };
        line_chart_png(&p, "one point", "x", "y", &[s], false).unwrap();
        assert_eq!(png_size(&p), style::CHART_SIZE);
    }
}
