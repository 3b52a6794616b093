//! SOMNURBS_SIMD forces one compiled copy of the kernels (fitness, DE trial, PSO move, cuckoo
//! search's Levy steps): every forced copy must give the same tables, bit for bit, as the
//! scalar one; a copy this CPU lacks is refused with a one-line error (exit 2); a malformed value
//! likewise.

use crate::common::*;
use somnurbs::simd::Isa;

/// Every optimiser (so every kernel) on two nets, one of them with padded lanes.
const ALL_KERNELS: &str = r#"
name = "simd"
master_seed = 5
[optimise]
datasets = ["sphere"]
grid = "20x20"
control_nets = ["6x6", "9x7"]
parameterisations = ["chord_length"]
optimisers = ["ga", "de", "pso", "csa", "icsa"]
repeats = 2
generations = 30
population = 10
init_range = 1e-3
[optimise.som]
iterations = 300
"#;

/// Run the spec with SOMNURBS_SIMD = `simd` into `out`; the output.
fn run_with(case: &Case, spec: &str, simd: &str, out: &str) -> std::process::Output {
    crate::common::bin()
        .args(["run", spec, "--out", out, "--jobs", "2"])
        .current_dir(case.dir.path())
        .env("SOMNURBS_DATA", data_dir())
        .env("SOMNURBS_SIMD", simd)
        .output()
        .unwrap()
}

fn forced_copy_matches_scalar(simd: &str, supported: bool) {
    let case = Case::new();
    let spec = case.write("simd.toml", ALL_KERNELS);
    let spec = spec.to_str().unwrap();
    if !supported {
        let out = run_with(&case, spec, simd, "forced");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{}", case.explain(&["run", spec], &out));
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains("SOMNURBS_SIMD") && err.contains("lacks"), "{err}");
        assert!(!case.path("forced").join("runs.csv").exists(), "nothing written");
        println!(
            "SOMNURBS_SIMD={simd}: this CPU lacks the copy, so only its refusal was tested: {}",
            err.trim_end()
        );
        return;
    }
    for (simd, out) in [("scalar", "scalar"), (simd, "forced")] {
        let o = run_with(&case, spec, simd, out);
        assert!(o.status.success(), "SOMNURBS_SIMD={simd}\n{}", case.explain(&["run", spec], &o));
    }
    let n = same_tables(&case.path("scalar"), &case.path("forced"));
    assert!(n >= 1, "no tables compared");
    let (h, rows) = read_csv(&case.path("forced").join("runs.csv"));
    let opt = col(&h, "optimiser");
    for name in ["ga", "de", "pso", "csa", "icsa"] {
        assert!(rows.iter().any(|r| r[opt] == name), "no {name} run in runs.csv");
    }
}

#[test]
fn forced_avx2_copy_is_bit_identical_to_scalar() {
    forced_copy_matches_scalar("avx2", Isa::Avx2.supported());
}

#[test]
fn forced_avx512_copy_is_bit_identical_to_scalar() {
    forced_copy_matches_scalar("avx512", Isa::Avx512Vl.supported());
}

#[test]
fn auto_is_bit_identical_to_scalar() {
    forced_copy_matches_scalar("auto", true);
}

#[test]
fn malformed_simd_value_is_refused() {
    let case = Case::new();
    let spec = case.write("simd.toml", ALL_KERNELS);
    let out = run_with(&case, spec.to_str().unwrap(), "sse9", "out");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("SOMNURBS_SIMD must be scalar, avx2, avx512 or auto, got 'sse9'"),
        "{err}"
    );
}

#[test]
fn simd_values_are_parsed_and_checked_against_the_cpu() {
    use somnurbs::simd::parse_simd;
    for v in [None, Some(""), Some("auto"), Some(" auto ")] {
        assert_eq!(parse_simd(v).unwrap(), Isa::fastest());
    }
    assert_eq!(parse_simd(Some("scalar")).unwrap(), Isa::Baseline);
    for (v, isa) in [("avx2", Isa::Avx2), ("avx512", Isa::Avx512Vl)] {
        match parse_simd(Some(v)) {
            Ok(got) => assert!(got == isa && isa.supported(), "{v}"),
            Err(e) => {
                assert!(!isa.supported(), "{v}: {e}");
                assert!(
                    e.to_string().starts_with("SOMNURBS_SIMD asks for the")
                        && e.to_string().contains("lacks"),
                    "{e}"
                );
            }
        }
    }
    assert_eq!(
        parse_simd(Some("sse")).unwrap_err().to_string(),
        "SOMNURBS_SIMD must be scalar, avx2, avx512 or auto, got 'sse'"
    );
}
