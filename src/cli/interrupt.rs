//! Ctrl-C during `run` and `reproduce`: one line on stderr with the command that continues the
//! run, and exit status 130. The run's files are safe against a kill at any moment (atomic
//! writes, the cell log, `--resume`), so the handler cleans nothing up: it writes the line
//! prepared before the run started and exits, both async-signal-safe calls.

use std::sync::atomic::{AtomicPtr, AtomicUsize, Ordering};

/// The line the handler writes (leaked once per process: a run installs it once).
static LINE: AtomicPtr<u8> = AtomicPtr::new(std::ptr::null_mut());
static LINE_LEN: AtomicUsize = AtomicUsize::new(0);

/// The stderr line for an interrupted run that `resume` (a whole command line) continues.
pub(crate) fn line(resume: &str) -> String {
    format!("somnurbs: interrupted; continue with: {resume}\n")
}

/// A word of a command line as a POSIX shell reads it back (quoted when it holds anything but
/// letters, digits and `-_./=,:@+`).
pub(crate) fn quote(word: &str) -> String {
    let plain = !word.is_empty()
        && word.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=,:@+".contains(c));
    if plain {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

/// Install the SIGINT handler that writes `line(resume)` and exits 130.
pub(crate) fn on_sigint(resume: &str) {
    let bytes: &'static mut [u8] = Box::leak(line(resume).into_bytes().into_boxed_slice());
    LINE_LEN.store(bytes.len(), Ordering::SeqCst);
    LINE.store(bytes.as_mut_ptr(), Ordering::SeqCst);
    install();
}

#[cfg(unix)]
extern "C" fn handler(_signal: libc::c_int) {
    let (ptr, len) = (LINE.load(Ordering::SeqCst), LINE_LEN.load(Ordering::SeqCst));
    // SAFETY: write(2) and _exit(2) are async-signal-safe; `ptr` is null or points at `len`
    // leaked bytes that are never freed.
    unsafe {
        if !ptr.is_null() {
            libc::write(libc::STDERR_FILENO, ptr as *const libc::c_void, len);
        }
        libc::_exit(130);
    }
}

#[cfg(unix)]
fn install() {
    // SAFETY: a zeroed sigaction is a valid value (no flags, empty mask set below); the handler
    // only makes async-signal-safe calls.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = handler as extern "C" fn(libc::c_int) as libc::sighandler_t;
        libc::sigemptyset(&mut action.sa_mask);
        libc::sigaction(libc::SIGINT, &action, std::ptr::null_mut());
    }
}

#[cfg(not(unix))]
fn install() {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resume_lines_quote_what_a_shell_would_split() {
        assert_eq!(quote("results/ch6_same"), "results/ch6_same");
        assert_eq!(quote("my scans/o'k"), r"'my scans/o'\''k'");
        assert_eq!(quote(""), "''");
        assert_eq!(
            line("somnurbs run a.toml --out o --resume"),
            "somnurbs: interrupted; continue with: somnurbs run a.toml --out o --resume\n"
        );
    }
}
