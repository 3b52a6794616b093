//! Maps cells to results on a fixed-size thread pool, with a progress bar, calling `done` as each
//! cell finishes (to log it at once). Results come back in cell order whatever the thread count.

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

/// Run `work` over `cells` on `jobs` threads.
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
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs.max(1)).build().context("cannot start worker threads")?;
    let bar = ProgressBar::new(cells.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{prefix} [{elapsed_precise}] {wide_bar} {pos}/{len} cells, eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_prefix(label.to_string());
    let results = pool.install(|| {
        cells
            .par_iter()
            .with_max_len(1)
            .map(|c| {
                let r = work(c)?;
                done(c, &r)?;
                bar.inc(1);
                Ok(r)
            })
            .collect::<Result<Vec<R>>>()
    });
    bar.finish_and_clear();
    results
}

/// Run `work` over `cells` and append each finished cell's row to `<out>/runs.csv.partial` at
/// once (header first), so a killed run keeps every row it finished.
pub fn run_logged<C, R, Row>(cells: &[C], ctx: &super::RunContext, label: &str, work: impl Fn(&C) -> Result<R> + Sync, row: impl Fn(&R) -> &Row + Sync) -> Result<Vec<R>>
where
    C: Sync,
    R: Send,
    Row: serde::Serialize + Default,
{
    let header = crate::report::fsio::csv_text(&[Row::default()])?;
    let header = header.lines().next().unwrap_or_default().to_string();
    let log = std::sync::Mutex::new(crate::report::fsio::PartialLog::create(&ctx.out.join("runs.csv.partial"), &header)?);
    run_cells(cells, ctx.jobs, label, work, |_, r| {
        let text = crate::report::fsio::csv_text(std::slice::from_ref(row(r)))?;
        log.lock().map_err(|_| anyhow::anyhow!("log lock poisoned"))?.push(text.lines().nth(1).unwrap_or_default())
    })
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
            let out = run_cells(&cells, jobs, "t", |c| Ok(c * c), |c, _| {
                seen.lock().unwrap().push(*c);
                Ok(())
            })
            .unwrap();
            assert_eq!(out, cells.iter().map(|c| c * c).collect::<Vec<_>>());
            assert_eq!(seen.lock().unwrap().len(), 50);
        }
        let err = run_cells(&cells, 2, "t", |c| if *c == 7 { anyhow::bail!("cell 7 failed") } else { Ok(*c) }, |_, _| Ok(()));
        assert!(format!("{:#}", err.unwrap_err()).contains("cell 7"));
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
