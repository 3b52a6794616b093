//! 3-D wireframes of SOM grids, control nets and surfaces: the building block of the thesis'
//! visualisation tables (Table 4.8, Appendices A, B, D, I, J), which show each model as lines
//! between neighbouring neurons.
//!
//! Why it projects points itself: a 30 x 30 x 30 lattice has ~78k edges, so each point is
//! projected once and edges are drawn in pixel space, back to front (painter's order over all
//! meshes, so the near side of a closed DNSOM surface covers the far side), with far edges faded
//! toward white as a depth cue. The cube shown is the meshes' bounding box made cubic (equal
//! scale on all axes: a sphere stays round). Data z is drawn vertical.

use super::scale::plottable;
use super::style;
use super::{render_png, DrawError, PlotError};
use crate::geom::Point3;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// A set of 3-D points joined by straight edges (indices into `points`), drawn in one colour.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LineMesh {
    pub(crate) points: Vec<Point3>,
    pub(crate) edges: Vec<(u32, u32)>,
    pub(crate) colour: RGBColor,
    /// Legend text; meshes with an empty label get no legend entry.
    pub(crate) label: String,
}

/// `other` drawn as its difference from `base` magnified: each point `b + k (o - b)`, with `k`
/// chosen so the largest difference is `frac` of the base's largest bounding-box side (for two
/// surfaces that differ by too little to see). Meshes pair up in order and must have as many
/// points; returns the magnified meshes, `k` and the largest difference (None when nothing differs
/// or the meshes do not pair up).
pub(crate) fn magnified_difference(
    base: &[LineMesh],
    other: &[LineMesh],
    frac: f64,
) -> Option<(Vec<LineMesh>, f64, f64)> {
    if base.len() != other.len()
        || base.iter().zip(other).any(|(b, o)| b.points.len() != o.points.len())
    {
        return None;
    }
    let dist = |a: &Point3, b: &Point3| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let max_diff = base
        .iter()
        .zip(other)
        .flat_map(|(b, o)| b.points.iter().zip(&o.points).map(|(p, q)| dist(p, q)))
        .filter(|d| d.is_finite())
        .fold(0.0f64, f64::max);
    let (lo, hi) = base
        .iter()
        .flat_map(|m| m.points.iter())
        .filter(|p| p.iter().all(|c| c.is_finite()))
        .fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(lo, hi), p| {
            ([0, 1, 2].map(|a| lo[a].min(p[a])), [0, 1, 2].map(|a| hi[a].max(p[a])))
        });
    let side = (0..3).map(|a| hi[a] - lo[a]).fold(0.0f64, f64::max);
    if max_diff <= 0.0 || side.is_nan() || side <= 0.0 {
        return None;
    }
    let k = frac * side / max_diff;
    let meshes = base
        .iter()
        .zip(other)
        .map(|(b, o)| LineMesh {
            points: b
                .points
                .iter()
                .zip(&o.points)
                .map(|(p, q)| [0, 1, 2].map(|a| p[a] + k * (q[a] - p[a])))
                .collect(),
            ..o.clone()
        })
        .collect();
    Some((meshes, k, max_diff))
}

/// Viewing direction of a 3-D picture (plotters' projection: yaw about the vertical axis, then
/// pitch, in radians; `scale` shrinks the cube to fit its corners into the area).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct View3d {
    pub(crate) yaw: f64,
    pub(crate) pitch: f64,
    pub(crate) scale: f64,
    /// Draw tick labels on the axes (off for small overview panels).
    pub(crate) tick_labels: bool,
}

impl Default for View3d {
    /// A three-quarter view from slightly above, similar to GNUPlot's default `splot` view.
    fn default() -> Self {
        View3d { yaw: 0.65, pitch: 0.35, scale: 0.78, tick_labels: true }
    }
}

/// Edges of the 4-neighbourhood of a row-major `nx` x `ny` grid (node (i, j) has index i*ny + j).
pub(crate) fn grid_edges(nx: usize, ny: usize) -> Vec<(u32, u32)> {
    let mut e = Vec::with_capacity(2 * nx * ny);
    let id = |i: usize, j: usize| (i * ny + j) as u32;
    for i in 0..nx {
        for j in 0..ny {
            if i + 1 < nx {
                e.push((id(i, j), id(i + 1, j)));
            }
            if j + 1 < ny {
                e.push((id(i, j), id(i, j + 1)));
            }
        }
    }
    e
}

/// Edges of the 6-neighbourhood of an `n` x `n` x `n` lattice (node (i, j, k) has index
/// (i*n + j)*n + k), as in the 3-D SOM of thesis Section 2.
#[cfg(test)]
pub(crate) fn lattice_edges(n: usize) -> Vec<(u32, u32)> {
    let mut e = Vec::with_capacity(3 * n * n * n);
    let id = |i: usize, j: usize, k: usize| ((i * n + j) * n + k) as u32;
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                if i + 1 < n {
                    e.push((id(i, j, k), id(i + 1, j, k)));
                }
                if j + 1 < n {
                    e.push((id(i, j, k), id(i, j + 1, k)));
                }
                if k + 1 < n {
                    e.push((id(i, j, k), id(i, j, k + 1)));
                }
            }
        }
    }
    e
}

/// Centre and half side of the cube shown: the bounding box of the points drawn (the ends of the
/// edges whose two ends are finite: a dense wireframe's points between its drawn lines do not
/// count) made cubic, widened by 8 % (so end ticks sit away from the cube corners); the unit cube
/// when nothing is drawn.
fn view_cube(meshes: &[LineMesh]) -> ([f64; 3], f64) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let drawn = |p: &Point3| p.iter().all(|c| plottable(*c));
    for m in meshes {
        let point = |i: u32| m.points.get(i as usize).filter(|p| drawn(p));
        for &(a, b) in &m.edges {
            let (Some(pa), Some(pb)) = (point(a), point(b)) else { continue };
            for p in [pa, pb] {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
    }
    if lo[0] > hi[0] {
        return ([0.5; 3], 0.5);
    }
    let centre = [0, 1, 2].map(|a| lo[a] / 2.0 + hi[a] / 2.0);
    let half = (0..3).map(|a| hi[a] / 2.0 - lo[a] / 2.0).fold(0.0f64, f64::max);
    let half = if half > 0.0 {
        half * 1.08
    } else {
        centre.iter().fold(0.0f64, |m, c| m.max(c.abs())).max(1.0) * 0.05
    };
    (centre, half)
}

/// One projected edge: summed end depths, mesh index, pixel ends.
type Segment = (i32, u32, (i32, i32), (i32, i32));

/// Checks every edge index and the view; the message names the mesh and the edge.
fn validate(meshes: &[LineMesh], view: &View3d) -> Result<(), DrawError> {
    if ![view.yaw, view.pitch, view.scale].iter().all(|v| v.is_finite()) || view.scale <= 0.0 {
        return Err(DrawError::Input(format!(
            "view needs finite yaw/pitch and a positive scale, got yaw {} pitch {} scale {}",
            view.yaw, view.pitch, view.scale
        )));
    }
    for (mi, m) in meshes.iter().enumerate() {
        let n = m.points.len();
        if let Some((ei, &(a, b))) =
            m.edges.iter().enumerate().find(|(_, &(a, b))| a as usize >= n || b as usize >= n)
        {
            return Err(DrawError::Input(format!(
                "mesh {mi} ('{}'): edge {ei} = ({a}, {b}) refers past its {n} points",
                m.label
            )));
        }
    }
    Ok(())
}

/// Draws `meshes` as one 3-D wireframe picture on `area`, with `title` above (none if empty)
/// and a legend of the labelled meshes. Edges touching a non-finite point are skipped.
pub(crate) fn draw_meshes(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    title: &str,
    meshes: &[LineMesh],
    view: View3d,
) -> Result<(), DrawError> {
    draw_meshes_with(area, title, meshes, view, true)
}

/// [`draw_meshes`] with the legend optional (an overview draws one shared legend instead).
pub(crate) fn draw_meshes_with(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    title: &str,
    meshes: &[LineMesh],
    view: View3d,
    legend: bool,
) -> Result<(), DrawError> {
    style::ensure_fonts()?;
    validate(meshes, &view)?;
    let (w, h) = area.dim_in_pixel();
    let small = w.min(h) < 420;
    let (centre, half) = view_cube(meshes);
    let r = |a: usize| (centre[a] - half)..(centre[a] + half);

    // A title too wide for the picture shrinks, then wraps (the lines above the last are put on
    // the area first; the chart's own caption is the last).
    let margin = if small { 2 } else { 10 };
    let px = if small { style::CAPTION_PX } else { style::TITLE_PX };
    let (mut lines, px) = style::fitted_title(area, title, px, w as i32 - 2 * margin - 4)?;
    let last = lines.pop().unwrap_or_default();
    let mut plot_area = area.clone();
    for line in &lines {
        plot_area = plot_area
            .titled(line, style::bold(px))
            .map_err(|e| DrawError::Backend(e.to_string()))?;
    }
    let mut builder = ChartBuilder::on(&plot_area);
    builder.margin(margin as u32);
    if !last.is_empty() {
        builder.caption(&last, style::bold(px));
    }
    // plotters' Y axis is the vertical one: (data x, data z, data y).
    let mut chart = builder.build_cartesian_3d(r(0), r(2), r(1))?;
    chart.with_projection(|mut pb| {
        pb.yaw = view.yaw;
        pb.pitch = view.pitch;
        pb.scale = view.scale;
        pb.into_matrix()
    });
    let fmt = |v: &f64| {
        let d = if half >= 0.5 { 1 } else { ((-(half.log10())).ceil() as usize + 1).min(12) };
        format!("{:.*}", d, v)
    };
    let blank = |_: &f64| String::new();
    // Two axes meet at each corner of the box: end labels there print on top of each other
    // ("1.01.0"). The vertical axis and the depth axis leave out labels near their ends (the
    // data's ends sit 7 % of a half side inside the box); the first axis keeps all of its labels.
    let inside =
        |a: usize, v: f64| (v - (centre[a] - half)).min(centre[a] + half - v) >= 0.2 * half;
    let fmt_vertical = |v: &f64| if inside(2, *v) { fmt(v) } else { String::new() };
    let fmt_depth = |v: &f64| if inside(1, *v) { fmt(v) } else { String::new() };
    {
        let mut axes = chart.configure_axes();
        axes.light_grid_style(style::GRID.mix(0.5))
            .bold_grid_style(style::GRID)
            .axis_panel_style(RGBColor(248, 248, 248).filled())
            .max_light_lines(1)
            .label_style(style::text(if small { 10.0 } else { 12.0 }).color(&style::GREY));
        if view.tick_labels {
            axes.x_labels(3).y_labels(3).z_labels(3).tick_size(4);
            axes.x_formatter(&fmt).y_formatter(&fmt_vertical).z_formatter(&fmt_depth);
        } else {
            axes.x_labels(3).y_labels(3).z_labels(3).tick_size(0);
            axes.x_formatter(&blank).y_formatter(&blank).z_formatter(&blank);
        }
        axes.draw()?;
    }

    // Project every point once: pixel position and depth (larger = farther from the viewer).
    let plot = chart.plotting_area();
    let coord = plot.as_coord_spec();
    let mut segs: Vec<Segment> = Vec::new();
    for (mi, m) in meshes.iter().enumerate() {
        let proj: Vec<Option<((i32, i32), i32)>> = m
            .points
            .iter()
            .map(|p| {
                p.iter().all(|c| plottable(*c)).then(|| {
                    let q = (p[0], p[2], p[1]);
                    (plot.map_coordinate(&q), coord.projected_depth(&q.0, &q.1, &q.2))
                })
            })
            .collect();
        segs.reserve(m.edges.len());
        for &(a, b) in &m.edges {
            if let (Some((pa, da)), Some((pb, db))) = (proj[a as usize], proj[b as usize]) {
                segs.push((da + db, mi as u32, pa, pb));
            }
        }
    }
    // Back to front; stable, so equal depths keep mesh order.
    segs.sort_by_key(|s| std::cmp::Reverse(s.0));
    let (dmin, dmax) =
        segs.iter().fold((i32::MAX, i32::MIN), |(lo, hi), s| (lo.min(s.0), hi.max(s.0)));
    let span = (dmax as f64 - dmin as f64).max(1.0);
    let screen = plot.use_screen_coord();
    let dense = segs.len() > 20_000;
    for (d, mi, pa, pb) in segs {
        // Far edges fade toward white (up to 60 %), so front and back of a closed net separate.
        let far = (d as f64 - dmin as f64) / span;
        let c = meshes[mi as usize].colour;
        let fade = 0.6 * far + if dense { 0.15 } else { 0.0 };
        let mixc = |v: u8| (v as f64 + (255.0 - v as f64) * fade).round().clamp(0.0, 255.0) as u8;
        let colour = RGBColor(mixc(c.0), mixc(c.1), mixc(c.2));
        screen.draw(&PathElement::new(vec![pa, pb], colour.stroke_width(1)))?;
    }

    if legend {
        draw_legend(area, plot.get_base_pixel(), meshes, small)?;
    }
    Ok(())
}

/// The legend of the labelled meshes in the upper-left corner of the plotting area, whose top
/// left pixel is `(x0, y0)`.
fn draw_legend(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    (x0, y0): (i32, i32),
    meshes: &[LineMesh],
    small: bool,
) -> Result<(), DrawError> {
    let ts = style::text(if small { 12.0 } else { style::LABEL_PX });
    let line_h = if small { 14 } else { 19 };
    for (i, m) in meshes.iter().filter(|m| !m.label.is_empty()).enumerate() {
        let y = y0 + 6 + i as i32 * line_h + line_h / 2;
        let x = x0 + 6;
        area.use_screen_coord()
            .draw(&PathElement::new(vec![(x, y), (x + 18, y)], m.colour.stroke_width(3)))?;
        area.use_screen_coord().draw(&Text::new(
            m.label.clone(),
            (x + 24, y),
            ts.clone().pos(plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Left,
                plotters::style::text_anchor::VPos::Center,
            )),
        ))?;
    }
    Ok(())
}

/// Writes one wireframe picture of `size` pixels to `path` (a `.png` file in an existing folder).
pub(crate) fn mesh_png(
    path: &Path,
    title: &str,
    meshes: &[LineMesh],
    size: (u32, u32),
) -> Result<(), PlotError> {
    validate(meshes, &View3d::default())
        .map_err(|source| PlotError::Draw { path: path.to_path_buf(), source })?;
    render_png(path, size, |root| draw_meshes(root, title, meshes, View3d::default()))
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::*;

    /// A UV sphere split at the equator into two `n` x `n` grids, like the DNSOM bottom/top views.
    pub(crate) fn two_view_sphere(n: usize) -> Vec<LineMesh> {
        let view = |top: bool| {
            let mut pts = Vec::with_capacity(n * n);
            for i in 0..n {
                for j in 0..n {
                    // Map the square to a hemisphere (a disc lifted onto the sphere).
                    let u = 2.0 * i as f64 / (n - 1) as f64 - 1.0;
                    let v = 2.0 * j as f64 / (n - 1) as f64 - 1.0;
                    let (x, y) = (u * (1.0 - v * v / 2.0).sqrt(), v * (1.0 - u * u / 2.0).sqrt());
                    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
                    let z = if top { z } else { -z };
                    pts.push([0.5 + 0.5 * x, 0.5 + 0.5 * y, 0.5 + 0.5 * z]);
                }
            }
            LineMesh {
                points: pts,
                edges: grid_edges(n, n),
                colour: if top { style::DNSOM_TOP } else { style::DNSOM_BOTTOM },
                label: if top { "top view".into() } else { "bottom view".into() },
            }
        };
        vec![view(false), view(true)]
    }

    #[test]
    fn grid_edges_count_and_neighbourhood() {
        let e = grid_edges(4, 5);
        // (nx-1)*ny + nx*(ny-1) edges of a 4-neighbourhood.
        assert_eq!(e.len(), 3 * 5 + 4 * 4);
        assert!(e.contains(&(0, 1)) && e.contains(&(0, 5)) && !e.contains(&(4, 5)));
        assert!(e.iter().all(|&(a, b)| a < 20 && b < 20 && a < b));
        assert!(grid_edges(0, 3).is_empty() && grid_edges(1, 1).is_empty());
    }

    #[test]
    fn lattice_edges_count_and_neighbourhood() {
        let e = lattice_edges(30);
        assert_eq!(e.len(), 3 * 29 * 30 * 30);
        let e3 = lattice_edges(3);
        assert!(e3.contains(&(0, 1)) && e3.contains(&(0, 3)) && e3.contains(&(0, 9)));
        assert!(!e3.contains(&(2, 3)), "wraps across a row");
        let mut s = e3.clone();
        s.sort();
        s.dedup();
        assert_eq!(s.len(), e3.len());
    }

    #[test]
    fn mesh_png_writes_png_of_requested_size() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sphere.png");
        mesh_png(&p, "Sphere, DNSOM 20 x 20", &two_view_sphere(20), (640, 480)).unwrap();
        assert_eq!(png_size(&p), (640, 480));
        assert_eq!(listing(dir.path()), vec!["sphere.png".to_string()]);
    }

    #[test]
    fn mesh_png_skips_non_finite_points() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nan.png");
        let mut m = two_view_sphere(6);
        m[0].points[3] = [f64::NAN, 0.0, 0.0];
        m[1].points[7] = [0.0, f64::INFINITY, 0.0];
        mesh_png(&p, "with NaN", &m, (300, 300)).unwrap();
        assert_eq!(png_size(&p), (300, 300));
        let all_nan = vec![LineMesh {
            points: vec![[f64::NAN; 3]; 2],
            edges: vec![(0, 1)],
            colour: style::BLUE,
            label: String::new(),
        }];
        mesh_png(&p, "only NaN", &all_nan, (200, 200)).unwrap();
    }

    #[test]
    fn mesh_png_rejects_bad_edge_and_names_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.png");
        let m = vec![LineMesh {
            points: vec![[0.0; 3]; 2],
            edges: vec![(0, 2)],
            colour: style::BLUE,
            label: "net".into(),
        }];
        let e = mesh_png(&p, "bad", &m, (200, 200)).unwrap_err().to_string();
        assert!(e.contains("bad.png") && e.contains("edge 0") && e.contains("net"), "{e}");
        assert!(listing(dir.path()).is_empty());
    }

    #[test]
    fn mesh_png_missing_folder_names_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = missing_folder_path(dir.path());
        let e = mesh_png(&p, "t", &two_view_sphere(4), (200, 200)).unwrap_err().to_string();
        assert!(e.contains(&p.display().to_string()), "{e}");
        assert!(listing(dir.path()).is_empty());
    }

    #[test]
    fn lattice_30_draws_well_under_a_second_on_a_buffer() {
        let n = 30;
        let mut points = Vec::with_capacity(n * n * n);
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    points.push([i as f64, j as f64 + 0.1 * k as f64, k as f64]);
                }
            }
        }
        let m = vec![LineMesh {
            points,
            edges: lattice_edges(n),
            colour: style::BLUE,
            label: "3-D SOM".into(),
        }];
        let (w, h) = style::MESH_SIZE;
        let mut buf = vec![255u8; (w * h * 3) as usize];
        let t = std::time::Instant::now();
        {
            let area = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            draw_meshes(&area, "lattice", &m, View3d::default()).unwrap();
            area.present().unwrap();
        }
        let secs = t.elapsed().as_secs_f64();
        assert!(secs < 1.0, "30^3 lattice took {secs} s");
        // Something was drawn in the mesh colour's hue (not only the white background and grey axes).
        let blueish = buf.chunks(3).filter(|p| p[2] > p[0] + 40).count();
        assert!(blueish > 10_000, "only {blueish} bluish pixels");
    }

    #[test]
    fn view_cube_is_cubic_around_the_points() {
        let m = vec![LineMesh {
            points: vec![[0.0, 0.0, 0.0], [2.0, 1.0, 0.0]],
            edges: vec![(0, 1)],
            colour: style::BLUE,
            label: String::new(),
        }];
        let (c, h) = view_cube(&m);
        assert_eq!(c, [1.0, 0.5, 0.0]);
        assert!((h - 1.08).abs() < 1e-12);
    }

    /// A point no drawn edge reaches (a dense wireframe's point between its lines, where a
    /// surface swings out; an edge to a non-finite point) does not widen the box.
    #[test]
    fn view_cube_holds_only_what_is_drawn() {
        let m = vec![LineMesh {
            points: vec![[0.0, 0.0, 0.0], [2.0, 1.0, 0.0], [50.0, -40.0, 9.0], [f64::NAN; 3]],
            edges: vec![(0, 1), (1, 3)],
            colour: style::BLUE,
            label: String::new(),
        }];
        assert_eq!(view_cube(&m).0, [1.0, 0.5, 0.0]);
        assert!((view_cube(&m).1 - 1.08).abs() < 1e-12);
        let none = vec![LineMesh { edges: vec![], ..m[0].clone() }];
        assert_eq!(view_cube(&none), ([0.5; 3], 0.5), "nothing drawn: the unit cube");
    }
}
