//! The durable cell log of an output folder, and the fingerprint that says which run it belongs to.
//!
//! `cells.jsonl` holds one JSON line per finished cell, `{"key": …, "seed": …, "record": …}`
//! (`seed`: the cell's seed, checked against the spec's when the log is read back), appended and
//! flushed the moment the cell finishes. A run killed at any instant leaves every finished cell on
//! disk and at most one torn last line (a write cut short has no trailing newline), which a resumed
//! run drops. `fingerprint.toml` is written before the first cell: a resumed run (`--resume`) or a
//! merge of shards compares it with its own and refuses, naming the field, when they differ.

use anyhow::{bail, Context, Result};
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};

pub(crate) use crate::io::outdir::{FINGERPRINT_FILE, LOG_FILE, LOG_GZ};

/// The `I`-th of `N` deterministic slices of a spec's cells (1-based): cell number k belongs to
/// shard (k mod N) + 1, so every shard gets a mix of small and large cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl Shard {
    /// Parse `I/N` with 1 <= I <= N.
    pub fn parse(s: &str) -> Result<Shard> {
        let (i, n) =
            s.split_once('/').with_context(|| format!("--shard `{s}`: expected I/N, e.g. 2/8"))?;
        let (index, count): (usize, usize) = (
            i.trim().parse().with_context(|| format!("--shard `{s}`: I is not a number"))?,
            n.trim().parse().with_context(|| format!("--shard `{s}`: N is not a number"))?,
        );
        if count == 0 || index == 0 || index > count {
            bail!("--shard `{s}`: need 1 <= I <= N");
        }
        Ok(Shard { index, count })
    }

    /// Whether cell number `k` (0-based, in the spec's cell order) is in this shard.
    pub fn contains(&self, k: usize) -> bool {
        k % self.count == self.index - 1
    }
}

/// `merge`'s output folder must not be one of the shard folders it reads (compared as canonical
/// paths, so `s1`, `./s1/` and a link to it are one folder).
pub(crate) fn out_is_no_shard(shards: &[PathBuf], out: &Path) -> Result<()> {
    let Ok(target) = out.canonicalize() else { return Ok(()) };
    for dir in shards {
        if dir.canonicalize().is_ok_and(|d| d == target) {
            bail!(
                "merge: --out {} is the shard folder {} (write the merged run to a new folder)",
                out.display(),
                dir.display()
            );
        }
    }
    Ok(())
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// What makes two runs the same run: the spec (text after which profile), the seed, the shard.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Fingerprint {
    pub(crate) spec_name: String,
    pub(crate) spec_path: String,
    pub(crate) spec_sha256: String,
    pub(crate) profile: String,
    pub(crate) master_seed: u64,
    /// Cells in the whole spec (all shards).
    pub(crate) cells: usize,
    /// `I/N` when the folder holds one shard.
    #[serde(default)]
    pub(crate) shard: Option<String>,
    /// The spec's text, so that a merge can re-read it.
    pub(crate) spec_text: String,
    /// The command line's `--set KEY=VALUE` and `--sweep KEY=V1,V2` (absent for a plain run).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) set: Vec<String>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) sweep: Vec<String>,
    /// A plan's reading set's keys that reached the spec (`readings/<set>/<spec>`), applied over
    /// `spec_text` as the plan applied them (absent outside a reading set).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub(crate) readings: BTreeMap<String, toml::Value>,
}

/// A reading set's keys in words (`none` outside a set).
fn readings_text(r: &BTreeMap<String, toml::Value>) -> String {
    if r.is_empty() {
        return "none".into();
    }
    r.iter().map(|(k, v)| format!("{k} = {v}")).collect::<Vec<_>>().join(", ")
}

impl Fingerprint {
    /// The first field in which `other` differs, as `name: ours vs theirs` (None if equal).
    pub(crate) fn difference(&self, other: &Fingerprint) -> Option<String> {
        let pairs = [
            ("spec name", self.spec_name.clone(), other.spec_name.clone()),
            ("master seed", self.master_seed.to_string(), other.master_seed.to_string()),
            ("profile", self.profile.clone(), other.profile.clone()),
            ("spec text (sha256)", self.spec_sha256.clone(), other.spec_sha256.clone()),
            ("cell count", self.cells.to_string(), other.cells.to_string()),
            (
                "shard",
                self.shard.clone().unwrap_or_else(|| "none".into()),
                other.shard.clone().unwrap_or_else(|| "none".into()),
            ),
            ("--set", shown(&self.set), shown(&other.set)),
            ("--sweep", shown(&self.sweep), shown(&other.sweep)),
            ("reading set", readings_text(&self.readings), readings_text(&other.readings)),
        ];
        pairs.into_iter().find(|(_, a, b)| a != b).map(|(name, a, b)| format!("{name}: {a} vs {b}"))
    }

    /// The reading set's keys as overrides, as the plan applied them.
    pub(crate) fn reading_overrides(&self) -> Vec<super::Override> {
        self.readings
            .iter()
            .map(|(k, v)| super::Override { key: k.clone(), value: v.clone() })
            .collect()
    }

    /// The command line's changes, as a spec reads them back (merge).
    pub(crate) fn overrides(&self) -> super::spec::CliOverrides {
        super::spec::CliOverrides { set: self.set.clone(), sweep: self.sweep.clone() }
    }

    pub(crate) fn read(dir: &Path) -> Result<Option<Fingerprint>> {
        let path = dir.join(FINGERPRINT_FILE);
        if !path.exists() {
            return Ok(None);
        }
        let fp = crate::io::read_toml(&path)?;
        Ok(Some(fp))
    }

    pub(crate) fn write(&self, dir: &Path) -> Result<()> {
        let text = toml::to_string(self).context("cannot serialise the fingerprint")?;
        crate::io::write_atomic(&dir.join(FINGERPRINT_FILE), text.as_bytes())
    }
}

/// A list of command-line changes for messages ("none" when empty).
fn shown(list: &[String]) -> String {
    if list.is_empty() {
        "none".into()
    } else {
        list.join(" ")
    }
}

#[derive(Serialize, Deserialize)]
struct Line<T> {
    key: String,
    #[serde(default)]
    seed: Option<String>,
    /// The folder a reused cell's record was taken from (`--reuse`, a plan's reading sets).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    reused_from: Option<String>,
    record: T,
}

/// The records of the cells `wanted` that the log of `dir` holds (another run's folder, read
/// only: a torn last line is skipped, never cut), matched by their whole key, i.e. by what the
/// cells compute ([`super::seeds::identity_key`], which includes the master seed).
pub(crate) fn read_matching(
    dir: &Path,
    wanted: &std::collections::BTreeSet<String>,
) -> Result<BTreeMap<String, serde_json::Value>> {
    let mut out = BTreeMap::new();
    let texts = log_parts(dir)?;
    if texts.is_empty() {
        bail!("{}: no cell log ({LOG_GZ} or {LOG_FILE}) to reuse cells from", dir.display());
    }
    #[derive(Deserialize)]
    struct KeyOnly {
        key: String,
    }
    for (path, text) in &texts {
        let complete = text.rfind('\n').map_or(0, |k| k + 1);
        for (n, line) in text[..complete].lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let bad = |e: serde_json::Error| {
                anyhow::anyhow!("{}:{}: malformed cell record: {e}", path.display(), n + 1)
            };
            let k: KeyOnly = serde_json::from_str(line).map_err(bad)?;
            if wanted.contains(&k.key) {
                let l: Line<serde_json::Value> = serde_json::from_str(line).map_err(bad)?;
                out.insert(l.key, l.record);
            }
        }
    }
    Ok(out)
}

/// How many cells of `dir`'s log were taken from another folder: the lines with a `reused_from`
/// field (a scan for the field's name, which no key or value contains; the run has read and
/// checked every line already, so no line is parsed again).
pub(crate) fn count_reused(dir: &Path) -> Result<usize> {
    Ok(log_text(dir)?.lines().filter(|l| l.contains("\"reused_from\":")).count())
}

/// The finished cells a folder's log holds, by key (the last line wins if a key repeats): the
/// compressed log of a finished run ([`LOG_GZ`]) first, then the plain one ([`LOG_FILE`]). A torn
/// last line of the plain log (no newline: the write was cut short) is dropped and cut off the
/// file; any other malformed line is an error naming the file and line, and so is a line whose
/// seed is not the cell's seed under `master_seed` (a log that mixes runs).
pub(crate) fn read_records<T: DeserializeOwned>(
    dir: &Path,
    master_seed: u64,
) -> Result<BTreeMap<String, T>> {
    let mut out = BTreeMap::new();
    let gz = dir.join(LOG_GZ);
    if gz.exists() {
        parse_lines(&gz, &gunzip(&gz)?, master_seed, &mut out)?;
    }
    let path = dir.join(LOG_FILE);
    if !path.exists() {
        return Ok(out);
    }
    let text = crate::io::read_text(&path)?;
    let complete = match text.rfind('\n') {
        Some(k) => k + 1,
        None => 0,
    };
    parse_lines(&path, &text[..complete], master_seed, &mut out)?;
    if complete < text.len() {
        crate::io::outdir::no_link_inside(&path)?;
        let f = OpenOptions::new()
            .write(true)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&path)
            .with_context(|| format!("cannot open {}", path.display()))?;
        f.set_len(complete as u64)
            .with_context(|| format!("cannot cut the torn last line of {}", path.display()))?;
    }
    Ok(out)
}

fn parse_lines<T: DeserializeOwned>(
    path: &Path,
    text: &str,
    master_seed: u64,
    out: &mut BTreeMap<String, T>,
) -> Result<()> {
    for (n, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let l: Line<T> = serde_json::from_str(line).map_err(|e| {
            anyhow::anyhow!("{}:{}: malformed cell record: {e}", path.display(), n + 1)
        })?;
        let want = super::seeds::seed_hex(master_seed, super::seeds::place_of(&l.key));
        if l.seed.as_deref() != Some(want.as_str()) {
            bail!("{}:{}: cell {} was logged with seed {}, but its seed in this run is {want} (the folder mixes runs: start afresh without --resume)", path.display(), n + 1, l.key, l.seed.as_deref().unwrap_or("none"));
        }
        out.insert(l.key, l.record);
    }
    Ok(())
}

/// The text of a gzip-compressed log, whole (a truncated or corrupt file is an error naming it).
fn gunzip(path: &Path) -> Result<String> {
    // Decompressed, the log is bounded like any other log (a small file can hold a huge line).
    let text = crate::io::gunzip_text(path, 8, "cell log")?;
    if !text.is_empty() && !text.ends_with('\n') {
        bail!("{}: its last line is torn", path.display());
    }
    Ok(text)
}

/// Whether `dir` holds a cell log (compressed, plain or both).
pub(crate) fn has_log(dir: &Path) -> bool {
    dir.join(LOG_GZ).is_file() || dir.join(LOG_FILE).is_file()
}

/// The text of each part of a folder's log that is there, compressed part first, with its path.
fn log_parts(dir: &Path) -> Result<Vec<(PathBuf, String)>> {
    let mut parts = Vec::new();
    let gz = dir.join(LOG_GZ);
    if gz.exists() {
        let text = gunzip(&gz)?;
        parts.push((gz, text));
    }
    let plain = dir.join(LOG_FILE);
    if plain.exists() {
        let text = crate::io::read_text(&plain)?;
        parts.push((plain, text));
    }
    Ok(parts)
}

/// The whole log of a folder as text, compressed part first (for tests and tools that read it).
pub fn log_text(dir: &Path) -> Result<String> {
    Ok(log_parts(dir)?.into_iter().map(|(_, text)| text).collect())
}

/// Compress a finished run's log: the plain log's complete lines are added to `cells.jsonl.gz`
/// (written whole, atomically), then the plain log is removed. Interrupted at any point, the
/// folder still holds every line once: [`read_records`] reads both files.
pub(crate) fn compress(dir: &Path) -> Result<()> {
    use std::io::Write as _;
    let plain = dir.join(LOG_FILE);
    if !plain.exists() {
        return Ok(());
    }
    let text = log_text(dir)?;
    let complete = text.rfind('\n').map(|k| k + 1).unwrap_or(0);
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::new(6));
    enc.write_all(&text.as_bytes()[..complete]).context("cannot compress the cell log")?;
    let bytes = enc.finish().context("cannot compress the cell log")?;
    crate::io::write_atomic(&dir.join(LOG_GZ), &bytes)?;
    std::fs::remove_file(&plain).with_context(|| format!("cannot remove {}", plain.display()))
}

/// Appends one line per finished cell, flushed at once.
pub(crate) struct CellLog {
    file: File,
    path: PathBuf,
    master_seed: u64,
}

impl CellLog {
    /// Open the folder's log: appending to it when resuming, else starting it empty. A run
    /// opens it once, empty or not, and every cell family of the spec appends (`append`).
    pub(crate) fn open(dir: &Path, resume: bool, master_seed: u64) -> Result<CellLog> {
        let path = dir.join(LOG_FILE);
        crate::io::outdir::no_link_inside(&path)?;
        crate::io::require_regular_or_absent(&path)?;
        let mut opts = OpenOptions::new();
        opts.create(true).custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK);
        if resume {
            opts.append(true);
        } else {
            opts.write(true).truncate(true);
        }
        let file = opts.open(&path).with_context(|| format!("cannot open {}", path.display()))?;
        Ok(CellLog { file, path, master_seed })
    }

    /// Append to the folder's log (created if missing).
    pub(crate) fn append(dir: &Path, master_seed: u64) -> Result<CellLog> {
        CellLog::open(dir, true, master_seed)
    }

    pub(crate) fn push<T: Serialize>(&mut self, key: &str, record: &T) -> Result<()> {
        self.push_line(key, record, None)
    }

    /// [`push`](Self::push) of a record taken from another folder's log (`from`, which the
    /// line names, so the manifest can count the cells a run reused).
    pub(crate) fn push_line<T: Serialize>(
        &mut self,
        key: &str,
        record: &T,
        reused_from: Option<&str>,
    ) -> Result<()> {
        let seed = Some(super::seeds::seed_hex(self.master_seed, super::seeds::place_of(key)));
        let reused_from = reused_from.map(str::to_string);
        let line = Line { key: key.to_string(), seed, reused_from, record };
        let mut line = serde_json::to_string(&line).context("cannot serialise a cell record")?;
        line.push('\n');
        self.file
            .write_all(line.as_bytes())
            .with_context(|| format!("cannot append to {}", self.path.display()))?;
        self.file.flush().with_context(|| format!("cannot flush {}", self.path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_cells() {
        let n = 3;
        let shards: Vec<Shard> =
            (1..=n).map(|i| Shard::parse(&format!("{i}/{n}")).unwrap()).collect();
        for k in 0..20 {
            assert_eq!(shards.iter().filter(|s| s.contains(k)).count(), 1);
        }
        for bad in ["0/3", "4/3", "1/0", "x/2", "3"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(Shard::parse("2/5").unwrap().to_string(), "2/5");
    }

    #[test]
    fn log_survives_a_torn_last_line_and_names_a_bad_one() {
        let dir = tempfile::tempdir().unwrap();
        {
            let mut log = CellLog::open(dir.path(), false, 5).unwrap();
            log.push("a", &vec![1.0, 2.0]).unwrap();
            log.push("b", &vec![3.0]).unwrap();
        }
        // A write cut short.
        let path = dir.path().join(LOG_FILE);
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(b"{\"key\":\"c\",\"rec").unwrap();
        drop(f);
        let got: BTreeMap<String, Vec<f64>> = read_records(dir.path(), 5).unwrap();
        assert_eq!(got.len(), 2);
        assert_eq!(got["b"], vec![3.0]);
        // The torn line is gone, so appending continues on a clean line.
        let mut log = CellLog::open(dir.path(), true, 5).unwrap();
        log.push("c", &vec![4.0]).unwrap();
        let got: BTreeMap<String, Vec<f64>> = read_records(dir.path(), 5).unwrap();
        assert_eq!(got.keys().cloned().collect::<Vec<_>>(), vec!["a", "b", "c"]);
        // Lines of another run (another master seed) mixed in are named.
        CellLog::open(dir.path(), true, 6).unwrap().push("d", &vec![5.0]).unwrap();
        let e = read_records::<Vec<f64>>(dir.path(), 5).unwrap_err().to_string();
        assert!(
            e.contains("cells.jsonl:4") && e.contains("cell d") && e.contains("mixes runs"),
            "{e}"
        );
        let a = format!(
            "{{\"key\":\"a\",\"seed\":\"{}\",\"record\":[1]}}",
            crate::experiment::seeds::seed_hex(5, "a")
        );
        std::fs::write(&path, format!("{a}\nnot json\n")).unwrap();
        let e = read_records::<Vec<f64>>(dir.path(), 5).unwrap_err().to_string();
        assert!(e.contains("cells.jsonl:2"), "{e}");
    }

    #[test]
    fn records_keep_every_bit_of_a_float() {
        let dir = tempfile::tempdir().unwrap();
        let xs: Vec<f64> = vec![
            10.552161934452197,
            0.1 + 0.2,
            1e-300,
            f64::MIN_POSITIVE,
            2.0f64.sqrt(),
            -1.0 / 3.0,
        ];
        CellLog::open(dir.path(), false, 1).unwrap().push("k", &xs).unwrap();
        let back: BTreeMap<String, Vec<f64>> = read_records(dir.path(), 1).unwrap();
        assert_eq!(
            back["k"].iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            xs.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_compressed_log_reads_as_the_plain_one_and_takes_more_lines_after_it() {
        let dir = tempfile::tempdir().unwrap();
        let mut log = CellLog::open(dir.path(), false, 3).unwrap();
        for (k, v) in [("a", 1.0), ("b", 0.1 + 0.2)] {
            log.push(k, &vec![v]).unwrap();
        }
        drop(log);
        let plain: BTreeMap<String, Vec<f64>> = read_records(dir.path(), 3).unwrap();
        compress(dir.path()).unwrap();
        assert!(!dir.path().join(LOG_FILE).exists() && dir.path().join(LOG_GZ).exists());
        assert_eq!(read_records::<Vec<f64>>(dir.path(), 3).unwrap(), plain);
        // A resumed run appends to a new plain log; both are read, and compressed again whole.
        CellLog::open(dir.path(), true, 3).unwrap().push("c", &vec![2.0]).unwrap();
        assert_eq!(read_records::<Vec<f64>>(dir.path(), 3).unwrap().len(), 3);
        compress(dir.path()).unwrap();
        let all: BTreeMap<String, Vec<f64>> = read_records(dir.path(), 3).unwrap();
        assert_eq!((all.len(), all["b"][0].to_bits()), (3, (0.1f64 + 0.2).to_bits()));
        assert_eq!(log_text(dir.path()).unwrap().lines().count(), 3);
        // A truncated compressed log is named.
        let gz = dir.path().join(LOG_GZ);
        let bytes = std::fs::read(&gz).unwrap();
        std::fs::write(&gz, &bytes[..bytes.len() / 2]).unwrap();
        let e = read_records::<Vec<f64>>(dir.path(), 3).unwrap_err().to_string();
        assert!(e.contains("cells.jsonl.gz") && e.contains("not a whole"), "{e}");
    }

    #[test]
    fn fingerprint_names_the_first_difference() {
        let a = Fingerprint {
            spec_name: "s".into(),
            spec_path: "s.toml".into(),
            spec_sha256: "ab".into(),
            profile: "quick".into(),
            master_seed: 1,
            cells: 4,
            shard: None,
            spec_text: String::new(),
            set: Vec::new(),
            sweep: Vec::new(),
            readings: BTreeMap::new(),
        };
        assert_eq!(a.difference(&a.clone()), None);
        let b = Fingerprint { master_seed: 2, ..a.clone() };
        assert_eq!(a.difference(&b).unwrap(), "master seed: 1 vs 2");
        let c = Fingerprint { profile: "default".into(), ..a.clone() };
        assert!(a.difference(&c).unwrap().starts_with("profile"));
        let d = Fingerprint { set: vec!["optimise.de.f=0.5".into()], ..a.clone() };
        assert_eq!(a.difference(&d).unwrap(), "--set: none vs optimise.de.f=0.5");
        let readings = BTreeMap::from([("optimise.knots".to_string(), "nurbs_book".into())]);
        let e = Fingerprint { readings, ..a.clone() };
        assert_eq!(
            a.difference(&e).unwrap(),
            "reading set: none vs optimise.knots = \"nurbs_book\""
        );
    }
}
