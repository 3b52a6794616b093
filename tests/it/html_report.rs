//! report.html of a `run` folder: written beside REPORT.md with the vendored plotting library and
//! the 3-D views of a Chapter 5 run; and, when chromium is installed, opened in it headless by
//! `scripts/check_report_html.sh` (CI installs chromium and runs the same check on the quick
//! reproduction; without chromium this part is skipped with a printed reason).

use crate::common::*;
use std::path::Path;

const FITS: &str = r#"
name = "fits"
master_seed = 11
[fit]
datasets = ["sphere"]
grid = "20x20"
control_nets = ["6x6", "12x12"]
parameterisations = ["uniform", "chord_length"]
approaches = ["A", "B"]
maps = "ch4/maps"
pictures = true
"#;

#[test]
fn a_chapter_5_run_writes_a_self_contained_report_html() {
    let c = Case::new();
    c.write("maps.toml", CH4_FOR_FIT);
    c.ok(&["run", "maps.toml", "--out", "ch4"]);
    c.write("fits.toml", FITS);
    c.ok(&["run", "fits.toml", "--out", "out"]);
    let out = c.path("out");
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let views = std::fs::read_to_string(out.join("views3d.js")).unwrap();
    assert!(views.contains("sphere: DNSOM map 20x20"), "{}", &views[..200.min(views.len())]);
    assert!(
        views.contains("sphere: A surfaces furthest from the data")
            && views.contains("sphere: B surfaces furthest from the data")
    );
    let js = std::fs::read(out.join(somnurbs::report::PLOTLY_PATH)).unwrap();
    assert_eq!(js, somnurbs::report::PLOTLY_JS, "the vendored library is copied as it is");
    assert!(html.contains(&format!("<script src=\"{}\"></script>", somnurbs::report::PLOTLY_PATH)));
    assert!(html.contains("<script src=\"views3d.js\" data-folder=\"\"></script>"));
    assert!(html.contains("class=\"sortable"), "no sortable table");
    // Every picture of the folder is on the page, and nothing is fetched from elsewhere.
    for p in walk(&out).iter().filter(|p| p.extension().is_some_and(|e| e == "png")) {
        let rel = p.strip_prefix(&out).unwrap().display().to_string();
        assert!(html.contains(&format!("src=\"{rel}\"")), "{rel} is not on the page");
    }
    assert!(!html.contains("http://") && !html.contains("https://"));

    let Some(browser) = ["chromium", "chromium-browser"].iter().find(|b| {
        std::process::Command::new(b).arg("--version").output().is_ok_and(|o| o.status.success())
    }) else {
        println!("skipped the headless-browser half: chromium is not installed (scripts/install_chromium.sh installs it; CI does)");
        return;
    };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/check_report_html.sh");
    let run = std::process::Command::new("bash")
        .arg(&script)
        .arg(&out)
        .env("CHROMIUM", browser)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success() && said.contains("1 passed, 0 failed"),
        "{said}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
}
