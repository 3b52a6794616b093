//! The 3-D views of Chapter 6 in report.html (`views3d.js`): per grid and data set, the
//! optimised surfaces that go furthest from the data (largest dense `excursion` over every run),
//! then the least-error run of each (parameterisation, optimiser) at the largest net, evaluated
//! densely over the data, so a surface that swings out between the data points shows; the
//! reader switches between them in the page's view list.

use super::{OptimRun, ProblemKey};
use crate::experiment::spec::GridSize;
use crate::report::ordered;
use crate::report::plots::style;
use crate::report::views3d::{hex, Trace, View};
use crate::spline::ControlNetProblem;
use crate::spline::Parameterisation;
use std::collections::BTreeMap;

/// The most rows and columns of a surface in the views after each data set's first.
const COARSE_SIDE: usize = 16;

/// One view per (grid, data set): the data (both DNSOM views) and the bottom and top surfaces of
/// the run whose best control net has the largest dense excursion.
pub(crate) fn views(runs: &[OptimRun], problems: &BTreeMap<ProblemKey, ControlNetProblem>) -> Vec<View> {
    let far = super::furthest(runs);
    let mut views = Vec::new();
    // Grids, then data sets, in the order the runs name them.
    for grid in ordered(runs.iter().map(|r| r.cell.grid)) {
        for d in
            ordered(runs.iter().filter(|r| r.cell.grid == grid).map(|r| r.cell.dataset.clone()))
        {
            let k_far = far[&(grid, d.clone())];
            // The furthest run first, then one view per (parameterisation, optimiser): its MIN
            // run at the largest net (every record keeps its best control points).
            let mut shown: Vec<(usize, bool)> = vec![(k_far, true)];
            let mut min: BTreeMap<(Parameterisation, String), usize> = BTreeMap::new();
            for (k, r) in runs.iter().enumerate() {
                if r.cell.grid != grid || r.cell.dataset != d || k == k_far {
                    continue;
                }
                let e = min.entry((r.cell.param, r.competitor.clone())).or_insert(k);
                let held = &runs[*e];
                // The largest net; there the least error.
                if r.cell.cn > held.cell.cn || (r.cell.cn == held.cell.cn && r.row.best < held.row.best)
                {
                    *e = k;
                }
            }
            shown.extend(min.into_values().map(|k| (k, false)));
            for (k, furthest) in shown {
                let r = &runs[k];
                let problem = problems.get(&ProblemKey::new(&d, r.cell.cn, r.cell.param));
                if let Some(problem) = problem.filter(|_| !r.best_x.is_empty()) {
                    views.push(view(r, &d, grid, problem, furthest));
                }
            }
        }
    }
    views
}

/// The view of one run: the data and its densely evaluated surfaces.
fn view(r: &OptimRun, d: &str, grid: GridSize, problem: &ControlNetProblem, furthest: bool) -> View {
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
    // The cells after the first are drawn coarser (a third of the file each).
    let side = if furthest { crate::report::views3d::MAX_SIDE } else { COARSE_SIDE };
    let (bottom, bu, bv) = crate::report::views3d::coarse(&bottom, bu, bv, side);
    let (top, tu, tv) = crate::report::views3d::coarse(&top, tu, tv, side);
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
    let what = if furthest {
        "the optimised surfaces furthest from the data"
    } else {
        "the least-error run"
    };
    let title = format!(
        "{d} on {grid}, CN {}, {}: {what} ({} r{}, best {:.4e}, excursion {:.3e})",
        r.cell.cn,
        r.cell.param.name(),
        super::report::label(&r.competitor),
        r.cell.repeat,
        r.row.best,
        r.row.excursion
    );
    View { title, traces }
}
