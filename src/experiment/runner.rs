//! Maps cells to results on a fixed-size thread pool, with a progress bar, calling `done` as each
//! cell finishes (to log it at once). Results come back in cell order whatever the thread count.

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::{de::DeserializeOwned, Serialize};
use std::collections::BTreeMap;

/// Seconds between the plain progress lines of a run whose stderr is not a terminal (a log),
/// unless the environment variable [`PROGRESS_ENV`] gives another (e.g. `0.2` in tests).
pub(crate) const PROGRESS_SECS: f64 = 15.0;
pub(crate) const PROGRESS_ENV: &str = "SOMNURBS_PROGRESS_SECS";

/// The interval of the plain progress lines: [`PROGRESS_ENV`] if it holds a positive number of
/// seconds, else [`PROGRESS_SECS`].
fn progress_interval() -> std::time::Duration {
    let secs = std::env::var(PROGRESS_ENV)
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|s| *s > 0.0 && s.is_finite())
        .unwrap_or(PROGRESS_SECS);
    std::time::Duration::from_secs_f64(secs.min(86_400.0))
}

/// `1h02m03s`, `4m05s` or `6s`.
fn clock(d: std::time::Duration) -> String {
    let s = d.as_secs();
    match (s / 3600, s / 60 % 60, s % 60) {
        (0, 0, sec) => format!("{sec}s"),
        (0, m, sec) => format!("{m}m{sec:02}s"),
        (h, m, sec) => format!("{h}h{m:02}m{sec:02}s"),
    }
}

/// One plain progress line: `somnurbs: progress LABEL: DONE/TOTAL cells, elapsed E, eta T`.
pub(crate) fn progress_line(
    label: &str,
    done: usize,
    total: usize,
    elapsed: std::time::Duration,
) -> String {
    let eta = if done == 0 {
        "unknown".to_string()
    } else if done >= total {
        "0s".to_string()
    } else {
        clock(elapsed.mul_f64((total - done) as f64 / done as f64))
    };
    format!(
        "somnurbs: progress {label}: {done}/{total} cells, elapsed {}, eta {eta}",
        clock(elapsed)
    )
}

/// Run `work` over `cells` on `jobs` threads. On a terminal a progress bar shows; otherwise (a
/// log: SLURM, nohup, CI, or a [`crate::notice`] sink) a plain `progress_line` is a notice when the
/// cells start, every `progress_interval` and when they end.
pub fn run_cells<C, R>(
    cells: &[C],
    jobs: usize,
    label: &str,
    work: impl Fn(&C) -> Result<R> + Sync,
    done: impl Fn(&C, &R) -> Result<()> + Sync,
) -> Result<Vec<R>>
where
    C: Sync,
    R: Send,
{
    use std::io::IsTerminal;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .context("cannot start worker threads")?;
    let plain =
        (!std::io::stderr().is_terminal() || crate::notice::redirected()) && !cells.is_empty();
    let bar = if plain { ProgressBar::hidden() } else { ProgressBar::new(cells.len() as u64) };
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} cells, eta {eta}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_prefix(label.to_string());
    let finished = AtomicUsize::new(0);
    let stop = (std::sync::Mutex::new(false), std::sync::Condvar::new());
    let started = std::time::Instant::now();
    let results = std::thread::scope(|scope| {
        if plain {
            crate::notice::emit(&progress_line(label, 0, cells.len(), started.elapsed()));
            let (finished, stop) = (&finished, &stop);
            scope.spawn(move || {
                let interval = progress_interval();
                let mut stopped = stop.0.lock().unwrap_or_else(|e| e.into_inner());
                // The flag is read before every wait, under the lock the stop is set with, so a
                // stop that comes before the first wait (a tiny run) is never missed.
                while !*stopped {
                    let (guard, timeout) =
                        stop.1.wait_timeout(stopped, interval).unwrap_or_else(|e| e.into_inner());
                    stopped = guard;
                    if *stopped || !timeout.timed_out() {
                        continue;
                    }
                    crate::notice::emit(&progress_line(
                        label,
                        finished.load(Ordering::Relaxed),
                        cells.len(),
                        started.elapsed(),
                    ));
                }
            });
        }
        let results = pool.install(|| {
            cells
                .par_iter()
                .with_max_len(1)
                .map(|c| {
                    let r = work(c)?;
                    done(c, &r)?;
                    bar.inc(1);
                    finished.fetch_add(1, Ordering::Relaxed);
                    Ok(r)
                })
                .collect::<Result<Vec<R>>>()
        });
        *stop.0.lock().unwrap_or_else(|e| e.into_inner()) = true;
        stop.1.notify_all();
        results
    });
    bar.finish_and_clear();
    if plain && results.is_ok() {
        crate::notice::emit(&progress_line(label, cells.len(), cells.len(), started.elapsed()));
    }
    results
}

/// The cells of a two-list x repeats design in the specs' fixed order (a outer, b, then the
/// repeat 0..repeats inner), built by `make`.
pub(crate) fn product_cells<A, B, C>(
    a: &[A],
    b: &[B],
    repeats: usize,
    make: impl Fn(&A, &B, usize) -> C,
) -> Vec<C> {
    let mut out = Vec::with_capacity(a.len() * b.len() * repeats);
    for x in a {
        for y in b {
            for r in 0..repeats {
                out.push(make(x, y, r));
            }
        }
    }
    out
}

/// A cell of a spec: its stable key names its random stream and its line in the cell log.
pub(crate) trait Cell: Sync {
    fn key(&self) -> String;
}

/// A cell's result as the cell log keeps it: `record` is what a resumed run or a merge reads
/// back instead of recomputing the cell.
pub(crate) trait Logged: Send + Sized {
    type Record: Serialize + DeserializeOwned;
    fn record(&self) -> Self::Record;
}

/// The records of the cells `missing` that the folders of `ctx.reuse` hold (the first folder
/// that has a cell gives it), each with the folder it came from; only cells known by their
/// identity ([`super::seeds::identity_key`]) are looked for.
fn reused_records(
    ctx: &super::RunContext,
    missing: &std::collections::BTreeSet<String>,
) -> Result<BTreeMap<String, (String, serde_json::Value)>> {
    let mut out = BTreeMap::new();
    // Only a key that names what its cell computes can be matched: a family whose keys are
    // places alone (`seeds::place_of`) computes its cells itself.
    let mut wanted: std::collections::BTreeSet<String> =
        missing.iter().filter(|k| super::seeds::place_of(k) != k.as_str()).cloned().collect();
    for dir in &ctx.reuse {
        if wanted.is_empty() {
            break;
        }
        let found = super::log::read_matching(dir, &wanted)
            .with_context(|| format!("--reuse {}", dir.display()))?;
        for (key, rec) in found {
            wanted.remove(&key);
            out.insert(key, (dir.display().to_string(), rec));
        }
    }
    Ok(out)
}

/// Run the cells of this folder's slice (all, or the shard's) and return their results in cell
/// order. Each finished cell is appended to the folder's cell log at once; with `ctx.resume`,
/// cells already in the log are not run again but rebuilt by `restore` from their record, so a
/// resumed run gives the results of an uninterrupted one.
pub(crate) fn run_logged<C, R>(
    cells: &[C],
    ctx: &super::RunContext,
    label: &str,
    work: impl Fn(&C) -> Result<R> + Sync,
    restore: impl Fn(&C, R::Record) -> Result<R>,
) -> Result<Vec<R>>
where
    C: Cell,
    R: Logged,
{
    // The log may hold other cell families of the same spec: only this family's keys are read.
    let mut logged: BTreeMap<String, serde_json::Value> = if ctx.resume {
        super::log::read_records(&ctx.out, ctx.master_seed())?
    } else {
        BTreeMap::new()
    };
    let slice: Vec<&C> = cells
        .iter()
        .enumerate()
        .filter(|(k, _)| ctx.shard.is_none_or(|s| s.contains(*k)))
        .map(|(_, c)| c)
        .collect();
    let missing: std::collections::BTreeSet<String> =
        slice.iter().map(|c| c.key()).filter(|k| !logged.contains_key(k)).collect();
    let reused = reused_records(ctx, &missing)?;
    let todo: Vec<&C> = slice
        .iter()
        .copied()
        .filter(|c| missing.contains(&c.key()) && !reused.contains_key(&c.key()))
        .collect();
    if ctx.resume && ctx.compute && todo.len() < slice.len() {
        crate::notice::emit(&format!(
            "somnurbs: resuming {}: {} of {} cells already done",
            ctx.out.display(),
            slice.len() - todo.len() - reused.len(),
            slice.len()
        ));
    }
    if let (false, Some(c)) = (ctx.compute, todo.first()) {
        anyhow::bail!(
            "cell {} is not in the cell log of {} ({} of the {} cells are missing)",
            c.key(),
            ctx.out.display(),
            todo.len(),
            slice.len()
        );
    }
    // Every input has loaded: the folder becomes this run's (once per run), then the log
    // (empty unless resuming) gets one line per reused and per finished cell; every family
    // appends. A run that only reads records (`report`) opens no log.
    ctx.begin()?;
    let log = if todo.is_empty() && reused.is_empty() {
        None
    } else {
        Some(std::sync::Mutex::new(super::log::CellLog::append(&ctx.out, ctx.master_seed())?))
    };
    if let (Some(log), false) = (&log, reused.is_empty()) {
        let mut log = log.lock().map_err(|_| anyhow::anyhow!("cell log lock poisoned"))?;
        for c in &slice {
            if let Some((from, rec)) = reused.get(&c.key()) {
                log.push_line(&c.key(), rec, Some(from))?;
            }
        }
    }
    for (key, (_, rec)) in reused {
        logged.insert(key, rec);
    }
    let computed = run_cells(
        &todo,
        ctx.jobs,
        label,
        |c| work(c),
        |c, r: &R| {
            let record = r.record();
            if let Some(at) = super::finite::first_non_finite(&record) {
                anyhow::bail!("cell {}: its result is not finite ({at})", c.key());
            }
            let log = log.as_ref().context("no cell log open")?;
            log.lock()
                .map_err(|_| anyhow::anyhow!("cell log lock poisoned"))?
                .push(&c.key(), &record)
        },
    )?;
    let mut computed: BTreeMap<String, R> = todo.iter().map(|c| c.key()).zip(computed).collect();
    slice
        .into_iter()
        .map(|c| {
            let key = c.key();
            match computed.remove(&key) {
                Some(r) => Ok(r),
                None => {
                    let rec = logged
                        .remove(&key)
                        .with_context(|| format!("cell {key} is neither logged nor computed"))?;
                    let rec: R::Record = serde_json::from_value(rec).with_context(|| {
                        format!("cell {key}: its logged record does not fit this version's record")
                    })?;
                    restore(c, rec)
                        .with_context(|| format!("cannot restore cell {key} from the cell log"))
                }
            }
        })
        .collect()
}

/// The run protocol every cell follows: `work` on the cell's own stream (from the master seed and
/// the cell's key, [`super::seeds::cell_rng`]), timed in the thread's CPU seconds (the rows'
/// `cpu_s`).
pub(crate) fn on_stream<T>(
    master_seed: u64,
    key: &str,
    work: impl FnOnce(&mut rand_chacha::ChaCha8Rng) -> T,
) -> (T, f64) {
    let mut rng = super::seeds::cell_rng(master_seed, key);
    timed(|| work(&mut rng))
}

/// The same for a cell that draws no random number (a deterministic fit).
pub(crate) fn timed<T>(work: impl FnOnce() -> T) -> (T, f64) {
    let t0 = thread_cpu_seconds();
    let out = work();
    (out, thread_cpu_seconds() - t0)
}

/// One optimiser run of a cell through [`on_stream`]; an error names the cell.
pub(crate) fn optimise(
    opt: &dyn crate::optim::Optimiser,
    problem: &dyn crate::optim::Problem,
    budget: &crate::optim::Budget,
    master_seed: u64,
    key: &str,
) -> Result<(crate::optim::RunResult, f64)> {
    let (r, cpu_s) = on_stream(master_seed, key, |rng| opt.run(problem, budget, rng));
    Ok((r.with_context(|| key.to_string())?, cpu_s))
}

/// CPU seconds used by the calling thread so far (CLOCK_THREAD_CPUTIME_ID).
pub fn thread_cpu_seconds() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes into the timespec we own; the clock id is a constant.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    if rc != 0 {
        return 0.0;
    }
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_in_cell_order_for_any_thread_count() {
        let cells: Vec<u64> = (0..50).collect();
        for jobs in [1, 2, 4] {
            let seen = std::sync::Mutex::new(Vec::new());
            let out = run_cells(
                &cells,
                jobs,
                "t",
                |c| Ok(c * c),
                |c, _| {
                    seen.lock().unwrap().push(*c);
                    Ok(())
                },
            )
            .unwrap();
            assert_eq!(out, cells.iter().map(|c| c * c).collect::<Vec<_>>());
            assert_eq!(seen.lock().unwrap().len(), 50);
        }
        let err = run_cells(
            &cells,
            2,
            "t",
            |c| if *c == 7 { anyhow::bail!("cell 7 failed") } else { Ok(*c) },
            |_, _| Ok(()),
        );
        assert!(format!("{:#}", err.unwrap_err()).contains("cell 7"));
    }

    #[test]
    fn progress_lines_say_done_total_elapsed_and_eta() {
        let d = std::time::Duration::from_secs;
        assert_eq!(
            progress_line("ch6", 0, 10, d(3)),
            "somnurbs: progress ch6: 0/10 cells, elapsed 3s, eta unknown"
        );
        assert_eq!(
            progress_line("ch6", 5, 20, d(65)),
            "somnurbs: progress ch6: 5/20 cells, elapsed 1m05s, eta 3m15s"
        );
        assert_eq!(
            progress_line("x", 20, 20, d(3725)),
            "somnurbs: progress x: 20/20 cells, elapsed 1h02m05s, eta 0s"
        );
    }

    #[test]
    fn cpu_clock_advances() {
        let t0 = thread_cpu_seconds();
        let mut x = 0u64;
        for i in 0..20_000_000u64 {
            x = x.wrapping_add(i * i);
        }
        std::hint::black_box(x);
        assert!(thread_cpu_seconds() > t0);
    }
}
