//! The structured two-view grid CSV that Chapter 4 saves and Chapter 5 and `somnurbs fit` read:
//! columns i, j, view, class, x, y, z; one row per position of both views (2 nx ny rows).

use super::DataError;
use crate::double_net::TwoViewGrid;
use crate::geom::Point3;

/// Parse the grid CSV (sizes from the largest i and j; every position of both views exactly once).
pub(crate) fn parse_two_view_grid(text: &str) -> Result<TwoViewGrid, DataError> {
    let mut r = csv::ReaderBuilder::new().trim(csv::Trim::All).from_reader(text.as_bytes());
    let header: Vec<String> = r
        .headers()
        .map_err(|e| DataError::parse("line 1", e.to_string()))?
        .iter()
        .map(|s| s.to_string())
        .collect();
    let col = |name: &str| {
        header.iter().position(|h| h == name).ok_or_else(|| {
            DataError::parse(
                "line 1",
                format!("no `{name}` column (expected i,j,view,class,x,y,z)"),
            )
        })
    };
    let (ci, cj, cv, cx, cy, cz) =
        (col("i")?, col("j")?, col("view")?, col("x")?, col("y")?, col("z")?);
    let mut rows = Vec::new();
    for (n, rec) in r.records().enumerate() {
        let line = n + 2;
        let rec = rec.map_err(|e| DataError::parse(format!("line {line}"), e.to_string()))?;
        let field = |c: usize| rec.get(c).unwrap_or("");
        let int = |c: usize| {
            field(c).parse::<usize>().map_err(|_| {
                DataError::parse(format!("line {line}"), format!("`{}` is not an index", field(c)))
            })
        };
        let num = |c: usize| -> Result<f64, DataError> {
            let v: f64 = field(c).parse().map_err(|_| {
                DataError::parse(format!("line {line}"), format!("`{}` is not a number", field(c)))
            })?;
            if !v.is_finite() {
                Err(DataError::parse(
                    format!("line {line}"),
                    format!("non-finite coordinate `{}`", field(c)),
                ))
            } else if let Some(why) = super::coordinate_problem("coordinate", v) {
                Err(DataError::parse(format!("line {line}"), why))
            } else {
                Ok(v)
            }
        };
        let top = match field(cv) {
            "bottom" => false,
            "top" => true,
            other => {
                return Err(DataError::parse(
                    format!("line {line}"),
                    format!("view must be bottom or top, got `{other}`"),
                ))
            }
        };
        rows.push((int(ci)?, int(cj)?, top, [num(cx)?, num(cy)?, num(cz)?], line));
    }
    if rows.is_empty() {
        return Err(DataError::Invalid("the grid has no rows".into()));
    }
    let nx = rows.iter().map(|r| r.0).max().unwrap_or(0) + 1;
    let ny = rows.iter().map(|r| r.1).max().unwrap_or(0) + 1;
    if nx < 2 || ny < 2 {
        return Err(DataError::Invalid(format!(
            "the grid is {nx}x{ny}; both sides must be at least 2"
        )));
    }
    if rows.len() != 2 * nx * ny {
        return Err(DataError::Invalid(format!(
            "a {nx}x{ny} two-view grid needs {} rows (both views), found {}",
            2 * nx * ny,
            rows.len()
        )));
    }
    let mut bottom = vec![None; nx * ny];
    let mut top = vec![None; nx * ny];
    for (i, j, is_top, p, line) in rows {
        let slot = if is_top { &mut top[i * ny + j] } else { &mut bottom[i * ny + j] };
        if slot.is_some() {
            return Err(DataError::parse(
                format!("line {line}"),
                format!(
                    "position ({i}, {j}) of the {} view appears twice",
                    if is_top { "top" } else { "bottom" }
                ),
            ));
        }
        *slot = Some(p);
    }
    let bottom: Vec<Point3> = bottom
        .into_iter()
        .map(|p| p.expect("every position filled: counts match and no duplicates"))
        .collect();
    let top: Vec<Point3> = top.into_iter().map(|p| p.expect("every position filled")).collect();
    if bottom.iter().chain(&top).all(|p| *p == bottom[0]) {
        return Err(DataError::Invalid(format!(
            "all {} points of the grid are the same point (its bounding box has zero diagonal): \
             nothing to fit",
            2 * nx * ny
        )));
    }
    Ok(TwoViewGrid { nx, ny, bottom, top })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn csv(nx: usize, ny: usize) -> String {
        let mut s = String::from("i,j,view,class,x,y,z\n");
        for view in ["bottom", "top"] {
            for i in 0..nx {
                for j in 0..ny {
                    s.push_str(&format!(
                        "{i},{j},{view},0,{i},{j},{}\n",
                        if view == "top" { 1 } else { 0 }
                    ));
                }
            }
        }
        s
    }

    #[test]
    fn round_trip_and_errors() {
        let g = parse_two_view_grid(&csv(3, 4)).unwrap();
        assert_eq!((g.nx, g.ny), (3, 4));
        assert_eq!(g.top[2 * 4 + 3], [2.0, 3.0, 1.0]);
        let missing = csv(3, 4).lines().take(20).collect::<Vec<_>>().join("\n");
        assert!(parse_two_view_grid(&missing).unwrap_err().to_string().contains("needs 24 rows"));
        let nan = csv(3, 4).replace("1,2,bottom,0,1,2,0", "1,2,bottom,0,1,NaN,0");
        let e = parse_two_view_grid(&nan).unwrap_err().to_string();
        assert!(e.contains("line 8") && e.contains("NaN"), "{e}");
        let huge = csv(3, 4).replace("1,2,bottom,0,1,2,0", "1,2,bottom,0,1,-1e300,0");
        let e = parse_two_view_grid(&huge).unwrap_err().to_string();
        assert!(e.contains("line 8") && e.contains("beyond the limit"), "{e}");
        let g = csv(3, 4);
        let same: String = g
            .lines()
            .enumerate()
            .map(|(k, l)| {
                if k == 0 {
                    l.to_string()
                } else {
                    let f: Vec<&str> = l.split(',').collect();
                    format!("{},{},{},{},5,5,5", f[0], f[1], f[2], f[3])
                }
            })
            .collect::<Vec<_>>()
            .join("\n");
        let e = parse_two_view_grid(&same).unwrap_err().to_string();
        assert!(e.contains("all 24 points of the grid are the same point"), "{e}");
    }
}
