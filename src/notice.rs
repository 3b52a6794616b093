//! Where the library's notes and progress lines go: stderr for the CLI, or a sink the embedding
//! program installs (the Python package sends them to Python's `logging`, so that a caller can
//! silence or redirect them). One line per call, without the trailing newline.

use std::sync::RwLock;

/// A receiver of notice lines.
pub type Sink = Box<dyn Fn(&str) + Send + Sync>;

static SINK: RwLock<Option<Sink>> = RwLock::new(None);

/// Send every later notice to `sink` instead of stderr (`None`: back to stderr).
pub fn set_sink(sink: Option<Sink>) {
    *SINK.write().unwrap_or_else(|e| e.into_inner()) = sink;
}

/// Whether a sink is installed (then the runner prints plain progress lines, never a bar).
pub(crate) fn redirected() -> bool {
    SINK.read().map(|s| s.is_some()).unwrap_or(false)
}

/// Emit one notice line.
pub(crate) fn emit(line: &str) {
    match SINK.read() {
        Ok(guard) => match guard.as_ref() {
            Some(sink) => sink(line),
            None => eprintln!("{line}"),
        },
        Err(_) => eprintln!("{line}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    #[test]
    fn a_sink_receives_every_line_and_none_restores_stderr() {
        let got = Arc::new(Mutex::new(Vec::new()));
        let g = got.clone();
        set_sink(Some(Box::new(move |l| g.lock().unwrap().push(l.to_string()))));
        assert!(redirected());
        emit("one");
        emit("two");
        set_sink(None);
        assert!(!redirected());
        emit("to stderr");
        assert_eq!(*got.lock().unwrap(), ["one", "two"]);
    }
}
