//! Named data sets and user files: the one place in `data` that reads files.

use super::frame::{Frame, GENERATED};
use super::{generators, obj, off, ply, stl, validate, xyz, DataError, Normalise, PointCloud};
use crate::geom::Point3;
use rand::SeedableRng;
use std::path::{Path, PathBuf};

/// Built-in data-set names.
pub(crate) const BUILTIN: &[&str] = &[
    "cube",
    "sphere",
    "spindle",
    "oiltank",
    "talus",
    "bunny",
    "cylinder",
    "semi_sphere",
    "saddle",
];

/// Number of points sampled on the talus mesh (the thesis' talus has 5253 points).
pub(crate) const TALUS_POINTS: usize = 5253;
/// Seed of the talus sample (the thesis' own scan points are not public).
pub(crate) const TALUS_SAMPLE_SEED: u64 = 5253;
/// Points sampled from a user's STL file unless `path.stl:N` says otherwise.
pub(crate) const DEFAULT_STL_POINTS: usize = 5000;
/// The most points `path.stl:N` may ask for.
pub(crate) const MAX_STL_POINTS: usize = 10_000_000;
/// File types a data-set path may have.
pub(crate) const EXTENSIONS: [&str; 7] = [".ply", ".stl", ".off", ".obj", ".xyz", ".csv", ".txt"];

/// [`dataset_name`] of an entry validation has passed (the entry itself if it would not).
pub(crate) fn name_of(entry: &str) -> String {
    dataset_name(entry).unwrap_or_else(|_| entry.to_string())
}

/// A data-set entry of a spec split into its file and the `:N` point count of an STL path.
fn split_count(entry: &str) -> Result<(&str, Option<usize>), DataError> {
    match entry.rsplit_once(':') {
        Some((f, n)) if f.to_ascii_lowercase().ends_with(".stl") => {
            let n: usize = n
                .parse()
                .map_err(|_| DataError::Invalid(format!("{entry}: `{n}` is not a point count")))?;
            if !(4..=MAX_STL_POINTS).contains(&n) {
                return Err(DataError::Invalid(format!(
                    "{entry}: {n} points is outside [4, {MAX_STL_POINTS}]"
                )));
            }
            Ok((f, Some(n)))
        }
        _ => Ok((entry, None)),
    }
}

/// The name a data set goes by in cell keys, seeds, tables and file names: a built-in's own name,
/// a file's stem (`scans/part.xyz` and `/abs/part.xyz` are both `part`, so a result does not
/// depend on where its file lives). Refuses an entry that is neither a built-in nor a point file,
/// and a name that could not be a file name (empty, `.`, `..`).
pub(crate) fn dataset_name(entry: &str) -> Result<String, DataError> {
    if BUILTIN.contains(&entry) {
        return Ok(entry.to_string());
    }
    let (file, _) = split_count(entry)?;
    let lower = file.to_ascii_lowercase();
    if !EXTENSIONS.iter().any(|e| lower.ends_with(e)) {
        return Err(DataError::Invalid(format!(
            "unknown data set `{entry}` (built-in: {}; or a .ply/.stl/.off/.obj/.xyz/.csv/.txt file)",
            BUILTIN.join(", ")
        )));
    }
    let stem = Path::new(file).file_stem().and_then(|s| s.to_str()).unwrap_or("");
    if stem.is_empty() || stem == "." || stem == ".." || stem.starts_with('.') {
        return Err(DataError::Invalid(format!(
            "data set `{entry}`: its file name gives no usable name (`{stem}`)"
        )));
    }
    Ok(stem.to_string())
}

pub(crate) const BUNNY_FILE: &str = "bun_zipper.ply";
pub(crate) const TALUS_FILE: &str = "talus_r.stl";

/// One line about a built-in data set.
pub(crate) fn describe(name: &str) -> Option<&'static str> {
    Some(match name {
        "cube" => "7352 points, unit-cube surface lattice (generated)",
        "sphere" => "7082 points, sphere rings at 3-degree steps (generated)",
        "spindle" => {
            "7552 points, surface of revolution, 151 rings x 50 (generated; som.spindle_profile)"
        }
        "oiltank" => "5942 points, capsule with spherical-cap domes, 99 rings x 60 (generated)",
        "talus" => "5253 points sampled on talus_r.stl (TLEM 2.0 talus bone; data file)",
        "bunny" => "35947 vertices of bun_zipper.ply (Stanford bunny; data file)",
        "cylinder" => "3876 points, cylinder r = 5, h = 5, 51 rings x 76 (seed 004; generated)",
        "semi_sphere" => "3601 points, upper hemisphere (seed 001; generated)",
        "saddle" => "3600 points, z = x^2 - y^2 on a 60 x 60 lattice (seed 001; generated)",
        _ => return None,
    })
}

fn read(path: &Path, hint: &str) -> Result<Vec<u8>, DataError> {
    use crate::io::input::{self, InputError, Kind};
    input::read(path, Kind::Data).map_err(|e| match e {
        InputError::NotFound { .. } => {
            DataError::Missing { path: path.display().to_string(), hint: hint.to_string() }
        }
        e => input_error(e),
    })
}

/// A data file that could not be read: one that is there but is no regular file is named for
/// what it is (checked without opening it).
fn input_error(e: crate::io::input::InputError) -> DataError {
    use crate::io::input::InputError;
    match e {
        InputError::NotRegular { path, what } => DataError::Invalid(format!(
            "{path} is {what}, not a data file (name a .ply, .stl, .off, .obj, .xyz, .csv or .txt file)"
        )),
        e => DataError::Invalid(e.to_string()),
    }
}

fn where_to_get(file: &str) -> String {
    let source = match file {
        BUNNY_FILE => {
            "the Stanford 3D Scanning Repository, http://graphics.stanford.edu/pub/3Dscanrep/bunny.tar.gz (the file bunny/reconstruction/bun_zipper.ply inside it)"
        }
        _ => "https://github.com/modenaxe/msk-STAPLE/raw/master/bone_datasets/TLEM2/stl/talus_r.stl",
    };
    format!(
        "Download {file} from {source} into ./data (the default), or name its folder with SOMNURBS_DATA, the CLI's --data-dir or Python's data_dir= (README, \"Set up\")."
    )
}

fn sample_stl(bytes: &[u8], n: usize, seed: u64, shown: &str) -> Result<Vec<Point3>, DataError> {
    let tris = stl::parse_stl(bytes).map_err(|e| e.in_file(shown))?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    stl::sample_surface(&tris, n, &mut rng).map_err(|e| e.in_file(shown))
}

/// Load a data set by name or path (`Loader::load`): paths relative to the working folder,
/// normalised per axis (the thesis).
/// No spec is involved, so a missing file's hint names the working folder, not a spec.
pub fn load_dataset(name: &str, data_dir: &Path) -> Result<PointCloud, DataError> {
    let loader = Loader { data_dir: data_dir.to_path_buf(), ..Loader::default() };
    loader.load(name).map_err(|e| match e {
        DataError::Missing { path, .. } if !BUILTIN.contains(&name) => DataError::Missing {
            path,
            hint: "A relative path is read from the working folder; `somnurbs datasets list` \
                   names the built-in data sets."
                .into(),
        },
        other => other,
    })
}

/// How a spec's data sets load: the folder of the data files (bunny, talus), the folder a
/// relative data-set path resolves against (the spec's own), and the normalisation.
#[derive(Debug, Clone, Default)]
pub struct Loader {
    pub data_dir: PathBuf,
    pub base: PathBuf,
    pub normalise: Normalise,
    /// The spindle's profile and ring placement (`som.spindle_profile`, `som.spindle_rings`).
    pub spindle: (generators::SpindleProfile, generators::SpindleRings),
}

impl Loader {
    /// The file of a path entry (not a built-in): absolute as it is, relative under `base`.
    pub fn resolve(&self, entry: &str) -> Result<PathBuf, DataError> {
        let (file, _) = split_count(entry)?;
        Ok(if Path::new(file).is_absolute() { PathBuf::from(file) } else { self.base.join(file) })
    }

    /// Refuse a path entry whose file is not there (cheap: nothing is read), so that a run can
    /// fail before it writes anything.
    pub fn require_file(&self, entry: &str) -> Result<(), DataError> {
        if BUILTIN.contains(&entry) {
            return Ok(());
        }
        dataset_name(entry)?;
        let path = self.resolve(entry)?;
        use crate::io::input::{self, InputError, Kind};
        match input::check(&path, Kind::Data) {
            Ok(()) => {}
            Err(InputError::NotFound { .. }) => return Err(DataError::Missing { path: path.display().to_string(), hint: format!("The spec names `{entry}`; a relative data-set path is read from the spec's folder ({}).", if self.base.as_os_str().is_empty() { ".".into() } else { self.base.display().to_string() }) }),
            Err(e) => return Err(input_error(e)),
        }
        Ok(())
    }

    /// Load a data set by name (`somnurbs datasets list`) or a point file path (.ply, .off, .obj,
    /// .xyz, .csv, .txt, or .stl, sampled with `path.stl:N` points, default 5000). Points are
    /// validated (finite, at least 4, not all equal) and scaled by `normalise`; the cloud's frame
    /// records how.
    pub fn load(&self, name: &str) -> Result<PointCloud, DataError> {
        let (mut points, source) = self.read_points(name)?;
        validate(&points, 4).map_err(|e| e.in_file(name))?;
        let frame = Frame::of(self.normalise, &points, &dataset_name(name)?, &source);
        self.normalise.apply(&mut points);
        // Coordinates near the f64 limit overflow the ranges into inf and the points into NaN.
        validate(&points, 4).map_err(|e| {
            DataError::Invalid(format!(
                "{name}: after normalisation: {e} (coordinates too large to normalise)"
            ))
        })?;
        if points.iter().all(|p| *p == points[0]) {
            return Err(DataError::Invalid(format!(
                "{name}: all {} points are the same point",
                points.len()
            )));
        }
        Ok(PointCloud { name: dataset_name(name)?, points, frame })
    }

    /// The points of a data set as they are (before normalisation) and where they came from (the
    /// file as read, or `generated`).
    fn read_points(&self, name: &str) -> Result<(Vec<Point3>, String), DataError> {
        let data_dir = &self.data_dir;
        let generated = |p: Vec<Point3>| Ok((p, GENERATED.to_string()));
        match name {
            "cube" => generated(generators::cube()),
            "sphere" => generated(generators::sphere()),
            "spindle" => generated(generators::spindle_with(self.spindle.0, self.spindle.1)),
            "oiltank" => generated(generators::oiltank()),
            "cylinder" => generated(generators::cylinder()),
            "semi_sphere" => generated(generators::semi_sphere()),
            "saddle" => generated(generators::saddle()),
            "bunny" => {
                let path = data_dir.join(BUNNY_FILE);
                let shown = path.display().to_string();
                let p = ply::parse_ply(&read(&path, &where_to_get(BUNNY_FILE))?)
                    .map_err(|e| e.in_file(&shown))?;
                Ok((p, shown))
            }
            "talus" => {
                let path = data_dir.join(TALUS_FILE);
                let shown = path.display().to_string();
                let bytes = read(&path, &where_to_get(TALUS_FILE))?;
                Ok((sample_stl(&bytes, TALUS_POINTS, TALUS_SAMPLE_SEED, &shown)?, shown))
            }
            other => {
                self.require_file(other)?;
                let (_, count) = split_count(other)?;
                let path = self.resolve(other)?;
                let shown = path.display().to_string();
                let bytes = read(&path, "Check the path in the spec.")?;
                Ok((parse_file(&bytes, &shown, count)?, shown))
            }
        }
    }
}

/// The points of a user's file by its extension (`shown` names it in errors and notes).
fn parse_file(bytes: &[u8], shown: &str, count: Option<usize>) -> Result<Vec<Point3>, DataError> {
    let lower = shown.to_ascii_lowercase();
    let ext = lower.rsplit('.').next().unwrap_or("");
    if !matches!(ext, "ply" | "stl") {
        // A text format: UTF-16 (or NUL bytes) is named as such, not parsed into odd errors.
        crate::io::not_utf16(shown, bytes).map_err(DataError::Invalid)?;
    }
    match ext {
        "ply" => ply::parse_ply(bytes).map_err(|e| e.in_file(shown)),
        "off" => off::parse_off(bytes).map_err(|e| e.in_file(shown)),
        "obj" => obj::parse_obj(bytes).map_err(|e| e.in_file(shown)),
        "stl" => sample_stl(bytes, count.unwrap_or(DEFAULT_STL_POINTS), TALUS_SAMPLE_SEED, shown),
        _ => {
            let text = String::from_utf8_lossy(bytes);
            let (points, extra) = xyz::parse_xyz_columns(&text).map_err(|e| e.in_file(shown))?;
            if extra > 0 {
                note_once(
                    shown,
                    &format!(
                        "{shown}: the {extra} column{} after x y z ignored (e.g. normals)",
                        if extra == 1 { "" } else { "s" }
                    ),
                );
            }
            Ok(points)
        }
    }
}

/// Print `somnurbs: note: MESSAGE` on stderr the first time `key` is noted in this process (a
/// file read by several steps of one run is noted once).
fn note_once(key: &str, message: &str) {
    static NOTED: std::sync::Mutex<std::collections::BTreeSet<String>> =
        std::sync::Mutex::new(std::collections::BTreeSet::new());
    let first = NOTED.lock().map(|mut s| s.insert(key.to_string())).unwrap_or(true);
    if first {
        crate::notice::emit(&format!("somnurbs: note: {message}"));
    }
}

/// The top of the clone this crate was built from (`CARGO_MANIFEST_DIR`): where the tests find
/// the data, and where `reproduce` finds its plans when run from another folder without `--specs`.
pub(crate) const CLONE_DIR: &str = env!("CARGO_MANIFEST_DIR");

/// Where somnurbs finds a folder it reads, the one rule for the data folder and the folder of the
/// plans (docs/running.md, "Where data, specs and plans are found"): `flag`, else the environment
/// variable `env` when set and not empty, else `name` in the working folder when it is a folder,
/// else `name` in the clone somnurbs was built from when that is one, else `name` in the working
/// folder (what errors then name). The flag says the clone's was taken.
pub(crate) fn found_folder(flag: Option<&Path>, env: Option<&str>, name: &str) -> (PathBuf, bool) {
    if let Some(p) = flag {
        return (p.to_path_buf(), false);
    }
    if let Some(v) = env.and_then(std::env::var_os).filter(|v| !v.is_empty()) {
        return (PathBuf::from(v), false);
    }
    let here = PathBuf::from(name);
    if here.is_dir() {
        return (here, false);
    }
    let clone = Path::new(CLONE_DIR).join(name);
    if clone.is_dir() {
        return (clone, true);
    }
    (here, false)
}

/// The data folder the tests use: what a user's main job uses when run from the top of the clone
/// ([`found_folder`]: `SOMNURBS_DATA` if set, else `<clone>/data`).
pub fn clone_data_dir() -> PathBuf {
    match std::env::var_os("SOMNURBS_DATA") {
        Some(v) if !v.is_empty() => PathBuf::from(v),
        _ => Path::new(CLONE_DIR).join("data"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_are_found_by_flag_then_environment_then_working_folder() {
        // The unit tests run at the top of the clone, which has experiments/.
        let var = "SOMNURBS_TEST_FOUND_FOLDER";
        assert_eq!(
            found_folder(Some(Path::new("f")), Some(var), "experiments"),
            ("f".into(), false)
        );
        assert_eq!(found_folder(None, Some(var), "experiments"), ("experiments".into(), false));
        assert_eq!(found_folder(None, None, "no_such_folder"), ("no_such_folder".into(), false));
        std::env::set_var(var, "from_env");
        assert_eq!(found_folder(None, Some(var), "experiments"), ("from_env".into(), false));
        std::env::set_var(var, "");
        assert_eq!(found_folder(None, Some(var), "experiments"), ("experiments".into(), false));
    }

    #[test]
    fn bunny_first_point_after_normalisation() {
        let b = load_dataset("bunny", &clone_data_dir()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(b.points.len(), 35947);
        let want = [0.365193, 0.615243, 0.549817];
        for k in 0..3 {
            assert!((b.points[0][k] - want[k]).abs() < 1e-6, "{:?}", b.points[0]);
        }
    }

    #[test]
    fn talus_is_a_fixed_sample() {
        let a = load_dataset("talus", &clone_data_dir()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(a.points.len(), TALUS_POINTS);
        let b = load_dataset("talus", &clone_data_dir()).unwrap();
        assert_eq!(a, b);
        assert!(a.points.iter().all(|p| p.iter().all(|v| (0.0..=1.0).contains(v))));
    }

    #[test]
    fn missing_files_say_where_to_get_them() {
        let e = load_dataset("bunny", Path::new("/nonexistent")).unwrap_err().to_string();
        assert!(
            e.contains("/nonexistent/bun_zipper.ply")
                && e.contains("Stanford")
                && e.contains("SOMNURBS_DATA"),
            "{e}"
        );
        let e = load_dataset("teapot", Path::new(".")).unwrap_err().to_string();
        assert!(e.contains("teapot") && e.contains("cube"), "{e}");
    }

    /// A path that is there but is no regular file is named for what it is (checked without
    /// opening it), and a missing one outside a spec mentions no spec.
    #[test]
    fn a_path_that_is_no_regular_file_says_what_it_is() {
        let dir = tempfile::tempdir().unwrap();
        let folder = dir.path().join("scans.xyz");
        std::fs::create_dir(&folder).unwrap();
        let null = dir.path().join("null.xyz");
        std::os::unix::fs::symlink("/dev/null", &null).unwrap();
        for (path, kind) in [(&folder, "a folder"), (&null, "a device")] {
            let shown = path.display().to_string();
            let e = load_dataset(&shown, dir.path()).unwrap_err().to_string();
            let want = format!("{shown} is {kind}, not a data file (name a .ply,");
            assert!(e.starts_with(&want) && !e.contains("spec"), "{e}");
            let own = Loader { base: dir.path().to_path_buf(), ..Loader::default() };
            let e = own.require_file(&shown).unwrap_err().to_string();
            assert!(e.starts_with(&want), "{e}");
        }
        let none = dir.path().join("none.xyz").display().to_string();
        let e = load_dataset(&none, dir.path()).unwrap_err().to_string();
        assert!(e.contains("data file not found") && e.contains("working folder"), "{e}");
        assert!(!e.contains("spec"), "{e}");
    }

    #[test]
    fn names_are_stems_and_bad_files_are_refused_by_name() {
        assert_eq!(dataset_name("cube").unwrap(), "cube");
        assert_eq!(dataset_name("/abs/path/part.xyz").unwrap(), "part");
        assert_eq!(dataset_name("../up/part.stl:500").unwrap(), "part");
        for bad in ["../.xyz", "x.stl:0", "x.stl:99999999999", "x.step", "..", "."] {
            assert!(dataset_name(bad).is_err(), "{bad}");
        }
        let dir = tempfile::tempdir().unwrap();
        let huge = dir.path().join("huge.xyz");
        std::fs::write(&huge, "1e308 0 0\n-1e308 1 1\n0 0 2\n5 5 5\n").unwrap();
        let e = load_dataset(huge.to_str().unwrap(), dir.path()).unwrap_err().to_string();
        assert!(e.contains("huge.xyz: line 1") && e.contains("beyond the limit"), "{e}");
        let utf16 = dir.path().join("wide.xyz");
        std::fs::write(&utf16, b"\xFF\xFE1\x00 \x002\x00").unwrap();
        let e = load_dataset(utf16.to_str().unwrap(), dir.path()).unwrap_err().to_string();
        assert!(e.contains("wide.xyz: UTF-16 text") && !e.contains('\0'), "{e}");
        let same = dir.path().join("same.csv");
        std::fs::write(&same, "1,2,3\n1,2,3\n1,2,3\n1,2,3\n1,2,3\n").unwrap();
        let e = load_dataset(same.to_str().unwrap(), dir.path()).unwrap_err().to_string();
        assert!(e.contains("same.csv") && e.contains("same point"), "{e}");
        // A relative path resolves against the loader's base (a spec's folder), not the working folder.
        let own = Loader { base: dir.path().to_path_buf(), ..Loader::default() };
        assert!(own.load("same.csv").unwrap_err().to_string().contains("same point"));
        let e = own.load("sub/none.xyz").unwrap_err().to_string();
        assert!(
            e.contains(&dir.path().join("sub/none.xyz").display().to_string())
                && e.contains("spec's folder"),
            "{e}"
        );
        let ok = dir.path().join("ok.xyz");
        std::fs::write(&ok, "0 0 0\n1 0 0\n0 1 0\n0 0 1\n").unwrap();
        assert_eq!(load_dataset(ok.to_str().unwrap(), dir.path()).unwrap().name, "ok");
    }
}
