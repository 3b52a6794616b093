//! `somnurbs datasets`: list, describe and export data sets.

use crate::data::registry;
use anyhow::Result;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// What `somnurbs datasets` is asked to do (the command line's `DatasetsAction`).
#[derive(Debug, Clone)]
pub(crate) enum Action {
    /// List the built-in data sets.
    List,
    /// Load one data set and print its size and bounds.
    Show { name: String },
    /// Write a data set's normalised points to `file` (.csv, else XYZ).
    Export { name: String, file: PathBuf },
}

pub(crate) fn datasets(action: Action, data_dir: &Path) -> Result<()> {
    match action {
        Action::List => {
            for name in registry::BUILTIN {
                println!("{name:<12} {}", registry::describe(name).unwrap_or(""));
            }
            println!("\nAny .ply/.stl/.off/.obj/.xyz/.csv/.txt path is accepted as a data set too. Data directory: {}", data_dir.display());
        }
        Action::Show { name } => {
            let cloud = registry::load_dataset(&name, data_dir)?;
            let (lo, hi) = crate::geom::bounding_box(&cloud.points).unwrap_or(([0.0; 3], [0.0; 3]));
            println!(
                "{}: {} points (normalised per axis to [0,1])",
                cloud.name,
                cloud.points.len()
            );
            println!(
                "bounds x [{:.6}, {:.6}] y [{:.6}, {:.6}] z [{:.6}, {:.6}]",
                lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]
            );
            for p in cloud.points.iter().take(5) {
                println!("  {:.6} {:.6} {:.6}", p[0], p[1], p[2]);
            }
        }
        Action::Export { name, file } => {
            let cloud = registry::load_dataset(&name, data_dir)?;
            let csv = file.extension().map(|e| e.eq_ignore_ascii_case("csv")).unwrap_or(false);
            let mut text = String::new();
            if csv {
                text.push_str("x,y,z\n");
            }
            for p in &cloud.points {
                if csv {
                    let _ = writeln!(text, "{:?},{:?},{:?}", p[0], p[1], p[2]);
                } else {
                    let _ = writeln!(text, "{:?} {:?} {:?}", p[0], p[1], p[2]);
                }
            }
            // A result folder holds one run and nothing else; the file is written atomically,
            // and only over a regular file.
            crate::io::outdir::require_outside_results(&file, "datasets export NAME FILE")?;
            crate::io::write_atomic(&file, text.as_bytes())?;
            crate::notice::emit(&format!(
                "somnurbs: wrote {} points to {}",
                cloud.points.len(),
                file.display()
            ));
        }
    }
    Ok(())
}
