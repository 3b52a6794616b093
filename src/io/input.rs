//! Every file somnurbs reads comes through here: it must be a regular file (a named pipe would
//! block the reader forever, a device such as `/dev/zero` never ends, a folder is no file), and it
//! must fit its kind's size limit, checked before a byte is read, and again while reading (a file
//! that grows under the reader). The limits are in docs/specs.md ("Input limits"); the
//! environment variable [`LIMIT_VAR`] raises every one of them.

use std::fs::{File, OpenOptions};
use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::Path;

/// The environment variable that raises every input limit to its value in MiB (never lowers one).
pub(crate) const LIMIT_VAR: &str = "SOMNURBS_MAX_INPUT_MIB";

/// What an input is, for its size limit and its messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// A TOML file: spec, plan, frame, manifest, fingerprint, lock record (4 MiB).
    Toml,
    /// A text table or log: CSV, map, IOHprofiler `.json`/`.dat`, REPORT.md, a decompressed cell
    /// log (512 MiB).
    Text,
    /// A point cloud or mesh: PLY, STL, OFF, OBJ, XYZ, CSV points (2 GiB).
    Data,
}

impl Kind {
    fn default_limit(self) -> u64 {
        match self {
            Kind::Toml => 4 << 20,
            Kind::Text => 512 << 20,
            Kind::Data => 2 << 30,
        }
    }

    fn noun(self) -> &'static str {
        match self {
            Kind::Toml => "a TOML file",
            Kind::Text => "a table or log",
            Kind::Data => "a data file",
        }
    }

    /// The limit in force: the default, or [`LIMIT_VAR`] where that is larger.
    pub(crate) fn limit(self) -> u64 {
        let raised = std::env::var(LIMIT_VAR)
            .ok()
            .and_then(|v| v.trim().parse::<u64>().ok())
            .and_then(|mib| mib.checked_mul(1 << 20));
        self.default_limit().max(raised.unwrap_or(0))
    }
}

/// Why an input was not read.
#[derive(Debug, thiserror::Error)]
pub(crate) enum InputError {
    #[error("{path}: no such file")]
    NotFound { path: String },
    #[error("{path} is {what}, not a regular file; somnurbs reads only regular files")]
    NotRegular { path: String, what: &'static str },
    #[error("{path}: {size} bytes, over the limit of {limit} bytes for {noun} (set {LIMIT_VAR}=N to read up to N MiB)")]
    TooLarge { path: String, size: u64, limit: u64, noun: &'static str },
    #[error("cannot read {path}: {source}")]
    Io { path: String, source: std::io::Error },
}

impl InputError {
    fn io(path: &Path, source: std::io::Error) -> InputError {
        if source.kind() == std::io::ErrorKind::NotFound {
            return InputError::NotFound { path: path.display().to_string() };
        }
        InputError::Io { path: path.display().to_string(), source }
    }
}

/// What a file type is, in words (for a refusal).
pub(crate) fn kind_of(ty: std::fs::FileType) -> &'static str {
    if ty.is_dir() {
        "a folder"
    } else if ty.is_symlink() {
        "a symbolic link"
    } else if ty.is_char_device() || ty.is_block_device() {
        "a device"
    } else if ty.is_fifo() {
        "a FIFO (named pipe)"
    } else if ty.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

fn not_regular(path: &Path, ty: std::fs::FileType) -> InputError {
    InputError::NotRegular { path: path.display().to_string(), what: kind_of(ty) }
}

/// Whether `path` could be read as an input of `kind` (a regular file within the limit), without
/// opening it: for checks before a run writes anything.
pub(crate) fn check(path: &Path, kind: Kind) -> Result<(), InputError> {
    let meta = std::fs::metadata(path).map_err(|e| InputError::io(path, e))?;
    if !meta.is_file() {
        return Err(not_regular(path, meta.file_type()));
    }
    check_size(path, meta.len(), kind)
}

/// Open `path` for reading if it is a regular file within `kind`'s limit; returns the file and
/// its size. The type is checked before opening (so a pipe is never opened) and again on the
/// open file (a swap in between is caught); the open never blocks (`O_NONBLOCK`).
pub(crate) fn open(path: &Path, kind: Kind) -> Result<(File, u64), InputError> {
    check(path, kind)?;
    let file = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| InputError::io(path, e))?;
    let meta = file.metadata().map_err(|e| InputError::io(path, e))?;
    if !meta.is_file() {
        return Err(not_regular(path, meta.file_type()));
    }
    check_size(path, meta.len(), kind)?;
    Ok((file, meta.len()))
}

fn check_size(path: &Path, size: u64, kind: Kind) -> Result<(), InputError> {
    let limit = kind.limit();
    if size > limit {
        return Err(InputError::TooLarge {
            path: path.display().to_string(),
            size,
            limit,
            noun: kind.noun(),
        });
    }
    Ok(())
}

/// The bytes of the regular file `path`, at most `kind`'s limit ([`open`]).
pub(crate) fn read(path: &Path, kind: Kind) -> Result<Vec<u8>, InputError> {
    let (file, size) = open(path, kind)?;
    read_bounded(path, file, size, kind)
}

/// Everything `reader` gives, refused past `kind`'s limit (`path` names it); `hint` sizes the
/// first allocation (capped by the limit).
pub(crate) fn read_bounded(
    path: &Path,
    reader: impl Read,
    hint: u64,
    kind: Kind,
) -> Result<Vec<u8>, InputError> {
    let limit = kind.limit();
    let mut bytes = Vec::with_capacity(hint.min(limit).min(64 << 20) as usize);
    reader
        .take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| InputError::io(path, e))?;
    check_size(path, bytes.len() as u64, kind)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pipes_devices_and_folders_are_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe.dat");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        for (p, what) in [
            (fifo.as_path(), "named pipe"),
            (Path::new("/dev/zero"), "a device"),
            (dir.path(), "a folder"),
        ] {
            let e = read(p, Kind::Text).unwrap_err().to_string();
            assert!(e.contains(what) && e.contains("not a regular file"), "{e}");
        }
        let e = read(&dir.path().join("none.csv"), Kind::Text).unwrap_err();
        assert!(matches!(e, InputError::NotFound { .. }), "{e}");
    }

    #[test]
    fn sizes_over_the_limit_are_refused_naming_it_and_the_variable() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big.toml");
        std::fs::write(&p, vec![b'#'; (4 << 20) + 1]).unwrap();
        let e = read(&p, Kind::Toml).unwrap_err().to_string();
        assert!(
            e.contains("4194305 bytes") && e.contains("4194304") && e.contains(LIMIT_VAR),
            "{e}"
        );
        std::fs::write(&p, "a = 1\n").unwrap();
        assert_eq!(read(&p, Kind::Toml).unwrap(), b"a = 1\n");
        // A stream longer than the limit stops one byte past it.
        let e = read_bounded(&p, std::io::repeat(b'x'), 0, Kind::Toml).unwrap_err().to_string();
        assert!(e.contains("4194305 bytes"), "{e}");
    }
}
