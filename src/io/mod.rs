//! All file output goes through here: every error carries its path, and every finished file is
//! written to a unique temporary name in the same folder, synced, renamed, and the folder synced,
//! so a reader never sees half a file and two writers never share a temporary file (the rest of
//! the output-folder contract is in [`crate::io::outdir`]).

pub(crate) mod input;
pub(crate) mod map_file;
pub(crate) mod outdir;

use anyhow::{Context, Result};
use std::fs::{self, File};
use std::io::Write;
use std::path::Path;

/// Create a folder (and parents), naming it on failure; inside a result folder this process
/// writes, no part of the path may be a link ([`outdir::no_link_inside`]).
pub(crate) fn ensure_dir(dir: &Path) -> Result<()> {
    outdir::no_link_inside(dir)?;
    fs::create_dir_all(dir).with_context(|| format!("cannot create folder {}", dir.display()))
}

/// Refuse to replace anything but a regular file: a rename would put a plain file in place of a
/// device, a pipe, a socket, a folder or a link (a link's target would not be written).
pub(crate) fn require_regular_or_absent(path: &Path) -> Result<()> {
    let Ok(meta) = fs::symlink_metadata(path) else { return Ok(()) };
    if meta.file_type().is_file() {
        return Ok(());
    }
    anyhow::bail!(
        "cannot write {}: it is {}, and somnurbs replaces only regular files; name a new file",
        path.display(),
        input::kind_of(meta.file_type())
    )
}

/// Write `bytes` to `path` atomically (temporary file + rename); `path` must be a regular file or
/// absent ([`require_regular_or_absent`]).
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    outdir::no_link_inside(path)?;
    require_regular_or_absent(path)?;
    if outdir::fill(path, bytes)? == outdir::Fill::Same {
        return Ok(());
    }
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

/// Read a whole table or log as text ([`input::Kind::Text`]: a regular file within its limit),
/// naming it on failure (a UTF-16 or binary file: [`utf8_text`]).
pub(crate) fn read_text(path: &Path) -> Result<String> {
    read_text_of(path, input::Kind::Text)
}

/// Read a whole input of `kind` as UTF-8 text ([`input::read`], [`utf8_text`]).
pub(crate) fn read_text_of(path: &Path, kind: input::Kind) -> Result<String> {
    let bytes = input::read(path, kind)?;
    utf8_text(&path.display().to_string(), bytes).map_err(anyhow::Error::msg)
}

/// The text of the gzip-compressed file `path`, whole: decompressed, it is bounded like any text
/// input (at most `ratio` times the file's size, a small file can hold a huge text), and a truncated
/// or corrupt stream is an error saying it is `not a whole gzip-compressed {what}`.
pub(crate) fn gunzip_text(path: &Path, ratio: u64, what: &str) -> Result<String> {
    use input::{InputError, Kind};
    let (file, size) = input::open(path, Kind::Text)?;
    let decoder = flate2::read::GzDecoder::new(std::io::BufReader::new(file));
    let bytes = input::read_bounded(path, decoder, size.saturating_mul(ratio), Kind::Text)
        .map_err(|e| match e {
            InputError::Io { .. } => anyhow::Error::from(e)
                .context(format!("{}: not a whole gzip-compressed {what}", path.display())),
            e => e.into(),
        })?;
    utf8_text(&path.display().to_string(), bytes).map_err(anyhow::Error::msg)
}

/// An error chain as one printable line: line breaks become spaces and every other control
/// character its escape (`\0`, `\u{1b}`), so no input echoed into a message can break the line or
/// drive the terminal.
pub(crate) fn one_line(msg: &str) -> String {
    msg.chars()
        .map(|c| match c {
            '\n' | '\r' => " ".to_string(),
            c if c.is_control() => c.escape_debug().to_string(),
            c => c.to_string(),
        })
        .collect()
}

/// Refuse UTF-16 text (a byte-order mark FF FE or FE FF) and bytes with NUL in them, naming
/// `shown`: what a parser would otherwise echo into a message.
pub(crate) fn not_utf16(shown: &str, bytes: &[u8]) -> std::result::Result<(), String> {
    if bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]) || bytes.contains(&0) {
        return Err(format!("{shown}: UTF-16 text (or binary with NUL bytes); save it as UTF-8"));
    }
    Ok(())
}

/// A file's bytes as UTF-8 text, or a one-line error naming `shown`: UTF-16 (a byte-order mark
/// FF FE or FE FF) and NUL bytes are named as such, so no NUL byte reaches a parser's message.
pub(crate) fn utf8_text(shown: &str, bytes: Vec<u8>) -> std::result::Result<String, String> {
    not_utf16(shown, &bytes)?;
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "{shown}: not UTF-8 text (byte {} is not part of a UTF-8 character); save it as UTF-8",
            e.utf8_error().valid_up_to() + 1
        )
    })
}

/// A TOML parse error on one line, `path:line:col: message` (toml's own Display spans several
/// lines with a snippet of the file).
pub(crate) fn toml_message(path: &str, text: &str, e: &toml::de::Error) -> String {
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
pub(crate) fn read_toml<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let text = read_text_of(path, input::Kind::Toml)?;
    toml::from_str(&text)
        .map_err(|e| anyhow::Error::msg(toml_message(&path.display().to_string(), &text, &e)))
}

/// Typed rows of a CSV file (extra columns ignored); errors name the file and line.
pub(crate) fn read_rows<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
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
pub(crate) fn csv_text<T: serde::Serialize>(rows: &[T]) -> Result<String> {
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

/// CSV text of typed rows as [`csv_text`] writes them, and with no rows the header alone (the
/// field names of `T::default()`), so that an empty table still names its columns.
pub(crate) fn csv_table<T: serde::Serialize + Default>(rows: &[T]) -> Result<String> {
    if !rows.is_empty() {
        return csv_text(rows);
    }
    let one = csv_text(&[T::default()])?;
    Ok(one.lines().next().map(|h| format!("{h}\n")).unwrap_or_default())
}

/// CSV text from a header and string records, with no negative zero.
pub(crate) fn csv_records(header: &[String], rows: &[Vec<String>]) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header)?;
    for r in rows {
        w.write_record(r.iter().map(|f| no_negative_zero(f)))?;
    }
    Ok(String::from_utf8(w.into_inner().map_err(|e| e.into_error())?)?)
}

/// A path as messages and reports show it: `.` and `dir/..` dropped (lexically; the path opened
/// is unchanged), and relative to the working folder when it lies inside it.
pub(crate) fn shown(path: &Path) -> String {
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
        assert_eq!(shown(Path::new("../elsewhere/data")), "../elsewhere/data");
        assert_eq!(shown(Path::new("a/..")), ".");
        let cwd = std::env::current_dir().unwrap();
        assert_eq!(shown(&cwd.join("results/x")), "results/x");
        assert_eq!(shown(Path::new("/nonexistent/x/../y")), "/nonexistent/y");
    }

    #[test]
    fn messages_stay_one_printable_line_and_utf16_is_named() {
        assert_eq!(one_line("a\nb\r\0c\u{1b}[2Jd\tq"), "a b \\0c\\u{1b}[2Jd\\tq");
        assert_eq!(one_line("plain é ✓"), "plain é ✓");
        for bytes in [&[0xFF, 0xFE, b'n', 0][..], &[0xFE, 0xFF, 0, b'n'], b"n\0a\0m\0e\0"] {
            let e = utf8_text("f.toml", bytes.to_vec()).unwrap_err();
            assert_eq!(e, "f.toml: UTF-16 text (or binary with NUL bytes); save it as UTF-8");
        }
        assert!(utf8_text("f", b"ok \xC3\xA9".to_vec()).is_ok());
        assert!(utf8_text("f", b"ok\n\xE9t\xE9".to_vec()).unwrap_err().contains("byte 4 "));
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
