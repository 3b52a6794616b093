//! Critical-difference diagram (Demsar 2006, J. Mach. Learn. Res. 7, Fig. 1-2) for the
//! Friedman + Nemenyi comparison of optimisers over cells: where each method's mean rank lies,
//! how long the critical difference is, and which methods cannot be told apart.
//!
//! Layout follows the usual drawing (as in Orange's `graph_ranks`): a rank axis 1..k with rank
//! 1 (best) on the left, the CD as a bar above it, each method hanging from its mean rank to a
//! label on the nearer side (better half left, worse half right, outermost highest so no lines
//! cross), and thick bars under the axis joining each maximal group of methods whose mean ranks
//! differ by less than CD ("not significantly different", Demsar Section 3.2.2).

use super::style;
use super::{render_png, DrawError, PlotError};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

const WIDTH: u32 = 960;
const TITLE_H: i32 = 48;
const AXIS_Y: i32 = TITLE_H + 72;
const CLIQUE_GAP: i32 = 12;
const ROW_H: i32 = 28;
/// Longest method name shown, in characters.
const NAME_CHARS: usize = 22;
/// Horizontal room kept for labels on each side of the axis (pixels).
const SIDE: i32 = 250;

/// Methods in ascending mean rank with the index ranges [a, b] (into that order) of the maximal
/// groups whose extreme ranks differ by less than `cd`; singletons are not groups.
fn cliques_sorted(mean_ranks: &[(String, f64)], cd: f64) -> (Vec<usize>, Vec<(usize, usize)>) {
    let mut order: Vec<usize> = (0..mean_ranks.len()).collect();
    order.sort_by(|&a, &b| mean_ranks[a].1.total_cmp(&mean_ranks[b].1));
    let r: Vec<f64> = order.iter().map(|&i| mean_ranks[i].1).collect();
    let mut groups = Vec::new();
    let mut last_end = 0usize;
    for i in 0..r.len() {
        let mut j = i;
        while j + 1 < r.len() && r[j + 1] - r[i] < cd {
            j += 1;
        }
        // j never decreases with i, so (i, j) is maximal unless the previous group reached j.
        if j > i && (groups.is_empty() || j > last_end) {
            groups.push((i, j));
            last_end = j;
        }
    }
    (order, groups)
}

/// The maximal groups of methods not significantly different at critical difference `cd`
/// (mean ranks within less than `cd`), each listed by name in ascending mean rank.
#[cfg(test)]
pub(crate) fn cd_cliques(mean_ranks: &[(String, f64)], cd: f64) -> Vec<Vec<String>> {
    let (order, groups) = cliques_sorted(mean_ranks, cd);
    groups
        .iter()
        .map(|&(a, b)| order[a..=b].iter().map(|&i| mean_ranks[i].0.clone()).collect())
        .collect()
}

fn validate(mean_ranks: &[(String, f64)], cd: f64) -> Result<(), String> {
    let k = mean_ranks.len();
    if k < 2 {
        return Err(format!("a CD diagram needs at least 2 methods, got {k}"));
    }
    if !(cd.is_finite() && cd > 0.0) {
        return Err(format!("critical difference must be finite and positive, got {cd}"));
    }
    for (name, r) in mean_ranks {
        if !(r.is_finite() && *r >= 1.0 - 1e-9 && *r <= k as f64 + 1e-9) {
            return Err(format!("mean rank of '{name}' is {r}, outside 1..={k}"));
        }
    }
    Ok(())
}

/// Picture size of the diagram for these inputs (None when they are invalid).
pub(crate) fn cd_diagram_size(mean_ranks: &[(String, f64)], cd: f64) -> Option<(u32, u32)> {
    validate(mean_ranks, cd).ok()?;
    let (_, groups) = cliques_sorted(mean_ranks, cd);
    let rows = mean_ranks.len().div_ceil(2) as i32;
    let h = AXIS_Y + CLIQUE_GAP * (groups.len() as i32 + 2) + rows * ROW_H + 24;
    Some((WIDTH, h as u32))
}

/// Writes the critical-difference diagram of `mean_ranks` (name, mean rank in 1..=k) with
/// critical difference `cd` to `path`.
pub(crate) fn cd_diagram_png(
    path: &Path,
    title: &str,
    mean_ranks: &[(String, f64)],
    cd: f64,
) -> Result<(), PlotError> {
    validate(mean_ranks, cd).map_err(|reason| PlotError::input(path, reason))?;
    let size =
        cd_diagram_size(mean_ranks, cd).ok_or_else(|| PlotError::input(path, "invalid input"))?;
    render_png(path, size, |root| draw_cd(root, title, mean_ranks, cd))
}

fn draw_cd(
    root: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    title: &str,
    mean_ranks: &[(String, f64)],
    cd: f64,
) -> Result<(), DrawError> {
    let k = mean_ranks.len();
    let (x0, x1) = (SIDE, WIDTH as i32 - SIDE);
    let px = |r: f64| x0 + ((r - 1.0) / (k as f64 - 1.0) * (x1 - x0) as f64).round() as i32;
    let line = |pts: Vec<(i32, i32)>, w: u32| PathElement::new(pts, style::BLACK.stroke_width(w));
    let label_font = style::text(16.0);
    let tick_font = style::text(style::LABEL_PX);

    root.draw(&Text::new(
        title.to_string(),
        (WIDTH as i32 / 2, 10),
        style::bold(style::TITLE_PX).pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;

    // Rank axis with integer ticks (labelled) and half-rank ticks.
    root.draw(&line(vec![(x0, AXIS_Y), (x1, AXIS_Y)], 2))?;
    for i in 0..=(2 * (k - 1)) {
        let r = 1.0 + i as f64 / 2.0;
        let len = if i % 2 == 0 { 10 } else { 5 };
        root.draw(&line(vec![(px(r), AXIS_Y), (px(r), AXIS_Y - len)], 1))?;
        if i % 2 == 0 {
            root.draw(&Text::new(
                format!("{}", 1 + i / 2),
                (px(r), AXIS_Y - 14),
                tick_font.clone().pos(Pos::new(HPos::Center, VPos::Bottom)),
            ))?;
        }
    }

    // CD bar above the axis, starting at rank 1 (cut at rank k if longer).
    let bar_y = AXIS_Y - 46;
    let end = px((1.0 + cd).min(k as f64));
    root.draw(&line(vec![(px(1.0), bar_y), (end, bar_y)], 2))?;
    root.draw(&line(vec![(px(1.0), bar_y - 5), (px(1.0), bar_y + 5)], 1))?;
    root.draw(&line(vec![(end, bar_y - 5), (end, bar_y + 5)], 1))?;
    let cd_text = if 1.0 + cd > k as f64 {
        format!("CD = {cd:.3} (longer than the axis)")
    } else {
        format!("CD = {cd:.3}")
    };
    root.draw(&Text::new(
        cd_text,
        ((px(1.0) + end) / 2, bar_y - 6),
        tick_font.clone().pos(Pos::new(HPos::Center, VPos::Bottom)),
    ))?;

    // Groups not significantly different: thick bars just under the axis, one row each.
    let (order, groups) = cliques_sorted(mean_ranks, cd);
    for (g, &(a, b)) in groups.iter().enumerate() {
        let y = AXIS_Y + CLIQUE_GAP * (g as i32 + 1);
        let (ra, rb) = (mean_ranks[order[a]].1, mean_ranks[order[b]].1);
        root.draw(&line(vec![(px(ra) - 6, y), (px(rb) + 6, y)], 4))?;
    }

    // Method labels: better half on the left, worse half on the right, outermost highest.
    let first_row = AXIS_Y + CLIQUE_GAP * (groups.len() as i32 + 2);
    let n_left = k.div_ceil(2);
    for (pos, &i) in order.iter().enumerate() {
        let (name, r) = &mean_ranks[i];
        let x = px(*r);
        let (row, left) = if pos < n_left { (pos, true) } else { (k - 1 - pos, false) };
        let y = first_row + row as i32 * ROW_H;
        let text = format!("{} ({r:.2})", style::truncate(name, NAME_CHARS));
        if left {
            root.draw(&line(vec![(x, AXIS_Y), (x, y), (x0 - 10, y)], 1))?;
            root.draw(&Text::new(
                text,
                (x0 - 16, y),
                label_font.clone().pos(Pos::new(HPos::Right, VPos::Center)),
            ))?;
        } else {
            root.draw(&line(vec![(x, AXIS_Y), (x, y), (x1 + 10, y)], 1))?;
            root.draw(&Text::new(
                text,
                (x1 + 16, y),
                label_font.clone().pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::*;

    fn ranks(v: &[(&str, f64)]) -> Vec<(String, f64)> {
        v.iter().map(|(n, r)| (n.to_string(), *r)).collect()
    }

    #[test]
    fn cliques_of_demsar_example() {
        // Demsar (2006) Section 3.2.2: C4.5 variants with mean ranks 3.143, 2.000, 2.893, 1.964
        // over 14 data sets, CD = 1.25 at alpha 0.05 (q = 2.569, k = 4, N = 14).
        let m =
            ranks(&[("C4.5", 3.143), ("C4.5+m", 2.000), ("C4.5+cf", 2.893), ("C4.5+m+cf", 1.964)]);
        let cd = 2.569 * (4.0f64 * 5.0 / (6.0 * 14.0)).sqrt();
        assert!((cd - 1.25).abs() < 0.01, "{cd}");
        // Differences to C4.5: 1.143 and 1.179, both < CD: all four in one group.
        assert_eq!(cd_cliques(&m, cd), vec![vec!["C4.5+m+cf", "C4.5+m", "C4.5+cf", "C4.5"]]);
        // With a CD of 1.0 the two with +m separate from plain C4.5.
        assert_eq!(
            cd_cliques(&m, 1.0),
            vec![vec!["C4.5+m+cf", "C4.5+m", "C4.5+cf"], vec!["C4.5+cf", "C4.5"]]
        );
    }

    #[test]
    fn cliques_are_maximal_and_exclude_singletons() {
        let m = ranks(&[("a", 1.0), ("b", 1.5), ("c", 2.4), ("d", 4.0), ("e", 5.0)]);
        let c = cd_cliques(&m, 1.0);
        // a-b (c is 1.4 from a), b-c (0.9), d alone? d-e differ by exactly 1.0: not < CD.
        assert_eq!(c, vec![vec!["a", "b"], vec!["b", "c"]]);
        assert!(cd_cliques(&m, 0.1).is_empty());
        assert_eq!(cd_cliques(&m, 10.0).len(), 1);
    }

    #[test]
    fn cd_diagram_writes_png_of_computed_size() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cd.png");
        let m = ranks(&[("DE", 1.6), ("GA", 2.9), ("PSO", 3.1), ("CSA", 3.4), ("ICSA", 4.0)]);
        cd_diagram_png(&p, "Friedman / Nemenyi", &m, 1.36).unwrap();
        assert_eq!(png_size(&p), cd_diagram_size(&m, 1.36).unwrap());
        cd_diagram_png(&p, "huge CD", &m, 9.0).unwrap();
        assert_eq!(listing(dir.path()), vec!["cd.png".to_string()]);
    }

    #[test]
    fn invalid_input_is_an_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cd.png");
        type Case = (Vec<(String, f64)>, f64, &'static str);
        let cases: Vec<Case> = vec![
            (ranks(&[("a", 1.0)]), 1.0, "at least 2"),
            (ranks(&[("a", 1.0), ("b", 2.0)]), f64::NAN, "critical difference"),
            (ranks(&[("a", 1.0), ("b", 2.0)]), -1.0, "critical difference"),
            (ranks(&[("a", f64::NAN), ("b", 2.0)]), 1.0, "'a'"),
            (ranks(&[("a", 1.0), ("b", 3.5)]), 1.0, "'b'"),
        ];
        for (m, cd, needle) in cases {
            let e = cd_diagram_png(&p, "t", &m, cd).unwrap_err().to_string();
            assert!(e.contains("cd.png") && e.contains(needle), "{e}");
        }
        let q = missing_folder_path(dir.path());
        let e = cd_diagram_png(&q, "t", &ranks(&[("a", 1.0), ("b", 2.0)]), 1.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains(&q.display().to_string()), "{e}");
        assert!(listing(dir.path()).is_empty());
    }
}
