//! Bounded-time fuzzing of the readers of outside input: thousands of random mutations and
//! truncations of valid PLY (ascii, little and big endian), STL (ascii and binary), XYZ and spec
//! texts go through the library's parsers. None may panic, take more than a second, or ask for one
//! allocation above `MAX_ALLOCATION` (checked by a counting allocator: this file is its own test
//! binary, and its single test runs the cases one after another).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use somnurbs::data::{obj, off, ply, stl, xyz};
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The largest single allocation a parser may make on these (small) inputs.
const MAX_ALLOCATION: usize = 64 << 20;
const CASES_PER_SEED: usize = 400;

struct Counting;

static LARGEST: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        if layout.size() > MAX_ALLOCATION {
            // Refuse rather than exhaust the machine: the test then fails on LARGEST.
            return std::ptr::null_mut();
        }
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        if new_size > MAX_ALLOCATION {
            return std::ptr::null_mut();
        }
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

const NUMBERS: [&str; 12] = [
    "1000000000000",
    "1000000000000000000",
    "18446744073709551615",
    "-1",
    "0",
    "1e308",
    "-1e308",
    "inf",
    "nan",
    "4294967295",
    "2.5",
    "99999999999999999999999",
];

/// One random mutation of `seed`: byte flips, a number put in place of a digit run, a cut, a
/// repeated slice, or a line dropped.
fn mutate(seed: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..rng.gen_range(1..4) {
        if b.is_empty() {
            break;
        }
        let at = rng.gen_range(0..b.len());
        match rng.gen_range(0..6) {
            0 => b[at] = rng.gen(),
            1 => {
                // Replace the digit run at or after `at` by a troublesome number.
                let start = (at..b.len()).find(|&k| b[k].is_ascii_digit()).unwrap_or(at);
                let end = (start..b.len())
                    .find(|&k| !b[k].is_ascii_digit() && b[k] != b'.')
                    .unwrap_or(b.len());
                let n = NUMBERS[rng.gen_range(0..NUMBERS.len())].as_bytes();
                b.splice(start..end, n.iter().copied());
            }
            2 => b.truncate(at),
            3 => {
                let end = (at + rng.gen_range(1..64)).min(b.len());
                let piece = b[at..end].to_vec();
                b.splice(at..at, piece);
            }
            4 => {
                let end = (at..b.len()).find(|&k| b[k] == b'\n').map_or(b.len(), |k| k + 1);
                b.drain(at..end);
            }
            _ => {
                let v: u32 = rng.gen();
                let end = (at + 4).min(b.len());
                b.splice(at..end, v.to_le_bytes());
            }
        }
    }
    b
}

fn ply_seeds() -> Vec<Vec<u8>> {
    let verts: Vec<[f32; 3]> =
        (0..6).map(|k| [k as f32, (k * 2) as f32 * 0.5, 1.0 - k as f32]).collect();
    let header = |fmt: &str| {
        format!("ply\nformat {fmt} 1.0\ncomment fuzz\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n", verts.len())
    };
    let mut ascii = header("ascii");
    for v in &verts {
        ascii.push_str(&format!("{} {} {} 7\n", v[0], v[1], v[2]));
    }
    ascii.push_str("3 0 1 2\n3 1 2 3\n");
    let binary = |big: bool| {
        let mut b =
            header(if big { "binary_big_endian" } else { "binary_little_endian" }).into_bytes();
        for v in &verts {
            for x in v {
                b.extend(if big { x.to_be_bytes() } else { x.to_le_bytes() });
            }
            b.push(7);
        }
        for f in [[0i32, 1, 2], [1, 2, 3]] {
            b.push(3);
            for i in f {
                b.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
            }
        }
        b
    };
    vec![ascii.into_bytes(), binary(false), binary(true)]
}

fn stl_seeds() -> Vec<Vec<u8>> {
    let tris = [
        [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [0.0, 1.0, 2.0]],
    ];
    let mut ascii = String::from("solid s\n");
    let mut bin = vec![b' '; 80];
    bin.extend((tris.len() as u32).to_le_bytes());
    for t in &tris {
        ascii.push_str("facet normal 0 0 1\nouter loop\n");
        bin.extend([0u8; 12]);
        for v in t {
            ascii.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
            for x in v {
                bin.extend(x.to_le_bytes());
            }
        }
        bin.extend([0u8; 2]);
        ascii.push_str("endloop\nendfacet\n");
    }
    ascii.push_str("endsolid s\n");
    vec![ascii.into_bytes(), bin]
}

fn spec_seeds() -> Vec<Vec<u8>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments");
    let mut out: Vec<Vec<u8>> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.extension().is_some_and(|e| e == "toml")
                && !["thesis.toml", "seeds.toml", "all.toml"]
                    .contains(&p.file_name().unwrap().to_str().unwrap())
        })
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    out.sort();
    out
}

/// Run `parse` on `CASES_PER_SEED` mutations of each seed: no panic, each under a second.
fn fuzz(
    what: &str,
    seeds: &[Vec<u8>],
    rng: &mut ChaCha8Rng,
    parse: impl Fn(&[u8]) -> bool,
) -> (usize, usize) {
    let mut ok = 0;
    let mut total = 0;
    for seed in seeds {
        assert!(parse(seed), "{what}: an unmutated seed does not parse");
        for _ in 0..CASES_PER_SEED {
            let input = mutate(seed, rng);
            let t0 = Instant::now();
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| parse(&input)));
            let took = t0.elapsed();
            let shown = String::from_utf8_lossy(&input[..input.len().min(600)]).to_string();
            assert!(r.is_ok(), "{what}: panicked on\n{shown}");
            assert!(took < Duration::from_secs(1), "{what}: {took:?} on\n{shown}");
            assert!(
                LARGEST.load(Ordering::Relaxed) <= MAX_ALLOCATION,
                "{what}: an allocation of {} bytes on\n{shown}",
                LARGEST.load(Ordering::Relaxed)
            );
            ok += r.unwrap() as usize;
            total += 1;
        }
    }
    (ok, total)
}

#[test]
fn readers_and_spec_loader_survive_random_mutations() {
    let started = Instant::now();
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let ply = fuzz("PLY", &ply_seeds(), &mut rng, |b| ply::parse_ply(b).is_ok());
    let stl = fuzz("STL", &stl_seeds(), &mut rng, |b| stl::parse_stl(b).is_ok());
    let xyz_seed =
        b"x,y,z\n# points\n0 0 0\n1,0,0\n0;1;0\n0.5 0.5 1 extra\n1e-3 2e-3 3e-3\n".to_vec();
    let xyz =
        fuzz("XYZ", &[xyz_seed], &mut rng, |b| xyz::parse_xyz(&String::from_utf8_lossy(b)).is_ok());
    let off_seed = b"OFF\n# a tetrahedron\n4 4 6\n0 0 0\n1 0 0 0 0 1\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 0 2 3\n3 1 2 3\n".to_vec();
    let off = fuzz("OFF", &[off_seed], &mut rng, |b| off::parse_off(b).is_ok());
    let obj_seed =
        b"# quad\no q\nv 0 0 0\nv 1 0 0 1.0\nvn 0 0 1\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n".to_vec();
    let obj = fuzz("OBJ", &[obj_seed], &mut rng, |b| obj::parse_obj(b).is_ok());
    let specs = fuzz("spec", &spec_seeds(), &mut rng, |b| {
        let text = String::from_utf8_lossy(b);
        let plain = somnurbs::families::Loaded::parse("fuzz.toml", &text, None);
        let quick = somnurbs::families::Loaded::parse("fuzz.toml", &text, Some("quick"));
        // A spec that passes must also list its cells quickly.
        if let Ok(s) = plain.as_ref().or(quick.as_ref()) {
            let _ = somnurbs::experiment::dry_run_listing(s);
        }
        plain.is_ok() || quick.is_ok()
    });
    // Both outcomes occur: the mutations reach past the first check.
    for (what, (ok, total)) in
        [("PLY", ply), ("STL", stl), ("XYZ", xyz), ("OFF", off), ("OBJ", obj), ("spec", specs)]
    {
        assert!(ok > 0 && ok < total, "{what}: {ok} of {total} parsed");
    }
    assert!(started.elapsed() < Duration::from_secs(120), "{:?}", started.elapsed());
}
