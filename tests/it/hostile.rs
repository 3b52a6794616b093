//! Issue 46: hostile inputs and folders. Nothing outside the given folder is written through a link
//! inside it (nor its lock opened through one); no reader blocks on a named pipe or reads a device
//! without end; no new result is started inside a finished one; a write that fails on a full disk
//! stops with exit 2 and `--resume` then finishes the run as if nothing happened.

use crate::common::*;
use std::path::Path;

fn som() -> String {
    SOM_TINY.replace("DATA", "sphere")
}

fn mkfifo(p: &Path) {
    let status = std::process::Command::new("mkfifo").arg(p).status().unwrap();
    assert!(status.success());
}

/// A command that must fail with exit 2, its last line of stderr the error holding every needle
/// (progress lines may come before it).
fn fails_last(c: &Case, args: &[&str], needles: &[&str]) {
    let out = c.run(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let last = err.trim_end().lines().last().unwrap_or("");
    assert_eq!(out.status.code(), Some(2), "{}", c.explain(args, &out));
    assert!(last.starts_with("somnurbs: error: "), "{}", c.explain(args, &out));
    for n in needles {
        assert!(last.contains(n), "error lacks {n:?}\n{}", c.explain(args, &out));
    }
}

/// A command that must be refused within a few seconds (a reader blocked on a pipe would hang).
fn refused_quickly(c: &Case, args: &[&str], needles: &[&str]) {
    let start = std::time::Instant::now();
    c.fails(args, needles);
    assert!(start.elapsed().as_secs() < 60, "{args:?} took {:?}", start.elapsed());
}

#[test]
fn a_lock_file_that_is_a_link_or_a_pipe_is_refused_and_its_target_kept() {
    let c = Case::new();
    c.write("a.toml", &som());
    c.write("outside/precious.txt", "keep me\n");
    std::fs::create_dir_all(c.path("o")).unwrap();
    std::os::unix::fs::symlink(c.path("outside/precious.txt"), c.path("o/.somnurbs.lock")).unwrap();
    c.fails(&["run", "a.toml", "--out", "o"], &[".somnurbs.lock", "symbolic link"]);
    assert_eq!(std::fs::read_to_string(c.path("outside/precious.txt")).unwrap(), "keep me\n");
    // drift --accept takes the baseline's lock: the same refusal, the same file kept.
    c.ok(&["run", "a.toml", "--out", "cur"]);
    c.fails(&["drift", "o", "cur", "--accept"], &["symbolic link"]);
    assert_eq!(std::fs::read_to_string(c.path("outside/precious.txt")).unwrap(), "keep me\n");
    // A pipe as the lock: the writer refuses and a reader (drift) does not wait on it.
    std::fs::create_dir_all(c.path("p")).unwrap();
    mkfifo(&c.path("p/.somnurbs.lock"));
    refused_quickly(&c, &["run", "a.toml", "--out", "p"], &["named pipe", ".somnurbs.lock"]);
    c.ok(&["run", "a.toml", "--out", "fin"]);
    std::fs::create_dir_all(c.path("fin/x")).unwrap();
    mkfifo(&c.path("fin/x/.somnurbs.lock"));
    refused_quickly(&c, &["drift", "cur", "fin"], &["named pipe"]);
}

#[test]
fn a_resume_never_writes_through_a_link_inside_the_folder() {
    let c = Case::new();
    c.write("a.toml", &som().replace("[som]", "[som]\npictures = true"));
    c.ok(&["run", "a.toml", "--out", "o"]);
    // Make the finished run an unfinished one whose png/ is a link to an outside folder.
    std::fs::remove_file(c.path("o/manifest.toml")).unwrap();
    std::fs::remove_dir_all(c.path("o/png")).unwrap();
    std::fs::create_dir_all(c.path("outside")).unwrap();
    std::os::unix::fs::symlink(c.path("outside"), c.path("o/png")).unwrap();
    fails_last(
        &c,
        &["run", "a.toml", "--out", "o", "--resume"],
        &["png", "symbolic link", "inside"],
    );
    assert_eq!(std::fs::read_dir(c.path("outside")).unwrap().count(), 0, "wrote outside");
    // The cell log as a link to an outside file: neither appended to nor cut.
    let c2 = Case::new();
    c2.write("a.toml", &som());
    c2.ok(&["run", "a.toml", "--out", "o"]);
    std::fs::remove_file(c2.path("o/manifest.toml")).unwrap();
    c2.write("outside.jsonl", "{\"torn");
    std::os::unix::fs::symlink(c2.path("outside.jsonl"), c2.path("o/cells.jsonl")).unwrap();
    fails_last(
        &c2,
        &["run", "a.toml", "--out", "o", "--resume"],
        &["cells.jsonl", "symbolic link"],
    );
    assert_eq!(std::fs::read_to_string(c2.path("outside.jsonl")).unwrap(), "{\"torn");
}

#[test]
fn pipes_devices_and_folders_as_inputs_are_refused_without_waiting() {
    let c = Case::new();
    mkfifo(&c.path("grid.csv"));
    refused_quickly(
        &c,
        &["fit", "--grid", "grid.csv", "--cn", "4x4", "--out", "f"],
        &["grid.csv", "named pipe", "not a regular file"],
    );
    refused_quickly(
        &c,
        &["fit", "--grid", "/dev/zero", "--cn", "4x4", "--out", "f"],
        &["/dev/zero", "device"],
    );
    // A map whose frame file is a pipe.
    c.write("m.csv", &crate::robust::small_grid(6));
    mkfifo(&c.path("m.frame.toml"));
    refused_quickly(
        &c,
        &["fit", "--grid", "m.csv", "--cn", "4x4", "--out", "f"],
        &["m.frame.toml", "named pipe"],
    );
    // A spec and a data file that are not regular files.
    mkfifo(&c.path("spec.toml"));
    refused_quickly(&c, &["run", "spec.toml", "--out", "o"], &["spec.toml", "named pipe"]);
    mkfifo(&c.path("pts.xyz"));
    c.write("d.toml", &SOM_TINY.replace("DATA", "pts.xyz"));
    refused_quickly(&c, &["run", "d.toml", "--out", "o"], &["pts.xyz", "named pipe"]);
    refused_quickly(&c, &["datasets", "show", "pts.xyz"], &["pts.xyz", "named pipe"]);
    std::os::unix::fs::symlink("/dev/zero", c.path("zero.xyz")).unwrap();
    refused_quickly(&c, &["datasets", "show", "zero.xyz"], &["zero.xyz", "device"]);
    std::fs::create_dir_all(c.path("adir.xyz")).unwrap();
    refused_quickly(&c, &["datasets", "show", "adir.xyz"], &["adir.xyz", "folder"]);
    assert!(!c.path("o").exists() && !c.path("f").exists(), "a refused command wrote a folder");
}

#[test]
fn a_cell_log_that_inflates_without_bound_is_refused_naming_it_and_the_limit() {
    use std::io::Write;
    let c = Case::new();
    c.write("a.toml", &som());
    c.ok(&["run", "a.toml", "--out", "o"]);
    std::fs::remove_file(c.path("o/manifest.toml")).unwrap();
    // 600 MiB of one line compresses to well under a MiB.
    let f = std::fs::File::create(c.path("o/cells.jsonl.gz")).unwrap();
    let mut gz = flate2::write::GzEncoder::new(f, flate2::Compression::fast());
    let chunk = vec![b'x'; 1 << 20];
    for _ in 0..600 {
        gz.write_all(&chunk).unwrap();
    }
    gz.finish().unwrap();
    let start = std::time::Instant::now();
    c.fails(
        &["run", "a.toml", "--out", "o", "--resume"],
        &["cells.jsonl.gz", "over the limit", "SOMNURBS_MAX_INPUT_MIB"],
    );
    assert!(start.elapsed().as_secs() < 120);
}

#[test]
fn no_new_result_starts_inside_a_finished_one() {
    let c = Case::new();
    c.write("a.toml", &som());
    c.write("s.toml", SPEC);
    c.ok(&["run", "a.toml", "--out", "fin"]);
    let before = snapshot(&c.path("fin"));
    c.fails(&["run", "a.toml", "--out", "fin/sub"], &["fin/sub", "inside the result folder"]);
    c.fails(&["run", "a.toml", "--out", "fin/a/b"], &["inside the result folder"]);
    c.write("g.csv", &crate::robust::small_grid(6));
    c.fails(
        &["fit", "--grid", "g.csv", "--cn", "4x4", "--out", "fin/x"],
        &["inside the result folder"],
    );
    c.ok(&["run", "s.toml", "--out", "s1", "--shard", "1/2"]);
    c.ok(&["run", "s.toml", "--out", "s2", "--shard", "2/2"]);
    c.fails(&["merge", "s1", "s2", "--out", "s1/merged"], &["inside the result folder", "s1"]);
    c.fails(
        &["reproduce", "--profile", "quick", "--out", "fin/plan"],
        &["inside the result folder"],
    );
    assert!(snapshot(&c.path("fin")) == before, "the finished folder changed");
    assert!(!c.path("s1/merged").exists());
}

/// A full disk: a 256 KiB tmpfs (mounted only where the tests run as root and may mount; else the
/// test says why it skips). The run stops with exit 2 naming what it could not write, and a
/// `--resume` on a roomy copy of the folder finishes it with the tables of an uninterrupted run.
#[test]
fn a_full_disk_stops_the_run_and_resume_finishes_it() {
    let c = Case::new();
    let mnt = c.path("small");
    std::fs::create_dir_all(&mnt).unwrap();
    let mounted = std::process::Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=256k", "tmpfs"])
        .arg(&mnt)
        .output();
    if !mounted.is_ok_and(|o| o.status.success()) {
        eprintln!("skipped: cannot mount a small tmpfs here (needs root and mount rights)");
        return;
    }
    struct Unmount(std::path::PathBuf);
    impl Drop for Unmount {
        fn drop(&mut self) {
            let _ = std::process::Command::new("umount").arg(&self.0).status();
        }
    }
    let _guard = Unmount(mnt.clone());
    c.write("s.toml", SPEC);
    fails_last(&c, &["run", "s.toml", "--out", "small/o"], &["small/o", "No space left"]);
    assert!(!c.path("small/o/manifest.toml").exists());
    // Copy the unfinished folder to roomy disk and finish it there.
    let copied = std::process::Command::new("cp")
        .args(["-a"])
        .arg(c.path("small/o"))
        .arg(c.path("o"))
        .status()
        .unwrap();
    assert!(copied.success());
    c.ok(&["run", "s.toml", "--out", "o", "--resume"]);
    c.ok(&["run", "s.toml", "--out", "whole"]);
    assert!(same_tables(&c.path("whole"), &c.path("o")) > 0);
}

#[test]
fn an_interrupted_accept_leaves_nothing_the_next_one_keeps() {
    let c = Case::new();
    c.write("a.toml", &som());
    c.ok(&["run", "a.toml", "--out", "cur"]);
    c.ok(&["drift", "base", "cur", "--accept"]);
    // What a kill during the swap leaves beside the baseline: a staged folder of a dead process.
    c.write("base/../.base.999999999.0.staged/runs.csv", "x\n1\n");
    let out = c.ok(&["drift", "base", "cur", "--accept"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("removed 1 folder(s) an interrupted drift --accept left"), "{err}");
    assert!(!c.path(".base.999999999.0.staged").exists());
}
