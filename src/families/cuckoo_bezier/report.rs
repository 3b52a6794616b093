//! Seed 003 report: the paper's Tables 3 (CSA's fitting errors), 4 (the five methods, with error
//! rates) and 5 (Wilcoxon signed-rank and rank-sum tests of CSA against each other method) from
//! the runs, each beside the published numbers (`experiments/reference/seed003_table*.csv`),
//! whether each comparison's direction and significance agree with the paper's (computed from
//! both tables), and the convergence diagrams (best Y against iterations, median and quartiles
//! over the runs).

use super::{Run, CuckooBezierSpec, EXAMPLES, METHODS};
use crate::report::plots::{self, boxplot::quantile_type7, style, Series};
use crate::report::reference::RefTable;
use crate::stats::{rank_sum::rank_sum, wilcoxon::signed_rank, Alternative};
use anyhow::Result;
use std::fmt::Write;
use std::path::Path;

/// Table 4's statistics of one (example, method): Y mean, best, sample variance, std; RMSE mean,
/// best.
#[derive(Debug, Clone, Copy)]
struct Stats {
    y_mean: f64,
    y_best: f64,
    y_var: f64,
    y_std: f64,
    rmse_mean: f64,
    rmse_best: f64,
}

impl Stats {
    fn of(runs: &[&Run]) -> Stats {
        let y: Vec<f64> = runs.iter().map(|r| r.row.y).collect();
        let n = y.len() as f64;
        let (y_mean, y_var) = crate::stats::describe::mean_var(&y);
        let rmse_mean = runs.iter().map(|r| r.row.rmse).sum::<f64>() / n;
        let min = |v: &mut dyn Iterator<Item = f64>| v.fold(f64::INFINITY, f64::min);
        Stats {
            y_mean,
            y_best: min(&mut y.iter().copied()),
            y_var,
            y_std: y_var.sqrt(),
            rmse_mean,
            rmse_best: min(&mut runs.iter().map(|r| r.row.rmse)),
        }
    }

    fn get(&self, stat: &str) -> f64 {
        match stat {
            "y_mean" => self.y_mean,
            "y_best" => self.y_best,
            "y_var" => self.y_var,
            "y_std" => self.y_std,
            "rmse_mean" => self.rmse_mean,
            _ => self.rmse_best,
        }
    }
}

/// A published table of [`PUBLISHED`].
fn table(name: &str) -> Option<RefTable> {
    crate::report::reference::lookup(PUBLISHED, name)
}

/// Seed 003's Tables 3, 4 and 5.
pub(crate) const PUBLISHED: crate::report::reference::Published = &[
    ("seed003_table3", include_str!("../../../experiments/reference/seed003_table3.csv")),
    ("seed003_table4", include_str!("../../../experiments/reference/seed003_table4.csv")),
    ("seed003_table5", include_str!("../../../experiments/reference/seed003_table5.csv")),
];

/// Table 3's rows (and Table 4's without the error rates).
const STATS: [&str; 6] = ["y_mean", "y_best", "y_var", "y_std", "rmse_mean", "rmse_best"];
/// Statistics that carry an error rate in Table 4.
const RATED: [&str; 4] = ["y_mean", "y_best", "rmse_mean", "rmse_best"];
/// Table 5's indices per comparison.
const INDICES: [&str; 6] = ["p_sign", "signed_rank", "h_sign", "p_sum", "rank_sum", "h_sum"];

fn sel<'a>(runs: &'a [Run], example: &str, method: &str) -> Vec<&'a Run> {
    let mut v: Vec<&Run> =
        runs.iter().filter(|r| r.row.example == example && r.row.method == method).collect();
    v.sort_by_key(|r| r.row.run);
    v
}

/// Table 5 for x = `other`'s Y and y = CSA's Y, paired by run: p, W+ (sum of the ranks of the
/// positive differences x - y), h; p, rank sum of x in the pooled sample, h (MATLAB's `signrank`
/// and `ranksum` statistics); NaN where a test is undefined (e.g. all differences zero).
fn tests(other: &[f64], csa: &[f64], alpha: f64) -> [f64; 6] {
    let h = |p: f64| if p.is_nan() { f64::NAN } else { (p < alpha) as u8 as f64 };
    let (p1, w) = signed_rank(other, csa, Alternative::TwoSided)
        .map(|t| (t.p_value, t.w_plus))
        .unwrap_or((f64::NAN, f64::NAN));
    let n1 = other.len() as f64;
    let (p2, r) = rank_sum(other, csa, Alternative::TwoSided)
        .map(|t| (t.p_value, t.w + n1 * (n1 + 1.0) / 2.0))
        .unwrap_or((f64::NAN, f64::NAN));
    // + 0.0 turns the -0.0 of an empty sum into 0.
    [p1, w + 0.0, h(p1), p2, r, h(p2)]
}

fn num(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        format!("{v:e}")
    }
}

fn cell(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() && x.fract() == 0.0 && x.abs() < 1e5 => format!("{}", x + 0.0),
        Some(x) if x.is_finite() => format!("{x:.4e}"),
        _ => "-".into(),
    }
}

fn write_csv(out: &Path, name: &str, header: &[&str], rows: &[Vec<String>]) -> Result<()> {
    let header: Vec<String> = header.iter().map(|h| h.to_string()).collect();
    crate::io::write_atomic(&out.join(name), crate::io::csv_records(&header, rows)?.as_bytes())
}

/// Where the CSA/ICSA start population lies under the spec's `start` reading.
fn start_text(s: &CuckooBezierSpec) -> String {
    if s.start.classical().is_none() {
        return "uniform on [0,1]^dim".into();
    }
    format!(
        "uniform in the parameterisation `start = \"{}\"` +- {} (clamped to [0,1])",
        s.start.key(),
        s.start_spread
    )
}

/// Write runs.csv, the tables and the pictures; return the REPORT.md section.
pub(crate) fn write(spec_name: &str, s: &CuckooBezierSpec, runs: &[Run], out: &Path) -> Result<String> {
    let rows: Vec<_> = runs.iter().map(|r| r.row.clone()).collect();
    crate::io::write_atomic(&out.join("runs.csv"), crate::io::csv_text(&rows)?.as_bytes())?;
    let examples: Vec<&str> =
        EXAMPLES.iter().copied().filter(|e| s.examples.iter().any(|x| x == e)).collect();
    let methods: Vec<&str> =
        METHODS.iter().copied().filter(|m| s.methods.iter().any(|x| x == m)).collect();
    let stats = |e: &str, m: &str| -> Option<Stats> {
        let v = sel(runs, e, m);
        (!v.is_empty()).then(|| Stats::of(&v))
    };
    let (ref3, ref4, ref5) =
        (table("seed003_table3"), table("seed003_table4"), table("seed003_table5"));
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Seed 003: cuckoo search for Bezier surface approximation (Iglesias et al.)\n"
    );
    let _ = writeln!(md, "Data (stated choices, see the spec's header): Example I = Franke's function on a {0}x{0} grid of [0,1]^2, degree ({1},{1}), SNR {2} dB; Example II = MATLAB's peaks on a {3}x{3} grid of [-3,3]^2, degree ({4},{4}), SNR {5} dB; Example III = {6} points at uniform random parameters of a degree-(5,5) Bezier surface with random poles in [-1,1]^3 whose four corner poles coincide (fixed stream), fitted at degree ({7},{7}), SNR {8} dB. Noise: i.i.d. Gaussian on x, y and z, redrawn for every run and shared by the five methods in that run (so runs pair by index). Classical methods: the paper's Eqs. 11-13 on the grid rows and columns; for the unorganised Example III along the order of the points on the cloud's two principal axes. CSA/ICSA: {9} nests, start population {17}, iterations per example {10}/{11}/{12}; pa = {13} (CSA), pa from {14} to {15} (ICSA). {16} runs per (example, method). Y = sum of squared 3-D distances (Eq. 4/5), RMSE = sqrt(Y / points) (Eq. 14/15). The paper's absolute Y depends on its unpublished surfaces and noise scale, so compare orders and directions, not digits.\n",
        s.example1.size, s.example1.degree, s.example1.snr_db, s.example2.size, s.example2.degree, s.example2.snr_db, s.example3.size, s.example3.degree, s.example3.snr_db, s.nests, s.example1.generations, s.example2.generations, s.example3.generations, s.csa.pa, s.icsa.pa_max, s.icsa.pa_min, s.runs, start_text(s));

    // Table 3: CSA's statistics, examples in columns.
    if methods.contains(&"csa") {
        table_3(s.runs, &examples, ref3.as_ref(), out, &mut md, &stats)?;
    }

    // Table 4: every method, with the error rate 100 * value / best value of the row.
    table_4(&examples, &methods, ref4.as_ref(), out, &mut md, &stats)?;
    if let Some(r4) = &ref4 {
        paper_consistency(r4, &examples, &methods, &mut md);
    }

    // Table 5 and the agreement with the paper.
    let others: Vec<&str> = ["uniform", "chordal", "centripetal", "icsa"]
        .into_iter()
        .filter(|m| methods.contains(m))
        .collect();
    if methods.contains(&"csa") && !others.is_empty() {
        write_tests(
            spec_name,
            s,
            runs,
            &examples,
            &others,
            ref4.as_ref(),
            ref5.as_ref(),
            out,
            &mut md,
            &stats,
        )?;
    }

    speed(runs, &examples, &methods, &mut md);
    convergence(s, runs, &examples, &methods, out, &mut md, &stats)?;
    Ok(md)
}

/// Where the transcribed Table 4 contradicts itself (computed from its own cells): std^2 against
/// var (more than 5% apart), and the printed error rates against 100 x value / best of the row
/// (more than 0.15 points apart).
fn paper_consistency(r4: &RefTable, examples: &[&str], methods: &[&str], md: &mut String) {
    let v = |e: &str, st: &str, m: &str| {
        r4.value(&["example", "statistic"], &[e.to_string(), st.to_string()], m)
    };
    let mut notes = Vec::new();
    for e in examples {
        for m in methods {
            if let (Some(var), Some(sd)) = (v(e, "y_var", m), v(e, "y_std", m)) {
                if (sd * sd - var).abs() > 0.05 * var {
                    notes.push(format!("{e} {m}: var {var:e} but std^2 = {:.6e}", sd * sd));
                }
            }
        }
        for st in RATED {
            let best = methods.iter().filter_map(|m| v(e, st, m)).fold(f64::INFINITY, f64::min);
            for m in methods {
                if let (Some(x), Some(er)) = (v(e, st, m), v(e, &format!("er_{st}"), m)) {
                    let want = 100.0 * x / best;
                    if (want - er).abs() > 0.15 {
                        notes.push(format!(
                            "{e} {m} er_{st}: printed {er} but 100 x {x:e} / {best:e} = {want:.1}"
                        ));
                    }
                }
            }
        }
    }
    if !notes.is_empty() {
        let _ = writeln!(md, "
The transcribed Table 4 is not consistent with itself in these cells (garbled in the seed text or in the paper; transcribed as printed):
");
        for n in notes {
            let _ = writeln!(md, "- {n}");
        }
    }
    let _ = writeln!(md, "
Table 5's Example II cells for CSA vs centripetal are garbled: the sign test's h reads \"1 (alpha = 0.1)\", the sum test's \"1 (alpha = 0.15)\" (the text: h = 0 at 0.05), and its rank-sum p-value is printed \"0.148521 x 10^-1\" although the text says order 10^-1 (likely 1.48521e-1); the transcription keeps the printed number and h = 0.");
}

/// One comparison of Table 5: (method, `csa_vs_<method>`, per example the six indices).
type Comparison = (String, String, Vec<[f64; 6]>);

/// Table 5 (`seed003_table5.csv`) and its Markdown: each method against CSA, paired by run.
#[allow(clippy::too_many_arguments)]
fn table5(
    s: &CuckooBezierSpec,
    runs: &[Run],
    examples: &[&str],
    others: &[&str],
    ref5: Option<&RefTable>,
    out: &Path,
    md: &mut String,
) -> Result<Vec<Comparison>> {
    let mut t5 = Vec::new();
    let _ = writeln!(md, "\n### Table 5: Wilcoxon signed-rank (sign) and rank-sum (sum) tests, alpha = {} (ours, paper in brackets)\n", s.alpha);
    let _ = writeln!(md, "x = the compared method, y = CSA, paired by run (same data). signed_rank = sum of the ranks of the positive x - y (MATLAB's `signrank` statistic); rank_sum = sum of x's ranks in the pooled sample (MATLAB's `ranksum`); 1275 and 3775 are their maxima for 50 runs (every x above every y). p-values: exact when there are no ties, else the normal approximation with tie and continuity corrections (the paper's MATLAB uses the normal approximation for 50 runs, so its p-values differ a little at the same statistic).\n");
    let _ = writeln!(md, "| comparison | index | {} |", examples.join(" | "));
    let _ = writeln!(md, "|---|---|{}", "---|".repeat(examples.len()));
    let mut results = Vec::new();
    for o in others {
        let per: Vec<[f64; 6]> = examples
            .iter()
            .map(|e| {
                let x: Vec<f64> = sel(runs, e, o).iter().map(|r| r.row.y).collect();
                let y: Vec<f64> = sel(runs, e, "csa").iter().map(|r| r.row.y).collect();
                if x.len() == y.len() {
                    tests(&x, &y, s.alpha)
                } else {
                    [f64::NAN; 6]
                }
            })
            .collect();
        let comp = format!("csa_vs_{o}");
        for (k, idx) in INDICES.iter().enumerate() {
            t5.push(
                [comp.clone(), idx.to_string()]
                    .into_iter()
                    .chain(per.iter().map(|v| num(v[k])))
                    .collect(),
            );
            let paper = |e: &str| {
                ref5.and_then(|t| {
                    t.value(&["comparison", "index"], &[comp.clone(), idx.to_string()], e)
                })
            };
            let _ = writeln!(
                md,
                "| {comp} | {idx} | {} |",
                examples
                    .iter()
                    .zip(&per)
                    .map(|(e, v)| format!("{} ({})", cell(Some(v[k])), cell(paper(e))))
                    .collect::<Vec<_>>()
                    .join(" | ")
            );
        }
        results.push((o.to_string(), comp, per));
    }
    let mut header = vec!["comparison", "index"];
    header.extend(examples);
    write_csv(out, "seed003_table5.csv", &header, &t5)?;
    Ok(results)
}

/// The agreement table (`seed003_agreement.csv`) and its Markdown: per comparison and example,
/// the better method and the tests' h, ours beside the paper's. Returns its rows.
#[allow(clippy::too_many_arguments)]
fn agreement(
    s: &CuckooBezierSpec,
    examples: &[&str],
    results: &[Comparison],
    ref4: Option<&RefTable>,
    ref5: Option<&RefTable>,
    out: &Path,
    md: &mut String,
    stats: &dyn Fn(&str, &str) -> Option<Stats>,
) -> Result<Vec<Vec<String>>> {
    let mut agree = Vec::new();

    let _ = writeln!(
        md,
        "\n### Agreement with the paper (computed from our tables and the transcribed ones)\n"
    );
    let _ = writeln!(md, "Better = lower mean Y (Table 4); h = significant at alpha = {}. The paper's h for CSA vs centripetal on Example II is 0 at 0.05 (its cells say 1 only at alpha 0.1 / 0.15).\n", s.alpha);
    let _ = writeln!(md, "| comparison | example | better (ours) | better (paper) | h sign (ours / paper) | h sum (ours / paper) | direction agrees | significance agrees | agrees |");
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|");
    let better = |e: &str, o: &str, mean: &dyn Fn(&str) -> Option<f64>| -> String {
        match (mean("csa"), mean(o)) {
            (Some(c), Some(x)) if c < x => "csa".into(),
            (Some(c), Some(x)) if x < c => o.to_string(),
            (Some(_), Some(_)) => "tie".into(),
            _ => {
                let _ = e;
                String::new()
            }
        }
    };
    for (o, comp, per) in results {
        for (e, v) in examples.iter().zip(per) {
            let ours = better(e, o, &|m| stats(e, m).map(|x| x.y_mean));
            let paper = better(e, o, &|m| {
                ref4.and_then(|t| {
                    t.value(&["example", "statistic"], &[e.to_string(), "y_mean".into()], m)
                })
            });
            let ph = |idx: &str| {
                ref5.and_then(|t| t.value(&["comparison", "index"], &[comp.clone(), idx.into()], e))
            };
            let (ph1, ph2) = (ph("h_sign"), ph("h_sum"));
            let yes = |b: bool| if b { "yes" } else { "no" };
            let dir_ok = !paper.is_empty() && ours == paper;
            let sig_ok = ph1 == Some(v[2]) && ph2 == Some(v[5]);
            let hs = |x: f64| if x.is_nan() { "-".to_string() } else { format!("{x}") };
            let pv = |x: Option<f64>| x.map(hs).unwrap_or_else(|| "-".into());
            agree.push(vec![
                comp.clone(),
                e.to_string(),
                ours.clone(),
                paper.clone(),
                num(v[2]),
                ph1.map(num).unwrap_or_default(),
                num(v[5]),
                ph2.map(num).unwrap_or_default(),
                yes(dir_ok).into(),
                yes(sig_ok).into(),
                yes(dir_ok && sig_ok).into(),
            ]);
            let _ = writeln!(
                md,
                "| {comp} | {e} | {ours} | {paper} | {} / {} | {} / {} | {} | {} | **{}** |",
                hs(v[2]),
                pv(ph1),
                hs(v[5]),
                pv(ph2),
                yes(dir_ok),
                yes(sig_ok),
                yes(dir_ok && sig_ok)
            );
        }
    }
    let n_dir = agree.iter().filter(|r| r[8] == "yes").count();
    let n_sig = agree.iter().filter(|r| r[9] == "yes").count();
    let n_all = agree.iter().filter(|r| r[10] == "yes").count();
    let _ = writeln!(md, "\nDirection agrees in {n_dir} of {} comparisons, significance (both tests) in {n_sig}, both (agrees) in {n_all}.", agree.len());
    write_csv(
        out,
        "seed003_agreement.csv",
        &[
            "comparison",
            "example",
            "better_ours",
            "better_paper",
            "h_sign_ours",
            "h_sign_paper",
            "h_sum_ours",
            "h_sum_paper",
            "direction_agrees",
            "significance_agrees",
            "agrees",
        ],
        &agree,
    )?;
    Ok(agree)
}

/// One claim per comparison for the combined report: the paper's verdict (direction and
/// significance) checked on each example.
fn agreement_claims(
    results: &[Comparison],
    agree: &[Vec<String>],
) -> Vec<crate::report::claims::Claim> {
    results
        .iter()
        .map(|(o, comp, _)| {
            let rows: Vec<&Vec<String>> = agree.iter().filter(|r| &r[0] == comp).collect();
            let paper: Vec<String> = rows.iter().map(|r| format!("{}: {} better", r[1], if r[3].is_empty() { "?" } else { &r[3] })).collect();
            crate::report::claims::Claim::every(
                "seed003",
                format!("CSA vs {o}: the better method and the significance of both Wilcoxon tests are as in the paper's Tables 4-5"),
                (rows.iter().filter(|r| r[10] == "yes").count(), rows.len()),
            )
            .note(format!("examples where both agree (seed003_agreement.csv); paper: {}", paper.join(", ")))
        })
        .collect()
}

/// Table 5 (`seed003_table5.csv`), the agreement table (`seed003_agreement.csv`) and their
/// Markdown. Direction: the method with the lower mean Y is better (Table 4's reading);
/// significance: h of each test at the spec's alpha.
#[allow(clippy::too_many_arguments)]
fn write_tests(
    spec_name: &str,
    s: &CuckooBezierSpec,
    runs: &[Run],
    examples: &[&str],
    others: &[&str],
    ref4: Option<&RefTable>,
    ref5: Option<&RefTable>,
    out: &Path,
    md: &mut String,
    stats: &dyn Fn(&str, &str) -> Option<Stats>,
) -> Result<()> {
    let results = table5(s, runs, examples, others, ref5, out, md)?;
    let agree = agreement(s, examples, &results, ref4, ref5, out, md, stats)?;
    crate::report::claims::write(out, spec_name, &agreement_claims(&results, &agree), false)
        .map(|_| ())
}

/// Convergence diagrams: per example, the median and quartiles over the runs of CSA's and ICSA's
/// best Y against iterations (evaluations - N over 2N), with the classical methods' mean Y as
/// flat lines; and the traces as CSV.
fn convergence(
    s: &CuckooBezierSpec,
    runs: &[Run],
    examples: &[&str],
    methods: &[&str],
    out: &Path,
    md: &mut String,
    stats: &dyn Fn(&str, &str) -> Option<Stats>,
) -> Result<()> {
    let n = s.nests as f64;
    let iteration = |evals: u64| (evals as f64 - n) / (2.0 * n);
    let mut trace_rows = Vec::new();
    for r in runs {
        for &(ev, f) in &r.trace {
            trace_rows.push(vec![
                r.row.cell.clone(),
                r.row.example.clone(),
                r.row.method.clone(),
                r.row.run.to_string(),
                ev.to_string(),
                format!("{}", iteration(ev)),
                format!("{f:e}"),
            ]);
        }
    }
    write_csv(
        out,
        "seed003_traces.csv",
        &["cell", "example", "method", "run", "evaluations", "iteration", "best_y"],
        &trace_rows,
    )?;
    crate::io::ensure_dir(&out.join("png"))?;
    let _ = writeln!(
        md,
        "\n### Convergence diagrams (the paper's Figures 2, 4, 6 show the mean for CSA)\n"
    );
    for e in examples {
        let mut series = Vec::new();
        let mut last = 0.0f64;
        for (k, m) in ["csa", "icsa"].iter().filter(|m| methods.contains(m)).enumerate() {
            let v = sel(runs, e, m);
            let len = v.iter().map(|r| r.trace.len()).min().unwrap_or(0);
            let mut pts = Vec::new();
            let mut band = Vec::new();
            for i in 0..len {
                let mut ys: Vec<f64> = v.iter().map(|r| r.trace[i].1).collect();
                ys.sort_by(f64::total_cmp);
                let x = iteration(v[0].trace[i].0);
                last = last.max(x);
                pts.push((x, quantile_type7(&ys, 0.5)));
                band.push((x, quantile_type7(&ys, 0.25), quantile_type7(&ys, 0.75)));
            }
            series.push(Series {
                label: format!("{m} median, quartiles"),
                colour: style::optimiser_colour(m).unwrap_or_else(|| style::cycle_colour(k)),
                points: pts,
                band: Some(band),
            });
        }
        for (k, m) in
            ["uniform", "chordal", "centripetal"].iter().filter(|m| methods.contains(m)).enumerate()
        {
            if let Some(st) = stats(e, m) {
                series.push(Series {
                    label: format!("{m} (mean Y)"),
                    colour: [style::BLUE, style::GREEN, style::BLACK][k],
                    points: vec![(0.0, st.y_mean), (last.max(1.0), st.y_mean)],
                    band: None,
                });
            }
        }
        if series.is_empty() {
            continue;
        }
        let png = format!("png/seed003_convergence_{e}.png");
        match plots::line_chart_png(
            &out.join(&png),
            &format!("{e}: best Y over {} runs", s.runs),
            "iterations",
            "Y (sum of squared errors)",
            &series,
            true,
        ) {
            Ok(()) => {
                let _ = writeln!(md, "![{png}]({png})\n");
            }
            Err(err) => crate::report::picture_skipped(&err),
        }
    }
    Ok(())
}

/// Table 3: CSA's statistics over the runs, examples in columns, beside the paper's
/// (seed003_table3.csv and its REPORT.md table).
fn table_3(
    runs: usize,
    examples: &[&str],
    ref3: Option<&RefTable>,
    out: &Path,
    md: &mut String,
    stats: &dyn Fn(&str, &str) -> Option<Stats>,
) -> Result<()> {
    let mut t3 = Vec::new();
    let _ = writeln!(md, "### Table 3: CSA fitting errors over {} runs (ours / paper)\n", runs);
    let _ = writeln!(
        md,
        "| statistic | {} |",
        examples.iter().map(|e| format!("{e} ours | {e} paper")).collect::<Vec<_>>().join(" | ")
    );
    let _ = writeln!(md, "|---|{}", "---|---|".repeat(examples.len()));
    for st in STATS {
        let ours: Vec<f64> = examples
            .iter()
            .map(|e| stats(e, "csa").map(|x| x.get(st)).unwrap_or(f64::NAN))
            .collect();
        t3.push(std::iter::once(st.to_string()).chain(ours.iter().map(|v| num(*v))).collect());
        let paper = |e: &str| ref3.and_then(|t| t.value(&["statistic"], &[st.to_string()], e));
        let _ = writeln!(
            md,
            "| {st} | {} |",
            examples
                .iter()
                .zip(&ours)
                .map(|(e, o)| format!("{} | {}", cell(Some(*o)), cell(paper(e))))
                .collect::<Vec<_>>()
                .join(" | ")
        );
    }
    let mut header = vec!["statistic"];
    header.extend(examples);
    write_csv(out, "seed003_table3.csv", &header, &t3)?;
    Ok(())
}

/// Table 4: every method, with the error rate 100 * value / best value of the row, beside the
/// paper's (seed003_table4.csv and its REPORT.md table).
fn table_4(
    examples: &[&str],
    methods: &[&str],
    ref4: Option<&RefTable>,
    out: &Path,
    md: &mut String,
    stats: &dyn Fn(&str, &str) -> Option<Stats>,
) -> Result<()> {
    let mut t4 = Vec::new();
    let _ = writeln!(md, "\n### Table 4: the five methods (ours, paper below each row); E.R. = 100 x value / best value of the row, empty for the best\n");
    let _ = writeln!(md, "| example | statistic | {} |", methods.join(" | "));
    let _ = writeln!(md, "|---|---|{}", "---|".repeat(methods.len()));
    for e in examples {
        for st in STATS {
            let vals: Vec<Option<f64>> =
                methods.iter().map(|m| stats(e, m).map(|x| x.get(st))).collect();
            let mut lines = vec![(st.to_string(), vals.clone())];
            if RATED.contains(&st) {
                let best = vals.iter().flatten().copied().fold(f64::INFINITY, f64::min);
                lines.push((
                    format!("er_{st}"),
                    vals.iter()
                        .map(|v| v.filter(|x| *x != best).map(|x| 100.0 * x / best))
                        .collect(),
                ));
            }
            for (name, vals) in lines {
                t4.push(
                    [e.to_string(), name.clone()]
                        .into_iter()
                        .chain(vals.iter().map(|v| v.map(num).unwrap_or_default()))
                        .collect(),
                );
                let paper: Vec<Option<f64>> = methods
                    .iter()
                    .map(|m| {
                        ref4.and_then(|t| {
                            t.value(&["example", "statistic"], &[e.to_string(), name.clone()], m)
                        })
                    })
                    .collect();
                let _ = writeln!(
                    md,
                    "| {e} | {name} | {} |",
                    vals.iter()
                        .zip(&paper)
                        .map(|(o, p)| format!("{} ({})", cell(*o), cell(*p)))
                        .collect::<Vec<_>>()
                        .join(" | ")
                );
            }
        }
    }
    let mut header = vec!["example", "statistic"];
    header.extend(methods);
    write_csv(out, "seed003_table4.csv", &header, &t4)?;
    Ok(())
}

/// Speed: evaluations per CPU second of the searches.
fn speed(runs: &[Run], examples: &[&str], methods: &[&str], md: &mut String) {
    let _ = writeln!(md, "\n### Speed\n");
    let _ = writeln!(
        md,
        "| example | method | mean CPU s per run | evaluations per run | evaluations/s |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|");
    for e in examples {
        for m in ["csa", "icsa"].iter().filter(|m| methods.contains(m)) {
            let v = sel(runs, e, m);
            let (cpu, ev): (f64, f64) = v
                .iter()
                .fold((0.0, 0.0), |(c, n), r| (c + r.row.cpu_s, n + r.row.evaluations as f64));
            if !v.is_empty() && cpu > 0.0 {
                let _ = writeln!(
                    md,
                    "| {e} | {m} | {:.3} | {:.0} | {:.0} |",
                    cpu / v.len() as f64,
                    ev / v.len() as f64,
                    ev / cpu
                );
            }
        }
    }
}
