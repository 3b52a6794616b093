//! XYZ / CSV point files: three numeric columns separated by white space, commas or semicolons;
//! blank lines and `#` comments are skipped, one leading non-numeric header line is allowed, and
//! columns after the third are ignored (the loader says so once per file).

use super::DataError;
use crate::geom::Point3;

pub fn parse_xyz(text: &str) -> Result<Vec<Point3>, DataError> {
    parse_xyz_columns(text).map(|(points, _)| points)
}

/// [`parse_xyz`], and the most columns after the third on any data line (normals `nx ny nz`: 3),
/// which are ignored; the caller says so once per file.
pub fn parse_xyz_columns(text: &str) -> Result<(Vec<Point3>, usize), DataError> {
    let mut out = Vec::new();
    let mut extra = 0;
    let mut seen_data = false;
    let mut header_used = false;
    for (n, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line
            .split(|c: char| c.is_whitespace() || c == ',' || c == ';')
            .filter(|f| !f.is_empty())
            .collect();
        let nums: Vec<Option<f64>> = fields.iter().take(3).map(|f| f.parse::<f64>().ok()).collect();
        if !seen_data && !header_used && nums.iter().all(|v| v.is_none()) {
            header_used = true;
            continue;
        }
        if fields.len() < 3 {
            return Err(DataError::parse(
                format!("line {}", n + 1),
                format!("needs three numbers, got `{line}`"),
            ));
        }
        let mut p = [0.0; 3];
        for k in 0..3 {
            p[k] = nums[k].ok_or_else(|| {
                DataError::parse(
                    format!("line {}", n + 1),
                    format!("`{}` is not a number", fields[k]),
                )
            })?;
        }
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            if let Some(why) = super::coordinate_problem(axis, p[a]) {
                return Err(DataError::parse(format!("line {}", n + 1), why));
            }
        }
        seen_data = true;
        extra = extra.max(fields.len() - 3);
        out.push(p);
    }
    Ok((out, extra))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_comments_separators() {
        let t = "x,y,z\n# a comment\n1,2,3\n\n4 5 6 7\n7;8;9 # trailing\n";
        assert_eq!(parse_xyz(t).unwrap(), vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]]);
        assert_eq!(parse_xyz_columns(t).unwrap().1, 1);
        let normals = "x y z nx ny nz\n0 0 0 0 0 1\n1 0 0 0 0 1\n";
        assert_eq!(parse_xyz_columns(normals).unwrap(), (vec![[0.0; 3], [1.0, 0.0, 0.0]], 3));
        assert_eq!(parse_xyz_columns("1 2 3\n").unwrap().1, 0);
    }

    #[test]
    fn bad_line_is_named() {
        let e = parse_xyz("1 2 3\n4 five 6\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("five"), "{e}");
        let e = parse_xyz("1 2 3\n4 5\n").unwrap_err().to_string();
        assert!(e.contains("line 2"), "{e}");
        // Non-finite coordinates and coordinates beyond 1e15 are refused naming their line.
        let e = parse_xyz("1 2 3\nnan 1 2\n").unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("non-finite x"), "{e}");
        let e = parse_xyz("1 2 3\n0 0 1e300\n").unwrap_err().to_string();
        assert!(
            e.contains("line 2") && e.contains("z = 1e300, beyond the limit |z| <= 1e15"),
            "{e}"
        );
        assert!(parse_xyz("0 0 -1e15\n").is_ok());
    }
}
