//! A real scan nobody here made, start to finish: CGAL's `hippo1.ply` (binary little-endian PLY
//! with normals, 6,104 points, from Debian's `libcgal-demo`, which `scripts/install_cgal_demo.sh`
//! installs) is mapped by the optimise spec's own SOM, fitted, optimised, exported from the
//! record in the scan's own frame and re-rendered from the records.
//!
//! Without the package the test says so and passes, unless `SOMNURBS_REQUIRE_REAL_SCAN` is set
//! (CI sets it: there the test cannot be skipped).

use crate::common::*;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Where Debian's `libcgal-demo` puts CGAL's data (a link to libcgal-dev's doc folder).
const CGAL_DATA: &str = "/usr/share/doc/libcgal-dev/data.tar.gz";
/// The scan's member in that archive.
const HIPPO: &str = "data/points_3/hippo1.ply";

/// One member of a (gzipped) tar archive, read with the ustar header layout: name at 0..100,
/// size in octal at 124..136, type at 156, ustar prefix at 345..500; GNU long names ('L').
fn tar_member(archive: &Path, wanted: &str) -> Option<Vec<u8>> {
    let mut bytes = Vec::new();
    flate2::read::GzDecoder::new(std::fs::File::open(archive).ok()?)
        .read_to_end(&mut bytes)
        .ok()?;
    let text =
        |b: &[u8]| String::from_utf8_lossy(b.split(|&c| c == 0).next().unwrap()).into_owned();
    let (mut at, mut long) = (0, None::<String>);
    while at + 512 <= bytes.len() && bytes[at] != 0 {
        let h = &bytes[at..at + 512];
        let size = usize::from_str_radix(text(&h[124..136]).trim(), 8).ok()?;
        let body = at + 512;
        let end = body.checked_add(size)?;
        let data = bytes.get(body..end)?;
        match h[156] {
            b'L' => long = Some(text(data)),
            _ => {
                let name = long.take().unwrap_or_else(|| {
                    let (prefix, name) = (text(&h[345..500]), text(&h[0..100]));
                    if prefix.is_empty() {
                        name
                    } else {
                        format!("{prefix}/{name}")
                    }
                });
                if name.trim_start_matches("./") == wanted {
                    return Some(data.to_vec());
                }
            }
        }
        at = body + size.div_ceil(512) * 512;
    }
    None
}

/// The scan written into `dir`, or None (said on stderr) without the package.
fn hippo(dir: &Path) -> Option<PathBuf> {
    let archive = Path::new(CGAL_DATA);
    let Some(bytes) = archive.is_file().then(|| tar_member(archive, HIPPO)).flatten() else {
        assert!(
            std::env::var_os("SOMNURBS_REQUIRE_REAL_SCAN").is_none(),
            "{HIPPO} not found in {CGAL_DATA}: run scripts/install_cgal_demo.sh"
        );
        eprintln!(
            "real_scan: skipped, {CGAL_DATA} is missing (scripts/install_cgal_demo.sh installs it)"
        );
        return None;
    };
    let path = dir.join("hippo1.ply");
    std::fs::write(&path, bytes).unwrap();
    Some(path)
}

/// (min, max) per axis of an OBJ mesh's vertices (the surfaces evaluated densely).
fn obj_extent(path: &Path) -> [(f64, f64); 3] {
    let text = std::fs::read_to_string(path).unwrap();
    let mut e = [(f64::INFINITY, f64::NEG_INFINITY); 3];
    let mut n = 0;
    for l in text.lines().filter_map(|l| l.strip_prefix("v ")) {
        for (ea, v) in e.iter_mut().zip(l.split_whitespace()) {
            let v: f64 = v.parse().unwrap();
            *ea = (ea.0.min(v), ea.1.max(v));
        }
        n += 1;
    }
    assert!(n > 100, "{}: {n} vertices", path.display());
    e
}

/// The scan's points' extent, read from its binary PLY (x, y, z, nx, ny, nz as doubles).
fn ply_extent(path: &Path) -> [(f64, f64); 3] {
    let bytes = std::fs::read(path).unwrap();
    let head_end = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let mut e = [(f64::INFINITY, f64::NEG_INFINITY); 3];
    for rec in bytes[head_end..].chunks_exact(48) {
        for (a, ea) in e.iter_mut().enumerate() {
            let v = f64::from_le_bytes(rec[8 * a..8 * a + 8].try_into().unwrap());
            *ea = (ea.0.min(v), ea.1.max(v));
        }
    }
    e
}

const SPEC: &str = r#"
name = "hippo"
master_seed = 17
[optimise]
datasets = ["hippo1.ply"]
grid = "12x12"
control_nets = ["6x6"]
parameterisations = ["chord_length"]
optimisers = ["de"]
repeats = 1
generations = 30
population = 10
[optimise.som]
iterations = 3000
"#;

#[test]
fn a_real_scan_is_mapped_fitted_optimised_exported_and_reported() {
    let c = Case::new();
    let Some(scan) = hippo(c.dir.path()) else { return };
    let data = ply_extent(&scan);
    let diagonal = data.iter().map(|(lo, hi)| (hi - lo).powi(2)).sum::<f64>().sqrt();
    // Inside the scan's box, grown by a tenth of its diagonal on every side.
    let near = |e: [(f64, f64); 3], what: &str| {
        for (a, (lo, hi)) in e.iter().enumerate() {
            let (dlo, dhi) = data[a];
            assert!(
                *lo >= dlo - 0.1 * diagonal && *hi <= dhi + 0.1 * diagonal,
                "{what}: axis {a} spans [{lo}, {hi}], the scan [{dlo}, {dhi}]"
            );
        }
    };
    c.write("hippo.toml", SPEC);
    c.ok(&["run", "hippo.toml", "--out", "r"]);
    // The map and its frame; the fitted surfaces, in the scan's frame, lie on the scan.
    let map = c.path("r/maps/dnsom_hippo1_12x12.csv.gz");
    assert!(map.is_file() && c.path("r/maps/dnsom_hippo1_12x12.frame.toml").is_file());
    // The default fit of this map leaves its box between the data points by more than the bound:
    // refused, nothing written, the user's own options measured; the first one named is taken.
    let grid = map.to_str().unwrap();
    let refused = c.run(&["fit", "--grid", grid, "--cn", "6x6", "--out", "f"]);
    let said = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{said}");
    assert!(
        said.contains("dnsom_hippo1_12x12.csv.gz") && said.contains("--fairness 1e-4"),
        "{said}"
    );
    assert!(!c.path("f").exists());
    c.ok(&["fit", "--grid", grid, "--cn", "6x6", "--fairness", "1e-4", "--out", "f"]);
    near(obj_extent(&c.path("f/surfaces.obj")), "fit's surfaces");
    // The optimised net, exported from the record: its error is the record's, its net on the scan.
    let (h, rows) = read_csv(&c.path("r/runs.csv"));
    let cell = rows[0][col(&h, "cell")].clone();
    // The run's own 6x6 fit leaves the map's box as the default fit did: its export is refused
    // the same way, and --allow-excursion writes it.
    let refused = c.run(&["export", "r", "--cell", &cell, "--out", "x"]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--allow-excursion"));
    assert!(!c.path("x").exists());
    c.ok(&["export", "r", "--cell", &cell, "--allow-excursion", "--out", "x"]);
    let (eh, erows) = read_csv(&c.path("x/export.csv"));
    let error: f64 = erows[0][col(&eh, "surface_error")].parse().unwrap();
    assert_eq!(error.to_bits(), rows[0][col(&h, "best")].parse::<f64>().unwrap().to_bits());
    assert!(error <= rows[0][col(&h, "b")].parse::<f64>().unwrap(), "DE's best is above B");
    near(obj_extent(&c.path("x/surfaces.obj")), "the exported optimised surfaces");
    // The report of the folder is made again from its records alone, byte for byte.
    report_restores_folder(&c, "r");
}
