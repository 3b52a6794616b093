//! The report's PNG side: one chart per file, each a function of (output path, data), as in
//! criterion's `plot/plotters_backend/`.
//!
//! Why this shape: a report run draws dozens of charts from finished results; one bad chart
//! (an empty group, a NaN in a trace, a folder that vanished) must come back as an error naming
//! its file so the caller can log it and go on, never as a panic or a half-written PNG. Hence
//! every file is rendered under a temporary name in the target folder and renamed into place
//! ([`render_png`]), non-finite values are dropped before they reach plotters, and axis ranges
//! are padded and labelled by [`scale`] so near-constant data (fitness values agreeing to seven
//! digits, as in the thesis' Appendices K-N) still gives a readable axis.
//!
//! Text uses DejaVu Sans embedded from the `dejavu` crate (no system fonts), registered once.

pub(crate) mod boxplot;
pub(crate) mod cd_diagram;
pub(crate) mod line_chart;
pub(crate) mod mesh3d;
pub(crate) mod overview;
mod palette;
pub(crate) mod scale;
pub(crate) mod style;

pub(crate) use boxplot::{box_plot_png, Level};
pub(crate) use cd_diagram::cd_diagram_png;
pub(crate) use line_chart::{line_chart_png, small_multiples_png, xy_chart_png, Series};
pub(crate) use mesh3d::{grid_edges, magnified_difference, mesh_png, LineMesh};
pub(crate) use overview::{overview_png, Panel};

use plotters::coord::Shift;
use plotters::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The largest width or height accepted for one picture (pixels).
pub(crate) const MAX_SIDE: u32 = 16_384;

/// A failure while drawing onto a drawing area (no file involved yet).
#[derive(Debug, Error)]
pub(crate) enum DrawError {
    /// plotters (or the bitmap backend) reported an error.
    #[error("drawing failed: {0}")]
    Backend(String),
    /// The DejaVu Sans font could not be registered with plotters.
    #[error("cannot register the DejaVu Sans font with plotters")]
    Font,
    /// The data cannot be drawn (explained in the message).
    #[error("{0}")]
    Input(String),
}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        DrawError::Backend(e.to_string())
    }
}

/// A chart that could not be written; every variant names the PNG it was meant for.
#[derive(Debug, Error)]
pub(crate) enum PlotError {
    /// The data or the requested picture cannot be drawn.
    #[error("chart {}: {reason}", path.display())]
    Input { path: PathBuf, reason: String },
    /// Rendering failed.
    #[error("chart {}: {source}", path.display())]
    Draw {
        path: PathBuf,
        #[source]
        source: DrawError,
    },
    /// The folder is missing or the file could not be moved into place.
    #[error("chart {}: {what}: {source}", path.display())]
    Io {
        path: PathBuf,
        what: &'static str,
        #[source]
        source: std::io::Error,
    },
}

impl PlotError {
    pub(crate) fn input(path: &Path, reason: impl Into<String>) -> Self {
        PlotError::Input { path: path.to_path_buf(), reason: reason.into() }
    }
}

/// Renders `draw` onto a white `size` bitmap and writes it atomically to `path` (a `.png` file in
/// an existing folder) as a palette PNG. No temporary file is left behind, whatever happens.
pub(crate) fn render_png<F>(path: &Path, size: (u32, u32), draw: F) -> Result<(), PlotError>
where
    F: FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), DrawError>,
{
    let (w, h) = size;
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Err(PlotError::input(
            path,
            format!("picture size {w}x{h} is outside 1..={MAX_SIDE} pixels per side"),
        ));
    }
    let is_png =
        path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !is_png {
        return Err(PlotError::input(path, "the file name must end in .png"));
    }
    // The temporary sibling every writer uses (`.NAME.PID.N.tmp`: a resumed run removes one a
    // kill left behind).
    let tmp = crate::io::outdir::temp_name(path, "tmp");
    crate::io::outdir::no_link_inside(path)
        .map_err(|e| PlotError::input(path, format!("{e:#}")))?;
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    match std::fs::metadata(folder) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(PlotError::Io {
                path: path.to_path_buf(),
                what: "the parent is not a folder",
                source: std::io::Error::new(
                    std::io::ErrorKind::NotADirectory,
                    folder.display().to_string(),
                ),
            })
        }
        Err(source) => {
            return Err(PlotError::Io {
                path: path.to_path_buf(),
                what: "the folder is not readable",
                source,
            })
        }
    }
    style::ensure_fonts().map_err(|source| PlotError::Draw { path: path.to_path_buf(), source })?;

    // Drawn into memory, then encoded as a palette PNG (`palette`) into the temporary file.
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    let outcome = catch_unwind(AssertUnwindSafe(|| -> Result<(), DrawError> {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
        Ok(())
    }));
    let drawn = match outcome {
        Ok(r) => r,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown cause".to_string());
            Err(DrawError::Backend(format!("plotters panicked: {msg}")))
        }
    };
    if let Err(source) = drawn {
        return Err(PlotError::Draw { path: path.to_path_buf(), source });
    }
    let bytes = palette::encode(&rgb, w, h).map_err(|e| PlotError::Draw {
        path: path.to_path_buf(),
        source: DrawError::Backend(format!("cannot encode the PNG: {e}")),
    })?;
    match crate::io::outdir::fill(path, &bytes) {
        Ok(crate::io::outdir::Fill::Same) => return Ok(()),
        Ok(crate::io::outdir::Fill::Write) => {}
        Err(e) => {
            return Err(PlotError::Draw {
                path: path.to_path_buf(),
                source: DrawError::Backend(format!("{e:#}")),
            })
        }
    }
    let written = std::fs::File::options()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .and_then(|mut f| std::io::Write::write_all(&mut f, &bytes));
    if let Err(source) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(PlotError::Io {
            path: path.to_path_buf(),
            what: "cannot write the rendered file",
            source,
        });
    }
    if let Err(source) = std::fs::rename(&tmp, path) {
        let _ = std::fs::remove_file(&tmp);
        return Err(PlotError::Io {
            path: path.to_path_buf(),
            what: "cannot move the rendered file into place",
            source,
        });
    }
    Ok(())
}

/// Test helpers shared by the chart modules: PNG signature and IHDR size, read from raw bytes.
#[cfg(test)]
pub(crate) mod testutil {
    use std::path::Path;

    pub(crate) const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a];

    /// (width, height) of a PNG file, checking the signature and that the first chunk is IHDR.
    pub(crate) fn png_size(path: &Path) -> (u32, u32) {
        let bytes = std::fs::read(path).expect("png readable");
        assert!(bytes.len() > 33, "png too short: {} bytes", bytes.len());
        assert_eq!(bytes[..8], PNG_SIGNATURE, "not a PNG signature");
        assert_eq!(&bytes[12..16], b"IHDR", "first chunk is not IHDR");
        let w = u32::from_be_bytes([bytes[16], bytes[17], bytes[18], bytes[19]]);
        let h = u32::from_be_bytes([bytes[20], bytes[21], bytes[22], bytes[23]]);
        (w, h)
    }

    /// Names of the files in `dir` (to check that no temporary file is left).
    pub(crate) fn listing(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .expect("dir readable")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// A path inside a folder that does not exist.
    pub(crate) fn missing_folder_path(dir: &Path) -> std::path::PathBuf {
        dir.join("no_such_folder").join("chart.png")
    }
}

#[cfg(test)]
mod tests {
    use super::testutil::*;
    use super::*;

    #[test]
    fn render_png_rejects_bad_sizes_and_extensions() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.png");
        let e = render_png(&p, (0, 10), |_| Ok(())).unwrap_err();
        assert!(e.to_string().contains("x.png"), "{e}");
        let q = dir.path().join("x.jpg");
        let e = render_png(&q, (10, 10), |_| Ok(())).unwrap_err();
        assert!(e.to_string().contains("x.jpg") && e.to_string().contains(".png"), "{e}");
        assert!(listing(dir.path()).is_empty());
    }

    #[test]
    fn failed_drawing_leaves_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("fail.png");
        let e = render_png(&p, (20, 20), |_| Err(DrawError::Input("boom".into()))).unwrap_err();
        assert!(e.to_string().contains("fail.png") && e.to_string().contains("boom"), "{e}");
        assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
    }

    #[test]
    fn panicking_drawing_becomes_an_error_and_leaves_no_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("panic.png");
        let e = render_png(&p, (20, 20), |_| panic!("deliberate")).unwrap_err();
        assert!(e.to_string().contains("panic.png") && e.to_string().contains("deliberate"), "{e}");
        assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
    }

    #[test]
    fn missing_folder_is_an_io_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = missing_folder_path(dir.path());
        let e = render_png(&p, (20, 20), |_| Ok(())).unwrap_err();
        assert!(matches!(e, PlotError::Io { .. }));
        assert!(e.to_string().contains(&p.display().to_string()), "{e}");
    }

    #[test]
    fn written_png_has_requested_size() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("blank.png");
        render_png(&p, (37, 23), |_| Ok(())).unwrap();
        assert_eq!(png_size(&p), (37, 23));
        assert_eq!(listing(dir.path()), vec!["blank.png".to_string()]);
    }
}
