//! A DNSOM map file, as Chapter 4 saves it and Chapters 5 and 6 and `somnurbs fit` read it: the
//! two-view grid as CSV, and the data set's frame beside it (`X.frame.toml` beside `X.csv`).

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
