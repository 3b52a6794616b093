//! The 3-D views of Chapter 6 in report.html (`views3d.js`): per grid and data set, the
//! optimised surfaces that go furthest from the data (largest dense `excursion` over every run),
//! evaluated densely over the data, so a surface that swings out between the data points shows.

use super::{OptimRun, ProblemKey};
use crate::experiment::spec::GridSize;
use crate::report::ordered;
use crate::report::plots::style;
use crate::report::views3d::{hex, Trace, View};
use crate::spline::ControlNetProblem;
use std::collections::BTreeMap;

/// One view per (grid, data set): the data (both DNSOM views) and the bottom and top surfaces of
/// the run whose best control net has the largest dense excursion.
pub fn views(runs: &[OptimRun], problems: &BTreeMap<ProblemKey, ControlNetProblem>) -> Vec<View> {
    let far = super::furthest(runs);
    let mut views = Vec::new();
    // Grids, then data sets, in the order the runs name them.
    for grid in ordered(runs.iter().map(|r| r.cell.grid)) {
        for d in
            ordered(runs.iter().filter(|r| r.cell.grid == grid).map(|r| r.cell.dataset.clone()))
        {
            let r = &runs[far[&(grid, d.clone())]];
            // `picture_points` gave this run its control points.
            let problem = problems.get(&(d.clone(), r.cell.cn, r.cell.param));
            if let Some(problem) = problem.filter(|_| !r.best_x.is_empty()) {
                views.push(view(r, &d, grid, problem));
            }
        }
    }
    views
}

/// The view of one run: the data and its densely evaluated surfaces.
fn view(r: &OptimRun, d: &str, grid: GridSize, problem: &ControlNetProblem) -> View {
    let parts = problem.parts();
    let mut traces = vec![
        Trace::Points {
            label: "data, bottom view".into(),
            colour: hex(style::DNSOM_BOTTOM),
            points: parts.data_bottom.clone(),
            lines: Vec::new(),
        },
        Trace::Points {
            label: "data, top view".into(),
            colour: hex(style::DNSOM_TOP),
            points: parts.data_top.clone(),
            lines: Vec::new(),
        },
    ];
    let [(bottom, bu, bv), (top, tu, tv)] = parts.dense_grids(&r.best_x);
    traces.push(Trace::Surface {
        label: "bottom surface".into(),
        colour: hex(style::DNSOM_BOTTOM),
        rows: bu,
        cols: bv,
        points: bottom,
    });
    traces.push(Trace::Surface {
        label: "top surface".into(),
        colour: hex(style::DNSOM_TOP),
        rows: tu,
        cols: tv,
        points: top,
    });
    let title = format!(
            "{d} on {grid}: the optimised surfaces furthest from the data ({} r{}, CN {}, {}, best {:.4e}, excursion {:.3e})",
            r.cell.optimiser.to_uppercase(),
            r.cell.repeat,
            r.cell.cn,
            r.cell.param.name(),
            r.row.best,
            r.row.excursion
        );
    View { title, traces }
}
