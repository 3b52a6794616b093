//! All file output goes through here: every error carries its path, and every finished file is
//! written to a unique temporary name in the same folder, synced, renamed, and the folder synced,
//! so a reader never sees half a file and two writers never share a temporary file (the rest of
//! the output-folder contract is in [`crate::io::outdir`]).

pub mod outdir;

use anyhow::{Context, Result};
use std::fs::{self, File};
use std::io::Write;
use std::path::Path;

/// Create a folder (and parents), naming it on failure.
pub fn ensure_dir(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir).with_context(|| format!("cannot create folder {}", dir.display()))
}

/// Refuse to replace anything but a regular file: a rename would put a plain file in place of a
/// device, a pipe, a socket, a folder or a link (a link's target would not be written).
pub fn require_regular_or_absent(path: &Path) -> Result<()> {
    let Ok(meta) = fs::symlink_metadata(path) else { return Ok(()) };
    let ty = meta.file_type();
    if ty.is_file() {
        return Ok(());
    }
    let kind = {
        use std::os::unix::fs::FileTypeExt;
        if ty.is_dir() {
            "a folder"
        } else if ty.is_symlink() {
            "a symbolic link"
        } else if ty.is_char_device() || ty.is_block_device() {
            "a device"
        } else if ty.is_fifo() {
            "a named pipe"
        } else if ty.is_socket() {
            "a socket"
        } else {
            "not a regular file"
        }
    };
    anyhow::bail!(
        "cannot write {}: it is {kind}, and somnurbs replaces only regular files; name a new file",
        path.display()
    )
}

/// Write `bytes` to `path` atomically (temporary file + rename); `path` must be a regular file or
/// absent ([`require_regular_or_absent`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    require_regular_or_absent(path)?;
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        ensure_dir(parent)?;
    }
    let tmp = crate::io::outdir::temp_name(path, "tmp");
    let result = (|| -> std::io::Result<()> {
        let mut f = File::options().write(true).create_new(true).open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.with_context(|| format!("cannot write {}", path.display()))?;
    crate::io::outdir::sync_dir(path.parent().unwrap_or(Path::new(".")))
}

/// Read a whole file as text, naming it on failure.
pub fn read_text(path: &Path) -> Result<String> {
    fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

/// A TOML parse error on one line, `path:line:col: message` (toml's own Display spans several
/// lines with a snippet of the file).
pub fn toml_message(path: &str, text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.len() - before.rfind('\n').map(|p| p + 1).unwrap_or(0) + 1;
            format!("{path}:{line}:{col}: {msg}")
        }
        None => format!("{path}: {msg}"),
    }
}

/// Read and parse a TOML file; an error names the file, and the line and column where it can.
pub fn read_toml<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let text = read_text(path)?;
    toml::from_str(&text)
        .map_err(|e| anyhow::Error::msg(toml_message(&path.display().to_string(), &text, &e)))
}

/// Typed rows of a CSV file (extra columns ignored); errors name the file and line.
pub fn read_rows<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    let text = read_text(path)?;
    let mut rd = csv::Reader::from_reader(text.as_bytes());
    rd.deserialize()
        .enumerate()
        .map(|(k, r)| r.with_context(|| format!("{}: line {}", path.display(), k + 2)))
        .collect()
}

/// A CSV field with a negative zero ("-0", "-0.0000", "-0e0": an empty f64 sum, or a small negative
/// value rounded for print) written as zero; every other field unchanged.
fn no_negative_zero(field: &str) -> &str {
    match field.strip_prefix('-') {
        Some(rest)
            if rest.starts_with(|c: char| c.is_ascii_digit()) && rest.parse::<f64>() == Ok(0.0) =>
        {
            rest
        }
        _ => field,
    }
}

/// Serialise rows to CSV text (header from the struct's field names), with no negative zero.
pub fn csv_text<T: serde::Serialize>(rows: &[T]) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)?;
    }
    let raw = w.into_inner().map_err(|e| e.into_error())?;
    let mut reader = csv::ReaderBuilder::new().has_headers(false).from_reader(raw.as_slice());
    let mut out = csv::Writer::from_writer(Vec::new());
    for record in reader.records() {
        out.write_record(record?.iter().map(no_negative_zero))?;
    }
    Ok(String::from_utf8(out.into_inner().map_err(|e| e.into_error())?)?)
}

/// CSV text from a header and string records, with no negative zero.
pub fn csv_records(header: &[String], rows: &[Vec<String>]) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header)?;
    for r in rows {
        w.write_record(r.iter().map(|f| no_negative_zero(f)))?;
    }
    Ok(String::from_utf8(w.into_inner().map_err(|e| e.into_error())?)?)
}

/// A path as messages and reports show it: `.` and `dir/..` dropped (lexically; the path opened
/// is unchanged), and relative to the working folder when it lies inside it.
pub fn shown(path: &Path) -> String {
    use std::path::{Component, PathBuf};
    let mut parts: Vec<Component> = Vec::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if matches!(parts.last(), Some(Component::Normal(_))) => {
                parts.pop();
            }
            c => parts.push(c),
        }
    }
    let clean: PathBuf = parts.iter().collect();
    if clean.is_absolute() {
        if let Some(rel) = std::env::current_dir()
            .ok()
            .and_then(|cwd| clean.strip_prefix(cwd).ok().map(Path::to_path_buf))
            .filter(|r| !r.as_os_str().is_empty())
        {
            return rel.display().to_string();
        }
    }
    if clean.as_os_str().is_empty() {
        return ".".into();
    }
    clean.display().to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shown_paths_are_clean_and_relative_to_the_working_folder() {
        assert_eq!(shown(Path::new("experiments/../results/ch4/maps")), "results/ch4/maps");
        assert_eq!(shown(Path::new("./a/./b")), "a/b");
        assert_eq!(shown(Path::new("../shared/data")), "../shared/data");
        assert_eq!(shown(Path::new("a/..")), ".");
        let cwd = std::env::current_dir().unwrap();
        assert_eq!(shown(&cwd.join("results/x")), "results/x");
        assert_eq!(shown(Path::new("/nonexistent/x/../y")), "/nonexistent/y");
    }

    #[derive(serde::Serialize)]
    struct Row {
        name: &'static str,
        v: f64,
    }

    #[test]
    fn no_negative_zero_in_csv() {
        let h = vec!["a".to_string(), "b".to_string(), "c".to_string(), "d".to_string()];
        let rows = vec![
            vec!["-0".to_string(), "-0.0000".to_string(), "-1e-300".to_string(), "-x".to_string()],
            vec![
                format!("{}", -0.0f64),
                format!("{:e}", -0.0f64),
                "-0.5".to_string(),
                "-".to_string(),
            ],
        ];
        assert_eq!(csv_records(&h, &rows).unwrap(), "a,b,c,d\n0,0.0000,-1e-300,-x\n0,0e0,-0.5,-\n");
        let t = csv_text(&[Row { name: "-0", v: -0.0 }, Row { name: "a,b", v: -2.5 }]).unwrap();
        assert_eq!(t, "name,v\n0,0.0\n\"a,b\",-2.5\n");
    }

    #[test]
    fn atomic_write_leaves_no_temp_and_names_path_on_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a/b.csv");
        write_atomic(&p, b"x,y\n").unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "x,y\n");
        assert_eq!(
            fs::read_dir(dir.path().join("a")).unwrap().count(),
            1,
            "no temporary file left"
        );
        let blocked = dir.path().join("a/b.csv/c.csv");
        let e = format!("{:#}", write_atomic(&blocked, b"1").unwrap_err());
        assert!(e.contains("b.csv"), "{e}");
    }
}
