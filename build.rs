//! Records the git commit, dirty flag and rustc version for run manifests.
use std::path::PathBuf;
use std::process::Command;

fn run(cmd: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(cmd).args(args).output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// The files whose change means another commit or another dirty flag: HEAD and the index (in the
/// git dir) and the branch HEAD names (in the common dir). Git is asked where they are, since in a
/// worktree `.git` is a file and the refs live in the main checkout's `.git`.
fn watched_git_files() -> Vec<PathBuf> {
    let Some(git_dir) = run("git", &["rev-parse", "--absolute-git-dir"]).map(PathBuf::from) else {
        return Vec::new();
    };
    let common = match run("git", &["rev-parse", "--git-common-dir"]).map(PathBuf::from) {
        Some(c) if c.is_absolute() => c,
        Some(c) => std::env::current_dir().map(|d| d.join(c)).unwrap_or_else(|_| git_dir.clone()),
        None => git_dir.clone(),
    };
    let mut files = vec![git_dir.join("HEAD"), git_dir.join("index"), common.join("packed-refs")];
    // A loose branch ref, else its folder (a commit on a packed branch creates the loose file).
    if let Some(branch) = run("git", &["rev-parse", "--symbolic-full-name", "HEAD"])
        .filter(|b| b.starts_with("refs/"))
    {
        let loose = common.join(&branch);
        files.push(if loose.exists() {
            loose
        } else {
            loose.parent().map(PathBuf::from).unwrap_or(loose)
        });
    }
    files.retain(|p| p.exists());
    files
}

fn main() {
    let commit = run("git", &["rev-parse", "HEAD"]).unwrap_or_default();
    // --no-optional-locks: a plain `git status` refreshes and rewrites the index, which is watched
    // below, so every next build would rerun this script and recompile the crate.
    let dirty =
        run("git", &["--no-optional-locks", "status", "--porcelain", "--untracked-files=no"])
            .map(|s| !s.is_empty())
            .unwrap_or(false);
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let rustc_version = run(&rustc, &["--version"]).unwrap_or_default();
    println!("cargo:rustc-env=SOMNURBS_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=SOMNURBS_GIT_DIRTY={dirty}");
    println!("cargo:rustc-env=SOMNURBS_RUSTC={rustc_version}");
    for p in watched_git_files() {
        println!("cargo:rerun-if-changed={}", p.display());
    }
    println!("cargo:rerun-if-changed=build.rs");
}
