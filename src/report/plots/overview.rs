//! A page of small 3-D wireframes, one per (data set, model or grid size), laid out like the
//! thesis' Appendix A / D tables: rows are data sets, columns models or grid sizes, a caption on
//! each panel, one shared legend under the page title (repeating "bottom view / top view" in
//! every panel would crowd panels of ~300 px).

use super::mesh3d::{draw_meshes_with, LineMesh, View3d};
use super::style;
use super::{render_png, DrawError, PlotError};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// One cell of an overview page.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Panel {
    /// Caption above the panel (e.g. "Spindle, DNSOM 5 x 6").
    pub(crate) title: String,
    pub(crate) meshes: Vec<LineMesh>,
}

/// Height of the page title band (pixels) when there is a title or a legend.
const HEADER_PX: u32 = 62;

/// Pixel size of an overview page of `n_panels` in `cols` columns (cols clamped to 1..=n), each
/// panel [`style::PANEL_PX`] square, plus a header band. None when there is nothing to lay out.
pub(crate) fn overview_size(n_panels: usize, cols: usize) -> Option<(u32, u32)> {
    if n_panels == 0 || cols == 0 {
        return None;
    }
    let cols = cols.min(n_panels);
    let rows = n_panels.div_ceil(cols);
    let w = u32::try_from(cols).ok()?.checked_mul(style::PANEL_PX)?;
    let h = u32::try_from(rows).ok()?.checked_mul(style::PANEL_PX)?.checked_add(HEADER_PX)?;
    Some((w, h))
}

/// Writes a grid of wireframe panels, `cols` per row, to `path`.
pub(crate) fn overview_png(
    path: &Path,
    title: &str,
    panels: &[Panel],
    cols: usize,
) -> Result<(), PlotError> {
    let size = overview_size(panels.len(), cols).ok_or_else(|| {
        PlotError::input(path, format!("an overview needs at least one panel and one column (got {} panels, {cols} columns)", panels.len()))
    })?;
    let cols = cols.min(panels.len());
    // Legend entries: distinct (label, colour) pairs in order of first appearance.
    let mut legend: Vec<(String, RGBColor)> = Vec::new();
    for m in panels.iter().flat_map(|p| p.meshes.iter()) {
        if !m.label.is_empty() && !legend.iter().any(|(l, c)| *l == m.label && *c == m.colour) {
            legend.push((m.label.clone(), m.colour));
        }
    }
    render_png(path, size, |root| {
        let (header, body) = root.split_vertically(HEADER_PX);
        let (lines, px) = fit_title(&header, title, size.0.saturating_sub(16))?;
        for (k, line) in lines.iter().enumerate() {
            header.draw_text(
                line,
                &style::bold(px).pos(Pos::new(HPos::Center, VPos::Top)),
                (size.0 as i32 / 2, 6 + k as i32 * (px as i32 + 2)),
            )?;
        }
        draw_legend(&header, &legend, size.0)?;
        let rows = panels.len().div_ceil(cols);
        let cells = body.split_evenly((rows, cols));
        let view = View3d { tick_labels: false, scale: 0.8, ..View3d::default() };
        for (cell, panel) in cells.iter().zip(panels) {
            let (w, h) = cell.dim_in_pixel();
            cell.draw(&Rectangle::new(
                [(0, 0), (w as i32 - 1, h as i32 - 1)],
                style::GRID.stroke_width(1),
            ))?;
            let inner = cell.margin(4, 2, 2, 2);
            draw_meshes_with(&inner, &panel.title, &panel.meshes, view, false)
                .map_err(|e| DrawError::Input(format!("panel '{}': {e}", panel.title)))?;
        }
        Ok(())
    })
}

/// The title's lines and font size so that it fits `width` pixels: one line at the title size if
/// it fits, else one line at a smaller size (down to the label size), else two lines split at the
/// space nearest the middle.
fn fit_title(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    title: &str,
    width: u32,
) -> Result<(Vec<String>, f64), DrawError> {
    let fits = |text: &str, px: f64| -> Result<bool, DrawError> {
        Ok(area.estimate_text_size(text, &style::bold(px))?.0 <= width)
    };
    let mut px = style::TITLE_PX;
    while px >= style::LABEL_PX {
        if fits(title, px)? {
            return Ok((vec![title.to_string()], px));
        }
        px -= 1.0;
    }
    let mid = title.len() / 2;
    let split = title
        .char_indices()
        .filter(|&(_, c)| c == ' ')
        .map(|(i, _)| i)
        .min_by_key(|&i| i.abs_diff(mid));
    let lines = match split {
        Some(i) => vec![title[..i].to_string(), title[i + 1..].to_string()],
        None => vec![title.to_string()],
    };
    let mut px = style::LABEL_PX + 2.0;
    while px > 8.0
        && !lines.iter().map(|l| fits(l, px)).collect::<Result<Vec<_>, _>>()?.iter().all(|&f| f)
    {
        px -= 1.0;
    }
    Ok((lines, px))
}

/// A one-line legend centred in the lower half of the header band.
fn draw_legend(
    header: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    legend: &[(String, RGBColor)],
    width: u32,
) -> Result<(), DrawError> {
    if legend.is_empty() {
        return Ok(());
    }
    let ts = style::text(style::LABEL_PX);
    let widths: Vec<i32> = legend
        .iter()
        .map(|(l, _)| header.estimate_text_size(l, &ts).map(|(w, _)| w as i32 + 24 + 22))
        .collect::<Result<_, _>>()?;
    let total: i32 = widths.iter().sum();
    let mut x = (width as i32 - total).max(0) / 2;
    let y = HEADER_PX as i32 - 16;
    for ((label, colour), w) in legend.iter().zip(widths) {
        header.draw(&PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(3)))?;
        header.draw(&Text::new(
            label.clone(),
            (x + 24, y),
            ts.clone().pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
        x += w;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::mesh3d::grid_edges;
    use super::super::testutil::*;
    use super::*;

    fn plane(n: usize, tilt: f64, colour: RGBColor, label: &str) -> LineMesh {
        let mut points = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                points.push([x, y, tilt * x * y]);
            }
        }
        LineMesh { points, edges: grid_edges(n, n), colour, label: label.into() }
    }

    #[test]
    fn size_is_cols_by_rows_of_panels_plus_header() {
        let p = style::PANEL_PX;
        assert_eq!(overview_size(12, 4), Some((4 * p, 3 * p + HEADER_PX)));
        assert_eq!(overview_size(5, 4), Some((4 * p, 2 * p + HEADER_PX)));
        assert_eq!(
            overview_size(2, 4),
            Some((2 * p, p + HEADER_PX)),
            "cols clamped to panel count"
        );
        assert_eq!(overview_size(0, 4), None);
        assert_eq!(overview_size(3, 0), None);
    }

    #[test]
    fn overview_writes_png_of_computed_size() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("overview.png");
        let panels: Vec<Panel> = (0..6)
            .map(|i| Panel {
                title: format!("panel {i}"),
                meshes: vec![plane(5, i as f64 * 0.2, style::BLUE, "net")],
            })
            .collect();
        overview_png(&p, "Overview", &panels, 3).unwrap();
        assert_eq!(png_size(&p), overview_size(6, 3).unwrap());
        assert_eq!(listing(dir.path()), vec!["overview.png".to_string()]);
    }

    #[test]
    fn overview_errors_name_the_path_and_leave_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("empty.png");
        let e = overview_png(&p, "t", &[], 3).unwrap_err().to_string();
        assert!(e.contains("empty.png"), "{e}");
        let bad = Panel {
            title: "broken".into(),
            meshes: vec![LineMesh {
                points: vec![],
                edges: vec![(0, 1)],
                colour: style::BLUE,
                label: String::new(),
            }],
        };
        let e = overview_png(&p, "t", &[bad], 1).unwrap_err().to_string();
        assert!(e.contains("empty.png") && e.contains("broken"), "{e}");
        let q = missing_folder_path(dir.path());
        let ok = Panel { title: "ok".into(), meshes: vec![plane(3, 0.0, style::BLUE, "")] };
        let e = overview_png(&q, "t", &[ok], 1).unwrap_err().to_string();
        assert!(e.contains(&q.display().to_string()), "{e}");
        assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
    }

    #[test]
    fn a_long_title_fits_the_page() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.png");
        let title = "Appendix D: CKSOM and DNSOM with different width and length of grid";
        let mut lines = Vec::new();
        render_png(&p, (600, 100), |root| {
            let (l, px) = fit_title(root, title, 584)?;
            for line in &l {
                assert!(
                    root.estimate_text_size(line, &style::bold(px))?.0 <= 584,
                    "{line} at {px}"
                );
            }
            lines = l;
            Ok(())
        })
        .unwrap();
        assert_eq!(lines.join(" "), title);
        assert!(lines.len() <= 2);
    }

    #[test]
    fn overview_tolerates_nan_points() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nan.png");
        let mut m = plane(4, 1.0, style::VERMILLION, "net");
        m.points[5] = [f64::NAN, 1.0, 1.0];
        overview_png(&p, "NaN", &[Panel { title: "nan".into(), meshes: vec![m] }], 2).unwrap();
        assert_eq!(png_size(&p), overview_size(1, 2).unwrap());
    }
}
