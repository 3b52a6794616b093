//! `somnurbs fit`: fit a user's two-view grid and write its control nets, IGES and OBJ.

use crate::cli::FitArgs;
use crate::experiment::spec::GridSize;
use crate::report::fsio::{csv_records, read_text, write_atomic};
use crate::spline::{export, fit_two_view, Approach, Parameterisation};
use anyhow::{Context, Result};

pub fn fit(args: &FitArgs) -> Result<()> {
    let cn: GridSize = args.cn.parse().map_err(|e| anyhow::anyhow!("--cn: {e}"))?;
    let param: Parameterisation = args.param.parse().map_err(|e| anyhow::anyhow!("--param: {e}"))?;
    let approach: Approach = args.approach.parse().map_err(|e| anyhow::anyhow!("--approach: {e}"))?;
    let shown = args.grid.display().to_string();
    let text = read_text(&args.grid)?;
    let grid = crate::data::grid_csv::parse_two_view_grid(&text).with_context(|| shown.clone())?;
    let fit = fit_two_view(&grid, cn.nx, cn.ny, param, approach).with_context(|| format!("{shown}: {}x{} grid", grid.nx, grid.ny))?;

    let header: Vec<String> = ["view", "a", "b", "x", "y", "z"].iter().map(|s| s.to_string()).collect();
    let mut rows = Vec::new();
    for (view, s) in [("bottom", &fit.bottom), ("top", &fit.top)] {
        for a in 0..s.cn_x {
            for b in 0..s.cn_y {
                let p = s.control[a * s.cn_y + b];
                rows.push(vec![view.to_string(), a.to_string(), b.to_string(), format!("{:?}", p[0]), format!("{:?}", p[1]), format!("{:?}", p[2])]);
            }
        }
    }
    let out = &args.out;
    write_atomic(&out.join("control_nets.csv"), csv_records(&header, &rows)?.as_bytes())?;
    let surfaces = [("bottom", &fit.bottom), ("top", &fit.top)];
    write_atomic(&out.join("surfaces.igs"), export::write_iges(&surfaces, true).as_bytes())?;
    write_atomic(&out.join("surfaces.obj"), export::write_obj(&surfaces, args.samples, args.samples).as_bytes())?;
    let summary: Vec<String> = ["grid", "cn", "parameterisation", "approach", "surface_error", "gap"].iter().map(|s| s.to_string()).collect();
    let row = vec![format!("{}x{}", grid.nx, grid.ny), cn.to_string(), param.name().into(), approach.letter().into(), format!("{:?}", fit.surface_error), format!("{:?}", fit.gap)];
    write_atomic(&out.join("fit.csv"), csv_records(&summary, &[row])?.as_bytes())?;
    println!("surface error {:.6}, gap {:.3e}; wrote control_nets.csv, surfaces.igs, surfaces.obj, fit.csv in {}", fit.surface_error, fit.gap, out.display());
    Ok(())
}
