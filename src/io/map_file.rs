//! A DNSOM map file, as Chapter 4 saves it and Chapters 5 and 6 and `somnurbs fit` read it: the
//! two-view grid as CSV, and the data set's frame beside it (`X.frame.toml` beside `X.csv`); a
//! folder that read a map keeps it gzip-compressed (`X.csv.gz`, the same frame file beside it).

use super::{csv_records, write_atomic};
use crate::data::frame::Frame;
use crate::double_net::{DoubleNet, TwoViewGrid, View};
use anyhow::Result;
use std::path::Path;

/// A two-view grid as CSV: i, j, view, class (1-based class number), x, y, z; one row per
/// position of both views (NON rows), bottom view first. Chapter 5 and `somnurbs fit` read it back.
pub(crate) fn text(grid: &TwoViewGrid) -> Result<String> {
    let net = DoubleNet::new(grid.nx, grid.ny)
        .ok_or_else(|| anyhow::anyhow!("grid {}x{} is too small", grid.nx, grid.ny))?;
    let mut rows = Vec::with_capacity(net.non());
    for view in View::BOTH {
        let points = match view {
            View::Bottom => &grid.bottom,
            View::Top => &grid.top,
        };
        for i in 0..net.nx {
            for j in 0..net.ny {
                let w = points[net.at(i, j)];
                rows.push(vec![
                    i.to_string(),
                    j.to_string(),
                    view.name().to_string(),
                    (net.class(view, i, j) + 1).to_string(),
                    format!("{:?}", w[0]),
                    format!("{:?}", w[1]),
                    format!("{:?}", w[2]),
                ]);
            }
        }
    }
    let header: Vec<String> =
        ["i", "j", "view", "class", "x", "y", "z"].iter().map(|s| s.to_string()).collect();
    csv_records(&header, &rows)
}

/// `bytes` gzip-compressed, the same bytes on every run (no name or time in the header): how a
/// folder keeps a copy of a map it read (`X.csv.gz`).
pub(crate) fn gzip(bytes: &[u8]) -> Result<Vec<u8>> {
    use std::io::Write as _;
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    enc.write_all(bytes)?;
    Ok(enc.finish()?)
}

/// The text of a map file: the CSV, or its gzip-compressed copy (`X.csv.gz`), bounded like any
/// table once decompressed.
pub(crate) fn read(path: &Path) -> Result<String> {
    if path.extension().is_none_or(|e| e != "gz") {
        return super::read_text(path);
    }
    super::gunzip_text(path, 16, "map")
}

/// Write `frame` beside the map file `map` ([`crate::data::frame::sidecar`]).
pub(crate) fn write_frame(map: &Path, frame: &Frame) -> Result<()> {
    let name = map.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let text = frame.to_toml(&name)?;
    write_atomic(&crate::data::frame::sidecar(map), text.as_bytes())
}

/// The frame saved beside a map (`X.frame.toml` beside `X.csv`), None when there is none; a frame
/// file that is there but cannot be read is an error naming it.
pub(crate) fn read_frame(map: &Path) -> Result<Option<Frame>> {
    let file = crate::data::frame::sidecar(map);
    if !file.exists() {
        return Ok(None);
    }
    let text = super::read_text(&file)?;
    let frame = Frame::parse(&text).map_err(|e| e.in_file(&super::shown(&file)))?;
    Ok(Some(frame))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder's compressed copy of a map reads back as the map's exact text, and compressing
    /// is the same bytes every time (so `somnurbs report` finds the copy it would write).
    #[test]
    fn a_compressed_copy_reads_back_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let points: Vec<[f64; 3]> =
            (0..18).map(|k| [k as f64 / 7.0, 0.1 * k as f64, -1.0 / (k as f64 + 3.0)]).collect();
        let grid =
            TwoViewGrid { nx: 3, ny: 3, bottom: points[..9].to_vec(), top: points[9..].to_vec() };
        let csv = text(&grid).unwrap();
        let copy = dir.path().join("dnsom_a_3x3.csv.gz");
        std::fs::write(&copy, gzip(csv.as_bytes()).unwrap()).unwrap();
        assert_eq!(read(&copy).unwrap(), csv);
        assert_eq!(gzip(csv.as_bytes()).unwrap(), std::fs::read(&copy).unwrap());
        assert!(std::fs::metadata(&copy).unwrap().len() < csv.len() as u64);
        std::fs::write(&copy, &gzip(csv.as_bytes()).unwrap()[..20]).unwrap();
        let e = read(&copy).unwrap_err().to_string();
        assert!(e.contains("not a whole gzip-compressed map"), "{e}");
    }
}
