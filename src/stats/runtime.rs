//! Runtime distributions of optimiser runs, as COCO and IOHanalyzer draw them, from improvement
//! traces (evaluation, value) of runs that minimise: the first hitting time of a target, the
//! empirical cumulative distribution (ECDF) of (run, target) pairs reached within a budget, the
//! expected running time (ERT) per target, the fixed-budget best value, and the area over the
//! convergence curve of the ECDF (AOCC: the ECDF's mean over every budget 1..=B, so 1 means every
//! target was reached at the first evaluation). Pure functions.

/// One run: its improvement rows (evaluation ascending, value strictly decreasing, as recorded)
/// and its evaluation count.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Trace<'a> {
    pub(crate) improvements: &'a [(u64, f64)],
    pub(crate) evaluations: u64,
}

impl Trace<'_> {
    /// The first evaluation at which the best so far is at most `target` (None: never).
    pub(crate) fn hitting_time(&self, target: f64) -> Option<u64> {
        self.improvements.iter().find(|r| r.1 <= target).map(|r| r.0)
    }

    /// The best value after `budget` evaluations (+inf before the first improvement).
    pub(crate) fn best_at(&self, budget: u64) -> f64 {
        self.improvements
            .iter()
            .take_while(|r| r.0 <= budget)
            .last()
            .map(|r| r.1)
            .unwrap_or(f64::INFINITY)
    }
}

/// `count` targets between `start` (first) and `best` (last, included), spaced evenly in log10 of
/// the gap above `best`: best + (start - best) 10^(-decades k / (count - 1)) for k < count - 1,
/// and `best` itself last. A zero or negative gap gives the single target `best`.
pub(crate) fn log_targets(start: f64, best: f64, count: usize, decades: f64) -> Vec<f64> {
    let gap = start - best;
    if gap.is_nan() || gap <= 0.0 || count < 2 {
        return vec![best];
    }
    let mut t: Vec<f64> = (0..count - 1)
        .map(|k| best + gap * 10f64.powf(-decades * k as f64 / (count - 2).max(1) as f64))
        .collect();
    t.push(best);
    t
}

/// Where a problem's targets start (the top of the log-spaced range down to the best known value,
/// also the reference that makes the fixed-budget gap 1), and the rule that chose it:
/// - `b_to_best_known`: approach B's error, when some run (or the certified optimum) beats it;
/// - `best_first_to_best_known`: when nothing beats B, the best first value of any run (the
///   improvement the optimisers made over their best start, as IOHanalyzer's default targets span
///   the observed values);
/// - `worst_first_to_best_known`: when that best start is itself the best known, the worst first
///   value;
/// - `none`: no run ever improved (every first value is the best known): no range (None); the
///   problem gets the single target `best_known` and no fixed-budget gap.
pub(crate) fn target_range(b: f64, best_known: f64, firsts: &[f64]) -> (Option<f64>, &'static str) {
    let best_first = firsts.iter().copied().fold(f64::INFINITY, f64::min);
    let worst_first = firsts.iter().copied().filter(|v| v.is_finite()).fold(f64::NAN, f64::max);
    if b > best_known {
        (Some(b), "b_to_best_known")
    } else if best_first.is_finite() && best_first > best_known {
        (Some(best_first), "best_first_to_best_known")
    } else if worst_first > best_known {
        (Some(worst_first), "worst_first_to_best_known")
    } else {
        (None, "none")
    }
}

/// The mean of curves tabulated at the same points, each curve weighing the same (the ECDF or
/// fixed-budget values of several problems aggregated with equal weight per problem, as
/// IOHanalyzer and COCO aggregate over functions); empty when there is no curve.
pub(crate) fn mean_curve(curves: &[&[f64]]) -> Vec<f64> {
    let Some(len) = curves.iter().map(|c| c.len()).min() else { return Vec::new() };
    (0..len).map(|k| curves.iter().map(|c| c[k]).sum::<f64>() / curves.len() as f64).collect()
}

/// The expected running time to reach `target`: the evaluations of all runs (until the hit for
/// those that hit, all for the others) over the number of hits; +inf when no run hits.
pub(crate) fn ert(runs: &[Trace], target: f64) -> (f64, usize) {
    let mut spent = 0u64;
    let mut hits = 0usize;
    for r in runs {
        match r.hitting_time(target) {
            Some(h) => {
                spent += h;
                hits += 1;
            }
            None => spent += r.evaluations,
        }
    }
    (if hits == 0 { f64::INFINITY } else { spent as f64 / hits as f64 }, hits)
}

/// The hitting times of every (run, target) pair of a problem (None: not reached).
pub(crate) fn hitting_times(runs: &[Trace], targets: &[f64]) -> Vec<Option<u64>> {
    runs.iter().flat_map(|r| targets.iter().map(move |&t| r.hitting_time(t))).collect()
}

/// The ECDF of hitting times (the (run, target) pairs of one problem, each weighing the same; over
/// several problems average their ECDFs with [`mean_curve`]) at each of `budgets`: the share of
/// pairs reached within the budget.
pub(crate) fn ecdf(times: &[Option<u64>], budgets: &[u64]) -> Vec<f64> {
    let mut hit: Vec<u64> = times.iter().flatten().copied().collect();
    hit.sort_unstable();
    let n = times.len().max(1) as f64;
    budgets.iter().map(|&b| hit.partition_point(|&h| h <= b) as f64 / n).collect()
}

/// The AOCC of the ECDF over budgets 1..=`budget`: (1/B) sum_{e=1..B} ECDF(e), exactly, from the
/// hitting times (a pair hit at h contributes (B - h + 1)/B).
pub(crate) fn aocc(times: &[Option<u64>], budget: u64) -> f64 {
    if times.is_empty() || budget == 0 {
        return 0.0;
    }
    let b = budget as f64;
    times.iter().flatten().filter(|&&h| h <= budget).map(|&h| (b - h as f64 + 1.0) / b).sum::<f64>()
        / times.len() as f64
}

/// `count` budgets from 1 to `max`, evenly spaced in log10 and rounded to whole evaluations
/// (duplicates removed; `max` always included).
pub(crate) fn log_budgets(max: u64, count: usize) -> Vec<u64> {
    if max <= 1 || count < 2 {
        return vec![max.max(1)];
    }
    let l = (max as f64).log10();
    let mut v: Vec<u64> = (0..count)
        .map(|k| (10f64.powf(l * k as f64 / (count - 1) as f64).round() as u64).clamp(1, max))
        .collect();
    v.push(max);
    v.sort_unstable();
    v.dedup();
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: [(u64, f64); 3] = [(1, 10.0), (5, 4.0), (20, 1.0)];
    const B: [(u64, f64); 2] = [(1, 8.0), (10, 5.0)];

    fn runs() -> [Trace<'static>; 2] {
        [Trace { improvements: &A, evaluations: 30 }, Trace { improvements: &B, evaluations: 40 }]
    }

    #[test]
    fn hitting_times_ert_and_fixed_budget_by_hand() {
        let [a, b] = runs();
        assert_eq!(
            (a.hitting_time(4.0), a.hitting_time(3.9), b.hitting_time(9.0)),
            (Some(5), Some(20), Some(1))
        );
        assert_eq!((a.best_at(4), a.best_at(5), a.best_at(0)), (10.0, 4.0, f64::INFINITY));
        // Target 5: a at 5, b at 10: ERT (5 + 10) / 2. Target 2: a at 20, b fails after 40.
        assert_eq!(ert(&runs(), 5.0), (7.5, 2));
        assert_eq!(ert(&runs(), 2.0), (60.0, 1));
        assert_eq!(ert(&runs(), 0.5).0, f64::INFINITY);
    }

    #[test]
    fn ecdf_and_aocc_by_hand() {
        let times = hitting_times(&runs(), &[8.0, 1.0]);
        assert_eq!(times, vec![Some(5), Some(20), Some(1), None]);
        assert_eq!(ecdf(&times, &[1, 4, 5, 19, 20, 100]), vec![0.25, 0.25, 0.5, 0.5, 0.75, 0.75]);
        // B = 20: (16 + 1 + 20) / 20 / 4.
        assert!((aocc(&times, 20) - 37.0 / 80.0).abs() < 1e-15);
        // The same as the mean of the ECDF over 1..=20.
        let e = ecdf(&times, &(1..=20).collect::<Vec<u64>>());
        assert!((aocc(&times, 20) - e.iter().sum::<f64>() / 20.0).abs() < 1e-15);
    }

    #[test]
    fn targets_and_budgets() {
        let t = log_targets(11.0, 1.0, 4, 2.0);
        assert_eq!(t.len(), 4);
        assert!(
            (t[0] - 11.0).abs() < 1e-12
                && (t[1] - 2.0).abs() < 1e-12
                && (t[2] - 1.1).abs() < 1e-12
                && t[3] == 1.0
        );
        assert_eq!(log_targets(1.0, 1.0, 5, 3.0), vec![1.0]);
        assert_eq!(log_budgets(100, 3), vec![1, 10, 100]);
        assert_eq!(*log_budgets(4040, 30).last().unwrap(), 4040);
    }

    /// The targets' rule: B when something beats it; else the best first value; else the worst
    /// first value; else none (a constant problem).
    #[test]
    fn target_range_rules() {
        assert_eq!(target_range(5.0, 4.0, &[6.0, 7.0]), (Some(5.0), "b_to_best_known"));
        // Nothing beats B = 3 (best known 3.5): from the best start 6 down to 3.5.
        assert_eq!(target_range(3.0, 3.5, &[6.0, 7.0]), (Some(6.0), "best_first_to_best_known"));
        // The best start is the best known: from the worst start.
        assert_eq!(target_range(3.0, 3.5, &[3.5, 7.0]), (Some(7.0), "worst_first_to_best_known"));
        assert_eq!(target_range(3.0, 3.5, &[3.5, 3.5]), (None, "none"));
        assert_eq!(target_range(3.0, 3.5, &[]), (None, "none"));
        let (start, _) = target_range(3.0, 3.5, &[6.0]);
        assert_eq!(log_targets(start.unwrap(), 3.5, 16, 3.0).len(), 16);
    }

    /// Equal weight per problem: problem a has 2 (run, target) pairs, b has 8; their ECDFs at
    /// budgets (1, 2) are (0.5, 1) and (0.25, 0.5), the mean (0.375, 0.75); pooling the 10 pairs
    /// would give (0.3, 0.6), weighing b four times as much as a.
    #[test]
    fn curves_weigh_problems_equally() {
        let a = [Some(1), Some(2)];
        let b = [Some(1), Some(1), Some(2), Some(2), None, None, None, None];
        let (ea, eb) = (ecdf(&a, &[1, 2]), ecdf(&b, &[1, 2]));
        assert_eq!((ea.clone(), eb.clone()), (vec![0.5, 1.0], vec![0.25, 0.5]));
        assert_eq!(mean_curve(&[&ea, &eb]), vec![0.375, 0.75]);
        let pooled: Vec<Option<u64>> = a.iter().chain(&b).copied().collect();
        assert_eq!(ecdf(&pooled, &[1, 2]), vec![0.3, 0.6]);
        assert!(mean_curve(&[]).is_empty());
    }
}
