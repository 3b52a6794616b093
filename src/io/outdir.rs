//! The output-folder contract, in one place.
//!
//! - **One writer.** Every command that writes a results folder (`run`, `reproduce`, `merge`,
//!   `drift --accept`) holds [`lock`] on it for its whole life: an exclusive `flock(2)` on
//!   `<folder>/.somnurbs.lock`, which also holds a record of the holder (host, pid, start, a
//!   heartbeat refreshed every [`HEARTBEAT`]). A second writer is refused (exit 2) with the
//!   holder named. The kernel drops the `flock` when the holder dies (even by `kill -9`), so a
//!   crashed run never blocks a resume. Across hosts sharing a file system, `flock` is coherent on
//!   NFSv4, Lustre mounted with `-o flock`, GPFS and BeeGFS; where it is only node-local (or not
//!   supported), the record is the second line of defence: a record of another host whose
//!   heartbeat is younger than [`STALE_AFTER`] refuses the writer too, and a record of this host
//!   whose process is alive does. (Two starts on two such hosts within the same instant can still
//!   both pass; nothing portable closes that window.)
//! - **An empty folder to start.** A result folder holds one run (or plan) and the files it wrote:
//!   a new result starts only in a missing or empty folder ([`require_empty`], which names what a
//!   refused folder holds); `--resume` continues only the same run and first removes the
//!   temporary files an interrupted writer left ([`remove_leftovers`]); single files (`datasets
//!   export`, `drift`'s CSV) are never written inside a result folder
//!   ([`require_outside_results`]).
//! - **Finished means a manifest.** A run folder (one holding `fingerprint.toml`, `cells.jsonl` or
//!   `manifest.toml`) is finished when `manifest.toml`, written after every other file, is there and it is not a
//!   single shard; a `reproduce` folder is unfinished while it holds [`INCOMPLETE`].
//!   [`require_finished`] refuses anything else, naming the missing piece.
//! - **Whole-folder swaps.** [`replace_dir`] builds a new folder beside the old one and swaps
//!   them with one `renameat2(RENAME_EXCHANGE)`, so a reader sees the old folder or the new one,
//!   never a mix, and a failure leaves the old one as it was.
//! - Files are written through [`crate::io::write_atomic`]: a unique temporary name
//!   (pid + counter) in the same folder, `fsync`, rename, `fsync` of the folder.

use anyhow::{bail, Context, Result};
use std::fs::{self, File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::os::unix::io::AsRawFd;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

pub(crate) const LOCK_FILE: &str = ".somnurbs.lock";
pub(crate) const MANIFEST: &str = "manifest.toml";
/// The cell log of a run (one JSON record per finished cell; see `experiment::log`).
pub(crate) const LOG_FILE: &str = "cells.jsonl";
/// The cell log of a finished run, gzip-compressed (see `experiment::log::compress`).
pub(crate) const LOG_GZ: &str = "cells.jsonl.gz";
/// The fingerprint of the run a folder holds (what `--resume` and `merge` compare).
pub(crate) const FINGERPRINT_FILE: &str = "fingerprint.toml";
/// Present in a `reproduce` folder from the moment its inputs have loaded until its REPORT.md.
pub(crate) const INCOMPLETE: &str = ".somnurbs-incomplete";
/// The record of the plan a `reproduce` folder holds (what `reproduce --resume` compares).
pub(crate) const PLAN_FILE: &str = "plan_fingerprint.toml";
/// The files that make a folder a result folder (a run, a shard, a plan or a `fit`).
const MARKERS: [&str; 7] =
    [MANIFEST, FINGERPRINT_FILE, LOG_FILE, LOG_GZ, INCOMPLETE, PLAN_FILE, LOCK_FILE];
/// How often a lock holder refreshes its record.
pub(crate) const HEARTBEAT: Duration = Duration::from_secs(20);
/// A record of another host older than this is taken to be left by a dead writer.
pub(crate) const STALE_AFTER: Duration = Duration::from_secs(120);

/// A unique name for a temporary sibling of `path`: `.NAME.PID.N.tmp`.
pub(crate) fn temp_name(path: &Path, what: &str) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}.{n}.{what}", std::process::id()))
}

/// The result folders this process holds the lock of ([`lock`]), as given and canonical: below
/// them no link is followed ([`no_link_inside`]).
static ROOTS: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn roots() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    ROOTS.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The held result folders that are being filled (`somnurbs report`): a file there that exists
/// is never replaced, only compared ([`fill`]).
static FILLING: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn filling() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    FILLING.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// What a write of `bytes` to `path` does in a folder being filled.
#[derive(Debug, PartialEq)]
pub(crate) enum Fill {
    /// Not in a filled folder, or the file is missing: write it.
    Write,
    /// The file is there with these very bytes: leave it.
    Same,
}

/// Whether `path` may be written: outside a folder being filled, always; inside one, only when
/// it is missing, and a file that is there must hold `bytes` exactly (else an error naming it:
/// a finished result is never rewritten).
pub(crate) fn fill(path: &Path, bytes: &[u8]) -> Result<Fill> {
    if !is_filling(path) {
        return Ok(Fill::Write);
    }
    match fs::symlink_metadata(path) {
        Err(_) => Ok(Fill::Write),
        Ok(_) => {
            let old = crate::io::input::read(path, crate::io::input::Kind::Data)?;
            if old == bytes {
                Ok(Fill::Same)
            } else {
                bail!(
                    "{}: the folder's records render it differently ({} bytes there, {} rendered): made by another build of somnurbs, or edited; left as it is",
                    path.display(),
                    old.len(),
                    bytes.len()
                )
            }
        }
    }
}

/// Whether files below `path` are only added, never replaced or removed (a folder being filled).
pub(crate) fn is_filling(path: &Path) -> bool {
    filling().iter().any(|r| path.starts_with(r))
}

/// Refuse `path` when, inside a result folder this process holds, it or a folder on its way is a
/// symbolic link: a write through it would land outside the folder it was given.
pub(crate) fn no_link_inside(path: &Path) -> Result<()> {
    let held: Vec<PathBuf> = roots().iter().filter(|r| path.starts_with(r)).cloned().collect();
    for root in held {
        let Ok(rel) = path.strip_prefix(&root) else { continue };
        let mut at = root.clone();
        for part in rel.components() {
            at.push(part);
            match fs::symlink_metadata(&at) {
                Ok(m) if m.file_type().is_symlink() => bail!(
                    "{} is a symbolic link inside the result folder {}; somnurbs follows no link inside a result folder (remove the link, or start afresh in a new folder)",
                    at.display(),
                    root.display()
                ),
                Ok(_) => {}
                Err(_) => break,
            }
        }
    }
    Ok(())
}

/// Whether a file name is one [`temp_name`] made: `.NAME.PID.N.WHAT` for a temporary file
/// (`tmp`) or folder (`staged`, `old`).
fn is_temp_name(name: &str) -> bool {
    let Some(rest) = name.strip_prefix('.') else { return false };
    let mut parts = rest.rsplitn(4, '.');
    let (what, n, pid, stem) = (parts.next(), parts.next(), parts.next(), parts.next());
    let digits =
        |s: Option<&str>| s.is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
    matches!(what, Some("tmp" | "staged" | "old"))
        && digits(n)
        && digits(pid)
        && stem.is_some_and(|s| !s.is_empty())
}

/// Remove the temporary files and folders that an interrupted writer left anywhere under `dir`
/// (names made by [`temp_name`]); call it only while holding the folder's [`lock`]. Returns how
/// many were removed.
pub(crate) fn remove_leftovers(dir: &Path) -> Result<usize> {
    let (files, dirs) = walk(dir)?;
    let mut gone: Vec<PathBuf> = Vec::new();
    for rel in dirs.iter().chain(&files) {
        let temp = rel.file_name().is_some_and(|n| is_temp_name(&n.to_string_lossy()));
        if !temp || gone.iter().any(|g| rel.starts_with(g)) {
            continue;
        }
        let path = dir.join(rel);
        let removed =
            if path.is_dir() { fs::remove_dir_all(&path) } else { fs::remove_file(&path) };
        removed.with_context(|| format!("cannot remove the leftover {}", path.display()))?;
        gone.push(rel.clone());
    }
    if !gone.is_empty() {
        sync_dir(dir)?;
    }
    Ok(gone.len())
}

/// The entries of `dir` other than its lock file, sorted, folders with a trailing `/` (none when
/// `dir` does not exist).
pub(crate) fn entries(dir: &Path) -> Result<Vec<String>> {
    let rd = match fs::read_dir(dir) {
        Ok(rd) => rd,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("cannot read folder {}", dir.display())),
    };
    let mut names = Vec::new();
    for e in rd {
        let e = e.with_context(|| format!("cannot read folder {}", dir.display()))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if name == LOCK_FILE {
            continue;
        }
        let folder = e.path().is_dir();
        names.push(if folder { format!("{name}/") } else { name });
    }
    names.sort();
    Ok(names)
}

/// What a non-empty folder holds, in words: a finished or unfinished run, a shard, a
/// reproduction, or files that are no somnurbs result.
fn describe(dir: &Path, entries: &[String]) -> String {
    #[derive(serde::Deserialize)]
    struct Named {
        spec_name: Option<String>,
        shard: Option<String>,
    }
    let named = |file: &str| -> Option<Named> {
        let text = crate::io::read_text_of(&dir.join(file), crate::io::input::Kind::Toml).ok()?;
        toml::from_str(&text).ok()
    };
    let has = |f: &str| entries.iter().any(|e| e == f);
    let spec = |n: &Option<Named>| {
        n.as_ref()
            .and_then(|n| n.spec_name.clone())
            .map(|s| format!(" of spec `{s}`"))
            .unwrap_or_default()
    };
    if has(PLAN_FILE) || has(INCOMPLETE) {
        return if has(INCOMPLETE) {
            "an unfinished reproduction (continue it with `somnurbs reproduce --resume` and the same --plan and --profile)".into()
        } else {
            "a finished reproduction".into()
        };
    }
    if has(MANIFEST) {
        let m = named(MANIFEST);
        let shard = m.as_ref().and_then(|m| m.shard.clone());
        return match shard {
            Some(s) => format!("shard {s}{}, finished", spec(&m)),
            None => format!("a finished run{}", spec(&m)),
        };
    }
    if has(FINGERPRINT_FILE) || has(LOG_FILE) || has(LOG_GZ) {
        return format!(
            "an unfinished run{} (continue it with --resume and the same spec, profile and options)",
            spec(&named(FINGERPRINT_FILE))
        );
    }
    let shown: Vec<&str> = entries.iter().take(5).map(String::as_str).collect();
    let more = entries.len().saturating_sub(shown.len());
    format!(
        "files that are not a somnurbs result ({}{})",
        shown.join(", "),
        if more > 0 { format!(" and {more} more") } else { String::new() }
    )
}

/// Refuse to start a new result in `dir` unless it is missing or empty (its lock file aside): a
/// result folder holds one run and the files that run wrote, and a finished one is never changed.
pub(crate) fn require_empty(dir: &Path) -> Result<()> {
    let found = entries(dir)?;
    if found.is_empty() {
        return Ok(());
    }
    bail!(
        "output folder {} already holds {}; a result folder holds one run and nothing else, so choose another --out (or remove that folder yourself)",
        dir.display(),
        describe(dir, &found)
    )
}

/// The result folder (a run, shard, plan or `fit` folder: one holding a manifest, fingerprint,
/// cell log, plan record or lock file) that `path` would be written into, if any: `path`'s
/// folder or one of its parents.
pub(crate) fn result_folder_of(path: &Path) -> Option<PathBuf> {
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    // The deepest folder on the way that exists (the rest would be created inside it).
    let start = parent.ancestors().find_map(|a| {
        let a = if a.as_os_str().is_empty() { Path::new(".") } else { a };
        fs::canonicalize(a).ok()
    })?;
    let marked = |d: &Path| MARKERS.iter().any(|m| fs::symlink_metadata(d.join(m)).is_ok());
    start.ancestors().find(|d| marked(d)).map(Path::to_path_buf)
}

/// Refuse a new output folder `out` (given with `option`) inside a result folder: a finished run,
/// a shard or a reproduction holds one result and nothing else, so nothing new is written into it.
pub(crate) fn require_folder_outside_results(out: &Path, option: &str) -> Result<()> {
    if let Some(folder) = result_folder_of(out) {
        bail!(
            "{option} {} is inside the result folder {}, which holds one result and nothing else; choose a folder outside it",
            out.display(),
            folder.display()
        );
    }
    Ok(())
}

/// Refuse to write the single file `path` (e.g. `datasets export`, `drift`'s CSV) inside a result
/// folder: results are never changed after the fact.
pub(crate) fn require_outside_results(path: &Path, option: &str) -> Result<()> {
    if let Some(folder) = result_folder_of(path) {
        bail!(
            "{} is inside the result folder {}, which holds one run and nothing else; write it elsewhere ({option})",
            path.display(),
            folder.display()
        );
    }
    Ok(())
}

/// `fsync` a folder, so that renames and creations in it are durable.
pub(crate) fn sync_dir(dir: &Path) -> Result<()> {
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    File::open(dir)
        .and_then(|f| f.sync_all())
        .with_context(|| format!("cannot sync folder {}", dir.display()))
}

pub(crate) fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|s| s.trim().to_string())
        .or_else(|_| std::env::var("HOSTNAME"))
        .unwrap_or_else(|_| "unknown".into())
}

fn now_unix() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0)
}

/// The holder record of a lock file.
#[derive(Debug, Clone, PartialEq)]
struct Holder {
    host: String,
    pid: u32,
    since: u64,
    command: String,
}

impl Holder {
    fn me(command: &str) -> Holder {
        Holder {
            host: host_name(),
            pid: std::process::id(),
            since: now_unix(),
            command: command.to_string(),
        }
    }

    fn text(&self) -> String {
        format!(
            "host = {:?}\npid = {}\nsince_unix = {}\ncommand = {:?}\n",
            self.host, self.pid, self.since, self.command
        )
    }

    fn parse(text: &str) -> Option<Holder> {
        #[derive(serde::Deserialize)]
        struct Raw {
            host: String,
            pid: u32,
            since_unix: u64,
            command: String,
        }
        let r: Raw = toml::from_str(text).ok()?;
        Some(Holder { host: r.host, pid: r.pid, since: r.since_unix, command: r.command })
    }

    fn describe(&self) -> String {
        format!(
            "`somnurbs {}`, pid {} on host {}, since unix time {}",
            self.command, self.pid, self.host, self.since
        )
    }
}

fn pid_alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else { return false };
    // SAFETY: kill with signal 0 only checks that the process exists.
    let rc = unsafe { libc::kill(pid, 0) };
    rc == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM)
}

enum Flock {
    Held,
    Busy,
    /// The file system does not support flock here.
    Unsupported,
}

fn try_flock(f: &File, op: libc::c_int) -> Result<Flock> {
    // SAFETY: flock on a file descriptor we own.
    let rc = unsafe { libc::flock(f.as_raw_fd(), op | libc::LOCK_NB) };
    if rc == 0 {
        return Ok(Flock::Held);
    }
    let e = std::io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::EWOULDBLOCK) => Ok(Flock::Busy),
        Some(libc::ENOLCK) | Some(libc::EINVAL) | Some(libc::EOPNOTSUPP) | Some(libc::ENOSYS) => {
            Ok(Flock::Unsupported)
        }
        _ => Err(e.into()),
    }
}

fn read_holder(f: &mut File) -> Option<Holder> {
    let mut text = String::new();
    f.seek(SeekFrom::Start(0)).ok()?;
    f.take(4096).read_to_string(&mut text).ok()?;
    Holder::parse(&text)
}

/// Why a live record refuses us (None: the record is stale or ours).
fn live_record(holder: &Holder, file: &File, flock_held: bool) -> Option<String> {
    if holder.pid == std::process::id() && holder.host == host_name() {
        return None;
    }
    if holder.host == host_name() {
        // flock is authoritative on one host: if we hold it, the recorded process is gone.
        return (!flock_held && pid_alive(holder.pid)).then(|| holder.describe());
    }
    let age = file
        .metadata()
        .and_then(|m| m.modified())
        .ok()
        .and_then(|t| SystemTime::now().duration_since(t).ok())
        .unwrap_or(Duration::ZERO);
    (age < STALE_AFTER).then(|| format!("{} (its last heartbeat {} s ago; a record older than {} s counts as left by a dead writer)", holder.describe(), age.as_secs(), STALE_AFTER.as_secs()))
}

/// The exclusive hold on an output folder; released (record cleared, flock dropped) on drop.
pub(crate) struct Lock {
    file: File,
    path: PathBuf,
    stop: Arc<AtomicBool>,
    heartbeat: Option<std::thread::JoinHandle<()>>,
    /// What this lock added to [`ROOTS`].
    roots: Vec<PathBuf>,
    /// Whether it also added them to [`FILLING`].
    fill: bool,
}

impl std::fmt::Debug for Lock {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Lock({})", self.path.display())
    }
}

/// Take the one-writer lock of `dir` (created if missing) for `command` (shown to a refused
/// writer, e.g. `run spec.toml`).
pub(crate) fn lock(dir: &Path, command: &str) -> Result<Lock> {
    if dir.exists() && !dir.is_dir() {
        bail!("output folder {} is not a folder (a file is there); choose another", dir.display());
    }
    crate::io::ensure_dir(dir)?;
    let path = dir.join(LOCK_FILE);
    let mut file = open_lock_file(&path, true).with_context(|| {
        format!("output folder {} is not writable (cannot open {LOCK_FILE})", dir.display())
    })?;
    let refused = |who: String| {
        anyhow::anyhow!("output folder {} is in use by another writer: {who}; wait for it to finish or choose another folder", dir.display())
    };
    let held = match try_flock(&file, libc::LOCK_EX)
        .with_context(|| format!("cannot lock {}", path.display()))?
    {
        Flock::Held => true,
        Flock::Busy => {
            return Err(refused(
                read_holder(&mut file)
                    .map(|h| h.describe())
                    .unwrap_or_else(|| "a process that has not written its record yet".into()),
            ))
        }
        Flock::Unsupported => false,
    };
    if let Some(h) = read_holder(&mut file) {
        if let Some(who) = live_record(&h, &file, held) {
            return Err(refused(who));
        }
    }
    let me = Holder::me(command);
    write_record(&mut file, &me.text())
        .with_context(|| format!("cannot write {}", path.display()))?;
    let stop = Arc::new(AtomicBool::new(false));
    let heartbeat = {
        let (stop, file) = (
            stop.clone(),
            file.try_clone().with_context(|| format!("cannot lock {}", path.display()))?,
        );
        std::thread::Builder::new()
            .name("somnurbs-lock".into())
            .spawn(move || {
                let mut file = file;
                while !stop.load(Ordering::Relaxed) {
                    std::thread::park_timeout(HEARTBEAT);
                    if !stop.load(Ordering::Relaxed) {
                        // Rewriting the record refreshes the file's modification time.
                        let _ = write_record(&mut file, &me.text());
                    }
                }
            })
            .ok()
    };
    let mut held_roots = vec![dir.to_path_buf()];
    held_roots.extend(fs::canonicalize(dir).ok().filter(|c| c != dir));
    roots().extend(held_roots.iter().cloned());
    Ok(Lock { file, path, stop, heartbeat, roots: held_roots, fill: false })
}

/// [`lock`] of a finished result folder to fill it (`somnurbs report`): every file its records
/// render that is missing is written; one that is there must already hold the rendered bytes.
pub(crate) fn lock_to_fill(dir: &Path, command: &str) -> Result<Lock> {
    let mut lock = lock(dir, command)?;
    filling().extend(lock.roots.iter().cloned());
    lock.fill = true;
    Ok(lock)
}

/// Open a folder's lock file (created when `create`) without following a link and without
/// blocking (a named pipe there would hang a plain open), refusing anything but a regular file.
fn open_lock_file(path: &Path, create: bool) -> Result<File> {
    use std::os::unix::fs::OpenOptionsExt;
    let mut opts = OpenOptions::new();
    opts.read(true).custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK);
    if create {
        opts.write(true).create(true).truncate(false);
    }
    let file = opts.open(path).map_err(|e| {
        let link = e.raw_os_error() == Some(libc::ELOOP);
        let e = anyhow::Error::from(e);
        if link {
            e.context(format!(
                "{} is a symbolic link; somnurbs opens no lock through a link (remove it)",
                path.display()
            ))
        } else {
            e.context(format!("cannot open {}", path.display()))
        }
    })?;
    let ty =
        file.metadata().with_context(|| format!("cannot read {}", path.display()))?.file_type();
    if !ty.is_file() {
        bail!(
            "{} is {}, not a regular file; remove it (somnurbs keeps its lock record there)",
            path.display(),
            crate::io::input::kind_of(ty)
        );
    }
    Ok(file)
}

fn write_record(file: &mut File, text: &str) -> std::io::Result<()> {
    file.set_len(0)?;
    file.seek(SeekFrom::Start(0))?;
    file.write_all(text.as_bytes())?;
    file.sync_data()
}

impl Drop for Lock {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.heartbeat.take() {
            h.thread().unpark();
            let _ = h.join();
        }
        // An empty record says "released"; the flock goes with the file descriptor.
        let _ = self.file.set_len(0);
        let release = |held: &mut Vec<PathBuf>| {
            for r in &self.roots {
                if let Some(k) = held.iter().position(|h| h == r) {
                    held.remove(k);
                }
            }
        };
        release(&mut roots());
        if self.fill {
            release(&mut filling());
        }
    }
}

/// Refuse to read a folder a live writer holds (a shared flock that would wait, or a live record).
pub(crate) fn require_not_being_written(dir: &Path) -> Result<()> {
    let path = dir.join(LOCK_FILE);
    if fs::symlink_metadata(&path).is_err() {
        return Ok(());
    }
    let mut file = open_lock_file(&path, false)?;
    let held = match try_flock(&file, libc::LOCK_SH)
        .with_context(|| format!("cannot check the lock {}", path.display()))?
    {
        Flock::Busy => {
            let who = read_holder(&mut file)
                .map(|h| h.describe())
                .unwrap_or_else(|| "another process".into());
            bail!("{} is being written by {who}; wait for it to finish", dir.display());
        }
        Flock::Held => true,
        Flock::Unsupported => false,
    };
    if let Some(who) = read_holder(&mut file).and_then(|h| live_record(&h, &file, held)) {
        bail!("{} is being written by {who}; wait for it to finish", dir.display());
    }
    Ok(())
}

/// Every file and folder under `dir` (relative paths, sorted), not following links to folders (a
/// link loop cannot hang a walk); links to files are listed when they point at a regular file.
pub(crate) fn walk(dir: &Path) -> Result<(Vec<PathBuf>, Vec<PathBuf>)> {
    const MAX_DEPTH: usize = 32;
    let (mut files, mut dirs) = (Vec::new(), vec![PathBuf::new()]);
    let mut stack = vec![(PathBuf::new(), 0usize)];
    while let Some((rel, depth)) = stack.pop() {
        let here = dir.join(&rel);
        let rd = fs::read_dir(&here)
            .with_context(|| format!("cannot read folder {}", here.display()))?;
        for e in rd {
            let e = e.with_context(|| format!("cannot read folder {}", here.display()))?;
            let ty =
                e.file_type().with_context(|| format!("cannot read {}", e.path().display()))?;
            let sub = rel.join(e.file_name());
            if ty.is_dir() {
                if depth + 1 > MAX_DEPTH {
                    bail!(
                        "{}: folders nested more than {MAX_DEPTH} deep",
                        dir.join(&sub).display()
                    );
                }
                dirs.push(sub.clone());
                stack.push((sub, depth + 1));
            } else if ty.is_file()
                || (ty.is_symlink() && fs::metadata(e.path()).is_ok_and(|m| m.is_file()))
            {
                files.push(sub);
            }
        }
    }
    files.sort();
    dirs.sort();
    Ok((files, dirs))
}

/// What a manifest says about completeness.
#[derive(serde::Deserialize)]
struct ManifestShard {
    #[serde(default)]
    shard: Option<String>,
}

/// Refuse a results folder that is not a finished, whole run: a run folder (holding
/// `fingerprint.toml`, `cells.jsonl` or `manifest.toml`) without `manifest.toml`, a shard's
/// folder, a `reproduce` folder still marked incomplete, or one a live writer holds. `role`
/// names the folder in messages (e.g. "the current folder").
pub(crate) fn require_finished(dir: &Path, role: &str) -> Result<()> {
    if !dir.is_dir() {
        bail!("{role} {} is not a folder", dir.display());
    }
    let (files, dirs) = walk(dir)?;
    for d in &dirs {
        let shown = if d.as_os_str().is_empty() { dir.to_path_buf() } else { dir.join(d) };
        require_not_being_written(&shown)?;
        let has = |f: &str| files.contains(&d.join(f));
        if has(INCOMPLETE) {
            bail!("{role} {} is unfinished: its reproduction did not complete ({INCOMPLETE} is still there); finish it with `somnurbs reproduce --resume`", shown.display());
        }
        let marker = [FINGERPRINT_FILE, LOG_FILE, LOG_GZ].into_iter().find(|f| has(f));
        if !has(MANIFEST) {
            if let Some(m) = marker {
                bail!("{role} {} is unfinished: it has {m} but no {MANIFEST} (the run did not complete; finish it with `somnurbs run SPEC --out {} --resume`)", shown.display(), shown.display());
            }
            continue;
        }
        let p = shown.join(MANIFEST);
        let m: ManifestShard = crate::io::read_toml(&p)?;
        if let Some(s) = m.shard {
            bail!("{role} {} holds shard {s} of a run only (no tables); combine the shards with `somnurbs merge` first", shown.display());
        }
    }
    Ok(())
}

/// Replace the folder `target` by one built by `build` in a sibling temporary folder, swapped in
/// with one atomic rename (`renameat2(RENAME_EXCHANGE)`; where the file system lacks it, two
/// renames). A failure before the swap removes the temporary folder and leaves `target` as it was.
pub(crate) fn replace_dir(target: &Path, build: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let parent = target.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let staged = temp_name(target, "staged");
    fs::create_dir(&staged).with_context(|| format!("cannot create {}", staged.display()))?;
    let built = build(&staged).and_then(|()| sync_dir(&staged));
    if let Err(e) = built {
        let _ = fs::remove_dir_all(&staged);
        return Err(e);
    }
    let swapped = if target.exists() {
        exchange(&staged, target)
    } else {
        fs::rename(&staged, target).map(|()| true)
    };
    match swapped {
        Ok(true) => {}
        Ok(false) => {
            // No RENAME_EXCHANGE here: move the old folder aside, then the new one in.
            let old = temp_name(target, "old");
            fs::rename(target, &old)
                .with_context(|| format!("cannot move {} aside", target.display()))?;
            if let Err(e) = fs::rename(&staged, target) {
                let _ = fs::rename(&old, target);
                let _ = fs::remove_dir_all(&staged);
                return Err(e)
                    .with_context(|| format!("cannot move the new {} in place", target.display()));
            }
            let _ = fs::remove_dir_all(&old);
        }
        Err(e) => {
            let _ = fs::remove_dir_all(&staged);
            return Err(e).with_context(|| {
                format!("cannot swap {} into {}", staged.display(), target.display())
            });
        }
    }
    // After an exchange, `staged` holds the old folder.
    if staged.exists() {
        let _ = fs::remove_dir_all(&staged);
    }
    sync_dir(parent)
}

/// The folders an interrupted [`replace_dir`] of `target` left beside it: its temporary siblings
/// (`.NAME.PID.N.staged` or `.old`, names [`temp_name`] made for it; real folders, not links)
/// whose process is not alive on this host. Sorted; none when the parent does not exist.
pub(crate) fn stale_siblings(target: &Path) -> Result<Vec<PathBuf>> {
    let parent = target.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let rd = match fs::read_dir(parent) {
        Ok(rd) => rd,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => {
            return Err(e).with_context(|| format!("cannot read folder {}", parent.display()))
        }
    };
    let mut out = Vec::new();
    for e in rd {
        let e = e.with_context(|| format!("cannot read folder {}", parent.display()))?;
        let entry = e.file_name().to_string_lossy().into_owned();
        if !e.file_type().is_ok_and(|t| t.is_dir()) || !is_temp_name(&entry) {
            continue;
        }
        let mut parts = entry[1..].rsplitn(4, '.');
        let (what, _, pid, stem) = (parts.next(), parts.next(), parts.next(), parts.next());
        let pid = pid.and_then(|p| p.parse::<u32>().ok());
        if stem == Some(name.as_str())
            && matches!(what, Some("staged" | "old"))
            && pid.is_some_and(|p| !pid_alive(p))
        {
            out.push(e.path());
        }
    }
    out.sort();
    Ok(out)
}

/// Remove `stale` ([`stale_siblings`] of `target`, left by an interrupted `command`), saying so
/// in one line; call it only while holding the lock that guards `target`.
pub(crate) fn remove_stale(stale: &[PathBuf], target: &Path, command: &str) -> Result<()> {
    if stale.is_empty() {
        return Ok(());
    }
    for s in stale {
        fs::remove_dir_all(s).with_context(|| {
            format!("cannot remove {}, left by an interrupted {command}", s.display())
        })?;
    }
    let names: Vec<String> = stale
        .iter()
        .filter_map(|s| s.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    crate::notice::emit(&format!(
        "somnurbs: note: removed {} folder(s) an interrupted {command} left beside {} (their process is gone): {}",
        stale.len(),
        target.display(),
        names.join(", ")
    ));
    Ok(())
}

/// Atomically exchange two paths; Ok(false) if the file system cannot.
fn exchange(a: &Path, b: &Path) -> std::io::Result<bool> {
    use std::os::unix::ffi::OsStrExt;
    let c = |p: &Path| {
        std::ffi::CString::new(p.as_os_str().as_bytes()).map_err(|_| {
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "path holds a NUL byte")
        })
    };
    let (ca, cb) = (c(a)?, c(b)?);
    // SAFETY: two NUL-terminated paths relative to the working folder.
    let rc = unsafe {
        libc::renameat2(
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            libc::RENAME_EXCHANGE,
        )
    };
    if rc == 0 {
        return Ok(true);
    }
    let e = std::io::Error::last_os_error();
    match e.raw_os_error() {
        Some(libc::EINVAL) | Some(libc::ENOSYS) | Some(libc::EOPNOTSUPP) => Ok(false),
        _ => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_writer_is_refused_and_a_released_lock_is_free() {
        let dir = tempfile::tempdir().unwrap();
        let a = lock(dir.path(), "run a.toml").unwrap();
        let e = lock(dir.path(), "run b.toml").unwrap_err().to_string();
        assert!(
            e.contains("in use")
                && e.contains(&format!("pid {}", std::process::id()))
                && e.contains("run a.toml"),
            "{e}"
        );
        assert!(require_not_being_written(dir.path()).is_err());
        drop(a);
        require_not_being_written(dir.path()).unwrap();
        drop(lock(dir.path(), "run b.toml").unwrap());
    }

    #[test]
    fn a_fresh_record_of_another_host_refuses_and_a_stale_one_does_not() {
        let dir = tempfile::tempdir().unwrap();
        let other = Holder {
            host: "elsewhere-node-17".into(),
            pid: 4242,
            since: 1,
            command: "run x.toml".into(),
        };
        fs::write(dir.path().join(LOCK_FILE), other.text()).unwrap();
        let e = lock(dir.path(), "run y.toml").unwrap_err().to_string();
        assert!(e.contains("elsewhere-node-17") && e.contains("pid 4242"), "{e}");
        let old = SystemTime::now() - STALE_AFTER - Duration::from_secs(5);
        File::options()
            .write(true)
            .open(dir.path().join(LOCK_FILE))
            .unwrap()
            .set_modified(old)
            .unwrap();
        drop(lock(dir.path(), "run y.toml").unwrap());
        // A dead process of this host does not hold a folder either.
        let dead =
            Holder { host: host_name(), pid: 999_999_999, since: 1, command: "run z.toml".into() };
        fs::write(dir.path().join(LOCK_FILE), dead.text()).unwrap();
        drop(lock(dir.path(), "run y.toml").unwrap());
    }

    #[test]
    fn walk_does_not_follow_folder_links() {
        let dir = tempfile::tempdir().unwrap();
        fs::create_dir(dir.path().join("a")).unwrap();
        fs::write(dir.path().join("a/t.csv"), "x\n1\n").unwrap();
        std::os::unix::fs::symlink(dir.path(), dir.path().join("a/loop1")).unwrap();
        std::os::unix::fs::symlink(dir.path(), dir.path().join("loop2")).unwrap();
        let (files, dirs) = walk(dir.path()).unwrap();
        assert_eq!(files, vec![PathBuf::from("a/t.csv")]);
        assert_eq!(dirs, vec![PathBuf::new(), PathBuf::from("a")]);
    }

    #[test]
    fn unfinished_and_shard_folders_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path().join("ch4");
        fs::create_dir(&run).unwrap();
        fs::write(run.join("runs.csv"), "a\n1\n").unwrap();
        fs::write(run.join("cells.jsonl"), "").unwrap();
        let e = require_finished(dir.path(), "the current folder").unwrap_err().to_string();
        assert!(
            e.contains("ch4") && e.contains("no manifest.toml") && e.contains("cells.jsonl"),
            "{e}"
        );
        fs::write(run.join(MANIFEST), "shard = \"2/3\"\n").unwrap();
        let e = require_finished(dir.path(), "x").unwrap_err().to_string();
        assert!(e.contains("shard 2/3"), "{e}");
        fs::write(run.join(MANIFEST), "spec_name = \"x\"\n").unwrap();
        require_finished(dir.path(), "x").unwrap();
        fs::write(dir.path().join(INCOMPLETE), "").unwrap();
        assert!(require_finished(dir.path(), "x")
            .unwrap_err()
            .to_string()
            .contains("reproduction did not complete"));
    }

    #[test]
    fn a_failed_build_leaves_the_old_folder_and_a_good_one_swaps_whole() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("base");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("a.csv"), "old").unwrap();
        let e = replace_dir(&target, |d| {
            fs::write(d.join("a.csv"), "new")?;
            bail!("disk full")
        });
        assert!(e.is_err());
        assert_eq!(fs::read_to_string(target.join("a.csv")).unwrap(), "old");
        replace_dir(&target, |d| Ok(fs::write(d.join("b.csv"), "new")?)).unwrap();
        assert!(!target.join("a.csv").exists() && target.join("b.csv").exists());
        let names: Vec<String> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, vec!["base"], "no temporary folder left behind");
    }

    /// Only the target's own staged and old siblings of a dead process are stale: not another
    /// name's, not a live process's, not a temporary file, not a link.
    #[test]
    fn stale_siblings_are_the_targets_leftovers_of_dead_processes() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("compare");
        let me = std::process::id();
        for name in [
            ".compare.999999999.0.staged".to_string(),
            ".compare.999999998.3.old".to_string(),
            format!(".compare.{me}.0.staged"),
            ".other.999999999.0.staged".to_string(),
            ".compare.999999999.0.tmp".to_string(),
            ".compare.x.0.staged".to_string(),
        ] {
            fs::create_dir(dir.path().join(name)).unwrap();
        }
        fs::write(dir.path().join(".compare.999999997.0.old"), "").unwrap();
        std::os::unix::fs::symlink(dir.path(), dir.path().join(".compare.999999996.0.old"))
            .unwrap();
        let found = stale_siblings(&target).unwrap();
        let names: Vec<String> =
            found.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
        assert_eq!(names, vec![".compare.999999998.3.old", ".compare.999999999.0.staged"]);
        assert!(stale_siblings(&dir.path().join("missing/compare")).unwrap().is_empty());
    }
}
