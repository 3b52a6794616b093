//! Unit tests of the spec parser (profiles, overrides, one section per spec), with real families.

use super::*;

/// The crate's own families.
type L = crate::families::Loaded;

const SPEC: &str = r#"
name = "t"
master_seed = 1
[som]
datasets = ["cube"]
iterations = 100
[[som.group]]
models = ["som2d", "dnsom"]
grids = ["10x10", "18x30"]
[profiles.quick.som]
iterations = 7
"#;

#[test]
fn parses_expands_and_applies_profile() {
    let s = L::parse("t.toml", SPEC, None).unwrap();
    assert_eq!(crate::families::som::spec::cells(s.section_as().unwrap()).len(), 4);
    assert_eq!(s.section_as::<crate::families::som::spec::SomSpec>().unwrap().iterations, 100);
    let q = L::parse("t.toml", SPEC, Some("quick")).unwrap();
    assert_eq!(q.section_as::<crate::families::som::spec::SomSpec>().unwrap().iterations, 7);
    assert_eq!(
        crate::families::som::spec::cells(q.section_as().unwrap())[3].key(),
        "som/cube/dnsom/18x30/r0"
    );
}

/// A profile's changes are listed, and one that lowers a number or shortens a list reduces the
/// run (the reports' "not evidence" caveat); raising one does not.
#[test]
fn profile_changes_say_whether_the_run_is_reduced() {
    let q = L::parse("t.toml", SPEC, Some("quick")).unwrap();
    assert_eq!(
        q.spec.profile_changes(),
        vec![ProfileChange { key: "som.iterations".into(), value: "7".into(), reduces: true }]
    );
    assert!(q.spec.reduced() && !L::parse("t.toml", SPEC, None).unwrap().spec.reduced());
    let more = SPEC.replace("iterations = 7", "iterations = 700");
    let m = L::parse("t.toml", &more, Some("quick")).unwrap();
    assert!(!m.spec.reduced(), "{:?}", m.spec.profile_changes());
    // A shorter list reduces too.
    let text = "name = \"f\"\nmaster_seed = 1\n[fit]\ndatasets = [\"cube\", \"sphere\"]\ngrid = \"20x20\"\ncontrol_nets = [\"6x6\"]\nparameterisations = [\"uniform\"]\napproaches = [\"A\"]\n[profiles.quick.fit]\ndatasets = [\"cube\"]\n";
    assert!(L::parse("f.toml", text, Some("quick")).unwrap().spec.reduced());
}

/// A reading set's keys go through the same parsing and validation as the file's own values;
/// a key of a section the spec does not have is skipped.
#[test]
fn overrides_apply_after_the_profile_and_are_validated() {
    let text = "name = \"f\"\nmaster_seed = 1\n[fit]\ndatasets = [\"cube\"]\ngrid = \"20x20\"\ncontrol_nets = [\"6x6\"]\nparameterisations = [\"uniform\"]\napproaches = [\"A\"]\n[profiles.quick.fit]\nfairness = 0.5\n";
    let ov = |k: &str, v: toml::Value| Override { key: k.into(), value: v };
    let plain = L::parse("f.toml", text, Some("quick")).unwrap();
    let fit = plain.section_as::<crate::families::fit::spec::FitSpec>().unwrap();
    assert_eq!(
        (fit.knots, fit.error_a, fit.fairness),
        (crate::spline::KnotRule::Eq2_10, crate::spline::ErrorA::PerSurface, 0.5)
    );
    let set = [
        ov("fit.knots", "nurbs_book".into()),
        ov("fit.error_a", "nov_bottom".into()),
        ov("optimise.knots", "nurbs_book".into()),
    ];
    let s = L::parse_with("f.toml", text, Some("quick"), &set).unwrap();
    let fit = s.section_as::<crate::families::fit::spec::FitSpec>().unwrap();
    assert_eq!(
        (fit.knots, fit.error_a, fit.fairness),
        (crate::spline::KnotRule::NurbsBook, crate::spline::ErrorA::NovBottom, 0.5)
    );
    assert!(
        s.section_as::<crate::families::optimise::spec::OptimSpec>().is_none(),
        "a key of an absent section is skipped"
    );
    let e = L::parse_with("f.toml", text, None, &[ov("fit.knots", "9.69".into())])
        .unwrap_err()
        .to_string();
    assert!(e.contains("fit.knots") && e.contains("9.69"), "{e}");
    let e = L::parse_with("f.toml", text, None, &[ov("fit.fairness", toml::Value::Float(-1.0))])
        .unwrap_err()
        .to_string();
    assert!(e.contains("fit.fairness"), "{e}");
    // The parameterisation readings: defaults (Section 2.3.2's 0.8, Eq. 5.1/5.2 over all lines),
    // a set value reaches the fit options, and alpha outside (0, 1] is refused naming the key.
    let opts = plain.section_as::<crate::families::fit::spec::FitSpec>().unwrap().fit_options();
    assert_eq!(opts.param, crate::spline::ParamReading::default());
    assert_eq!(opts.param.exponential_alpha, 0.8);
    let set = [
        ov("fit.exponential_alpha", toml::Value::Float(0.9)),
        ov("fit.param_rows", "middle".into()),
    ];
    let s = L::parse_with("f.toml", text, None, &set).unwrap();
    let opts = s.section_as::<crate::families::fit::spec::FitSpec>().unwrap().fit_options();
    assert_eq!(
        opts.param,
        crate::spline::ParamReading {
            exponential_alpha: 0.9,
            rows: crate::spline::ParamRows::Middle
        }
    );
    for bad in [0.0, 1.5, f64::NAN] {
        let e = L::parse_with(
            "f.toml",
            text,
            None,
            &[ov("fit.exponential_alpha", toml::Value::Float(bad))],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("fit.exponential_alpha"), "{e}");
    }
    let e = L::parse_with("f.toml", text, None, &[ov("fit.param_rows", "first".into())])
        .unwrap_err()
        .to_string();
    assert!(e.contains("fit.param_rows") || e.contains("first"), "{e}");
    let e = L::parse_with("f.toml", text, None, &[ov("fit.colour", "red".into())])
        .unwrap_err()
        .to_string();
    assert!(e.contains("colour"), "{e}");
}

/// The Chapter 4 readings (`som.som3d_adjacency`, `som.spindle_profile`, `som.spindle_rings`):
/// defaults as before, settable by a reading set, and an unknown value names its key.
#[test]
fn som_readings_default_parse_and_name_their_key() {
    use crate::data::generators::{SpindleProfile, SpindleRings};
    use crate::som::LatticeAdjacency;
    let ov = |k: &str, v: &str| Override { key: k.into(), value: v.into() };
    let som = |s: &L| {
        let s = s.section_as::<crate::families::som::spec::SomSpec>().unwrap();
        (s.som3d_adjacency, s.spindle_profile, s.spindle_rings)
    };
    let plain = L::parse("t.toml", SPEC, None).unwrap();
    assert_eq!(som(&plain), (LatticeAdjacency::N6, SpindleProfile::Sin, SpindleRings::Cos));
    let set = [
        ov("som.som3d_adjacency", "layer"),
        ov("som.spindle_profile", "cone"),
        ov("som.spindle_rings", "uniform"),
    ];
    let s = L::parse_with("t.toml", SPEC, None, &set).unwrap();
    assert_eq!(som(&s), (LatticeAdjacency::Layer, SpindleProfile::Cone, SpindleRings::Uniform));
    for (key, bad) in
        [("som.som3d_adjacency", "n8"), ("som.spindle_profile", "tan"), ("som.spindle_rings", "z")]
    {
        let e = L::parse_with("t.toml", SPEC, None, &[ov(key, bad)]).unwrap_err().to_string();
        let leaf = key.rsplit('.').next().unwrap();
        assert!(e.contains(leaf) && e.contains(bad), "{e}");
    }
}

#[test]
fn exactly_one_experiment_section() {
    let none = "name = \"t\"\nmaster_seed = 1\n";
    let e = L::parse("t.toml", none, None).unwrap_err().to_string();
    assert!(
        e.contains("no experiment section")
            && e.contains("[som]")
            && e.contains("[rational_bezier]"),
        "{e}"
    );
    let two = format!("{SPEC}\n[rational_bezier]\nsurfaces = [\"surface1\"]\n");
    let e = L::parse("t.toml", &two, None).unwrap_err().to_string();
    assert!(e.contains("[som] and [rational_bezier]"), "{e}");
}

#[test]
fn unknown_key_names_line_and_key() {
    let bad = SPEC.replace("iterations = 100", "iteratons = 100");
    let e = L::parse("t.toml", &bad, None).unwrap_err().to_string();
    assert!(e.starts_with("t.toml:6:1:") && e.contains("iteratons"), "{e}");
    assert!(!e.contains('\n'));
}

#[test]
fn bad_values_name_their_key() {
    for (from, to, key) in [
        // A name is read into its type with the file: the error gives the line and column.
        ("\"som2d\", \"dnsom\"", "\"som2d\", \"kohonen\"", "t.toml:8:"),
        ("iterations = 100", "iterations = 0", "som.iterations"),
        ("\"10x10\", \"18x30\"", "\"2x2\"", "som.group[0].grids"),
        ("datasets = [\"cube\"]", "datasets = []", "som.datasets"),
    ] {
        let e = L::parse("t.toml", &SPEC.replace(from, to), None).unwrap_err().to_string();
        assert!(e.contains(key), "{e}");
    }
    let e = L::parse("t.toml", "name = \"x\"\nmaster_seed = -1\n", None).unwrap_err().to_string();
    assert!(e.starts_with("t.toml:2:"), "{e}");
    let e = L::parse("t.toml", SPEC, Some("full")).unwrap_err().to_string();
    assert!(e.contains("no profile `full`") && e.contains("quick"), "{e}");
}

/// A spec, a profile and a `--set` key written with a former section name (`[optim]`) give the
/// spec written with the present one (`[optimise]`): the same cells, seeds and values; an error
/// still names the line of the file as written.
#[test]
fn former_section_names_read_as_the_present_ones() {
    let new = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/ch6_same.toml"),
    )
    .unwrap();
    let old = new
        .replace("[optimise", "[optim")
        .replace("[profiles.quick.optimise", "[profiles.quick.optim");
    assert!(old.contains("[optim]\n") && old.contains("[profiles.quick.optim]"));
    let cli = |k: &str| CliOverrides { set: vec![format!("{k}.de.f=0.5")], sweep: vec![] };
    for (text, key) in [(&new, "optimise"), (&old, "optim"), (&new, "optim"), (&old, "optimise")] {
        let v =
            cli(key).variants::<crate::families::Section>("t.toml", text, Some("quick")).unwrap();
        let o = v[0].section_as::<crate::families::optimise::OptimSpec>().unwrap();
        let de = format!("{:?}", o.tables.get("de".parse().unwrap()));
        assert!(de.contains("f: 0.5") && o.generations == 100, "{key}: {de}");
        let want = cli(key).variants::<crate::families::Section>("t.toml", &new, Some("quick"));
        assert_eq!(
            crate::experiment::dry_run_listing(&v[0]),
            crate::experiment::dry_run_listing(&want.unwrap()[0])
        );
    }
    let plain = |t: &str| crate::experiment::dry_run_listing(&L::parse("t.toml", t, None).unwrap());
    assert_eq!(plain(&old), plain(&new));
    let bad = old.replacen("generations = 2000", "generations = \"x\"", 1);
    let line = old.lines().position(|l| l.starts_with("generations = 2000")).unwrap() + 1;
    let e = L::parse("t.toml", &bad, None).unwrap_err().to_string();
    assert!(e.contains(&format!("t.toml:{line}:")), "{e}");
}
