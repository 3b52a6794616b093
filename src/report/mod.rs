//! Reports read only results: CSV tables, PNG pictures and REPORT.md.

pub mod ch4;
pub mod ch4_pictures;
pub mod ch5;
pub mod ch5_pictures;
pub mod ch6;
pub mod claims;
pub mod drift;
pub mod fsio;
pub mod html;
pub mod ioh;
pub mod markdown;
pub mod plots;
pub mod reference;
pub mod seed002;
pub mod seed003;
pub mod seed001;
pub mod seed004;
pub mod views3d;

use crate::experiment::spec::Spec;
use crate::experiment::Manifest;
use std::fmt::Write;

/// REPORT.md: a header naming the run, then the chapters' sections.
pub fn report_md(spec: &Spec, m: &Manifest, sections: &[String]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# somnurbs report: {}\n", spec.file.name);
    if !spec.file.description.is_empty() {
        let _ = writeln!(s, "{}\n", spec.file.description.trim());
    }
    let commit = if m.git_commit.is_empty() { "unknown".to_string() } else { format!("{}{}", &m.git_commit[..m.git_commit.len().min(12)], if m.git_dirty { " (dirty)" } else { "" }) };
    let _ = writeln!(
        s,
        "Spec `{}` (sha256 {}), profile `{}`, master seed {}, somnurbs {} at commit {}, {} on {} with {} thread(s): {} cells in {:.1} s wall, {:.1} s CPU in cells. Re-run: `somnurbs run {}{}`.\n",
        m.spec_path,
        &m.spec_sha256[..12],
        m.profile,
        m.master_seed,
        m.crate_version,
        commit,
        m.rustc,
        m.host,
        m.jobs,
        m.cells,
        m.wall_seconds,
        m.cpu_seconds_cells,
        m.spec_path,
        if m.profile == "default" { String::new() } else { format!(" --profile {}", m.profile) }
    );
    for sec in sections {
        s.push_str(sec);
        s.push('\n');
    }
    s
}

/// The distinct items in order of first appearance.
pub fn ordered<T: PartialEq + Clone>(items: impl Iterator<Item = T>) -> Vec<T> {
    let mut out = Vec::new();
    for x in items {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}
