//! `report.html`: a self-contained page beside REPORT.md, usable offline from the file system.
//!
//! It is built only from the results folder's own files: the REPORT.md text (rendered, its tables
//! sortable, columns of "ours (thesis)" cells split into two sortable columns, tables of six rows
//! or more filterable), every PNG of every report folder (those REPORT.md does not show sit in a
//! collapsed gallery per folder), and the 3-D views a run wrote as `views3d.js` (see
//! [`super::views3d`]). Folders with their own REPORT.md that the root REPORT.md does not include
//! as a `# <folder>` chapter (the readings' runs) become chapters of their own.
//!
//! The 3-D views use plotly.js (gl3d partial bundle), vendored in `vendor/` and copied once into
//! the results folder's `vendor/`; the page names it by a relative path and fetches nothing.

use super::views3d;
use crate::io::{read_text, write_atomic};
use anyhow::{Context, Result};
use std::collections::BTreeSet;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The page's file name.
pub(crate) const FILE: &str = "report.html";

/// The vendored plotting library: its path inside a results folder, and its bytes.
pub const PLOTLY_PATH: &str = "vendor/plotly-gl3d-4.1.1.min.js";
pub const PLOTLY_JS: &[u8] =
    include_bytes!("../../../vendor/plotly.js-gl3d-dist-min-4.1.1/plotly-gl3d.min.js");
const PLOTLY_LICENSE: &[u8] =
    include_bytes!("../../../vendor/plotly.js-gl3d-dist-min-4.1.1/LICENSE");
/// sha256 of [`PLOTLY_JS`] (the npm package plotly.js-gl3d-dist-min 4.1.1).
#[cfg(test)]
pub(crate) const PLOTLY_SHA256: &str =
    "aab04dcd9c103a92b18723f8c837712fe820f325d0bcd2421e415e8124a75b9f";

const PAGE_JS: &str = include_str!("page.js");
const PAGE_CSS: &str = include_str!("page.css");
/// First thing in the page: collect every error (a script that fails to load, an exception).
const ERROR_HOOK: &str = "window.somnurbsErrors = []; window.addEventListener('error', function (e) { window.somnurbsErrors.push(e.message ? e.message + ' at ' + (e.filename || '') + ':' + (e.lineno || '') : 'cannot load ' + (e.target && (e.target.src || e.target.href) || 'a resource')); }, true); window.addEventListener('unhandledrejection', function (e) { window.somnurbsErrors.push('unhandled rejection: ' + (e.reason && e.reason.message || e.reason)); });";

/// Write `root/report.html` (and `root/vendor/` when a folder has 3-D views); returns its path.
pub(crate) fn write(root: &Path) -> Result<PathBuf> {
    let page = build(root)?;
    if !page.view_folders.is_empty() {
        let js = root.join(PLOTLY_PATH);
        let fresh = crate::io::input::read(&js, crate::io::input::Kind::Text)
            .map(|b| b == PLOTLY_JS)
            .unwrap_or(false);
        if !fresh {
            write_atomic(&js, PLOTLY_JS)?;
            write_atomic(&root.join("vendor/plotly-LICENSE.txt"), PLOTLY_LICENSE)?;
        }
    }
    let path = root.join(FILE);
    write_atomic(&path, page.html.as_bytes())?;
    Ok(path)
}

struct Page {
    html: String,
    view_folders: Vec<String>,
}

/// A rendered chapter: its heading, id, level-2..4 headings (for the navigation) and body.
struct Chapter {
    title: String,
    id: String,
    toc: Vec<(usize, String, String)>,
    body: String,
}

/// Folders under `root` (relative, `/`-separated, "" for root) holding a REPORT.md, up to 3 deep.
fn report_folders(root: &Path) -> Result<Vec<String>> {
    let mut out = Vec::new();
    let mut stack = vec![(root.to_path_buf(), String::new(), 0usize)];
    while let Some((dir, rel, depth)) = stack.pop() {
        if dir.join("REPORT.md").is_file() {
            out.push(rel.clone());
        }
        if depth == 3 {
            continue;
        }
        let entries = std::fs::read_dir(&dir)
            .with_context(|| format!("cannot read folder {}", dir.display()))?;
        for e in entries {
            let e = e.with_context(|| format!("cannot read folder {}", dir.display()))?;
            let name = e.file_name().to_string_lossy().into_owned();
            if e.path().is_dir() && !name.starts_with('.') && name != "png" && name != "vendor" {
                stack.push((e.path(), join(&rel, &name), depth + 1));
            }
        }
    }
    out.sort();
    Ok(out)
}

fn join(folder: &str, name: &str) -> String {
    if folder.is_empty() {
        name.to_string()
    } else {
        format!("{folder}/{name}")
    }
}

/// Every PNG of a folder and of its `png/` sub-folder, relative to the root, sorted.
fn pictures(root: &Path, folder: &str) -> Result<Vec<String>> {
    let mut out = Vec::new();
    for sub in ["", "png"] {
        let rel = if sub.is_empty() { folder.to_string() } else { join(folder, sub) };
        let dir = root.join(&rel);
        if !dir.is_dir() {
            continue;
        }
        for e in std::fs::read_dir(&dir)
            .with_context(|| format!("cannot read folder {}", dir.display()))?
        {
            let e = e.with_context(|| format!("cannot read folder {}", dir.display()))?;
            let name = e.file_name().to_string_lossy().into_owned();
            if name.ends_with(".png") && e.path().is_file() {
                out.push(join(&rel, &name));
            }
        }
    }
    out.sort();
    Ok(out)
}

fn build(root: &Path) -> Result<Page> {
    let text = read_text(&root.join("REPORT.md"))?;
    let folders = report_folders(root)?;
    let mut ids = BTreeSet::new();
    let mut shown = BTreeSet::new();
    let mut view_folders = Vec::new();
    // The root REPORT.md, cut at its level-1 headings; a heading naming a report folder is that
    // folder's chapter.
    let mut parts: Vec<(String, Vec<&str>)> = Vec::new();
    for line in text.lines() {
        match line.strip_prefix("# ") {
            Some(h) => parts.push((h.trim().to_string(), Vec::new())),
            None if parts.is_empty() => parts.push((String::new(), vec![line])),
            None => parts.last_mut().expect("a part").1.push(line),
        }
    }
    let title = parts
        .first()
        .map(|p| p.0.clone())
        .filter(|t| !t.is_empty())
        .unwrap_or_else(|| "somnurbs report".into());
    let mut covered: Vec<String> = Vec::new();
    let mut chapters = Vec::new();
    for (k, (heading, lines)) in parts.iter().enumerate() {
        let folder = if k == 0 {
            Some(String::new())
        } else {
            folders.iter().find(|f| *f == heading && !f.is_empty()).cloned()
        };
        let mut ch = render_chapter(
            if heading.is_empty() { &title } else { heading },
            &lines.join("\n"),
            "",
            0,
            &mut ids,
            &mut shown,
        );
        if let Some(f) = folder.filter(|f| !f.is_empty()) {
            covered.push(f);
        }
        if k == 0 {
            covered.push(String::new());
        }
        chapters.push(ch_take(&mut ch));
    }
    // The other report folders (the readings' runs), each a chapter of its own.
    let mut uncovered: Vec<String> =
        folders.iter().filter(|f| !f.is_empty() && !covered.contains(f)).cloned().collect();
    // In the order the root REPORT.md names them (its table of specs), the rest after.
    uncovered.sort_by_key(|f| text.find(&format!("{f}/")).unwrap_or(usize::MAX));
    for f in &uncovered {
        let sub = read_text(&root.join(f).join("REPORT.md"))?;
        let body: Vec<&str> = sub.lines().skip_while(|l| !l.starts_with("# ")).skip(1).collect();
        let mut ch = render_chapter(f, &body.join("\n"), &format!("{f}/"), 1, &mut ids, &mut shown);
        covered.push(f.clone());
        chapters.push(ch_take(&mut ch));
    }
    // Each covered folder's remaining pictures and its 3-D views go at the end of its chapter
    // (the root's at the end of the first chapter).
    for (k, f) in covered.iter().enumerate() {
        let idx = if f.is_empty() {
            0
        } else {
            chapters.iter().position(|c| &c.title == f).unwrap_or(k.min(chapters.len() - 1))
        };
        let mut extra = String::new();
        if root.join(f).join(views3d::FILE).is_file() {
            let _ = write!(
                extra,
                "<h4 id=\"{0}\">3-D views</h4>\n<p class=\"note\">Drag to rotate, scroll to zoom, double-click to reset. Surfaces are evaluated on a dense parameter grid between the data points.</p>\n<div class=\"views3d\" data-folder=\"{1}\"><label>View <select></select></label><div class=\"plot3d\"></div></div>\n",
                unique_id(&mut ids, &format!("{f} 3-D views")),
                esc(f)
            );
            view_folders.push(f.clone());
            chapters[idx].toc.push((4, "3-D views".into(), extra_id(&extra)));
        }
        let rest: Vec<String> =
            pictures(root, f)?.into_iter().filter(|p| !shown.contains(p)).collect();
        if !rest.is_empty() {
            let _ = writeln!(extra, "<details class=\"gallery\"><summary>All pictures of <code>{}</code> ({})</summary><div class=\"grid\">", esc(if f.is_empty() { "." } else { f }), rest.len());
            for p in &rest {
                let name = p.rsplit('/').next().unwrap_or(p);
                let _ = writeln!(extra, "<figure><a href=\"{0}\"><img loading=\"lazy\" src=\"{0}\" alt=\"{1}\"></a><figcaption>{1}</figcaption></figure>", esc(p), esc(name));
            }
            extra.push_str("</div></details>\n");
        }
        chapters[idx].body.push_str(&extra);
    }
    let html = render_page(&title, &chapters, &view_folders);
    Ok(Page { html, view_folders })
}

/// The whole page: the navigation from the chapters' tables of contents, the chapters, the 3-D
/// views' scripts.
fn render_page(title: &str, chapters: &[Chapter], view_folders: &[String]) -> String {
    let mut html = String::new();
    let _ = write!(
        html,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>{}</title>\n<script>{}</script>\n<style>\n{}</style>\n</head>\n<body>\n<nav id=\"nav\"><p class=\"navtitle\">{}</p>\n<ol>\n",
        esc(title),
        ERROR_HOOK,
        PAGE_CSS,
        esc(title)
    );
    for c in chapters {
        let _ = write!(html, "<li><a href=\"#{}\">{}</a>", c.id, esc(&c.title));
        if !c.toc.is_empty() {
            html.push_str("<details><summary>sections</summary><ul>");
            for (level, t, id) in &c.toc {
                let _ = write!(
                    html,
                    "<li class=\"l{level}\"><a href=\"#{id}\">{}</a></li>",
                    inline(t, "")
                );
            }
            html.push_str("</ul></details>");
        }
        html.push_str("</li>\n");
    }
    html.push_str("</ol>\n<p class=\"navnote\">Built from this folder's files; opens offline. Click a table heading to sort.</p></nav>\n<main>\n");
    for c in chapters {
        let _ = write!(
            html,
            "<section class=\"chapter\">\n<h1 id=\"{}\">{}</h1>\n{}</section>\n",
            c.id,
            esc(&c.title),
            c.body
        );
    }
    html.push_str("<pre id=\"script-errors\" hidden></pre>\n</main>\n");
    if !view_folders.is_empty() {
        let _ = writeln!(html, "<script src=\"{PLOTLY_PATH}\"></script>");
        for f in view_folders {
            let _ = writeln!(
                html,
                "<script src=\"{}\" data-folder=\"{}\"></script>",
                esc(&join(f, views3d::FILE)),
                esc(f)
            );
        }
    }
    let _ = write!(html, "<script>\n{PAGE_JS}</script>\n</body>\n</html>\n");
    html
}

fn ch_take(c: &mut Chapter) -> Chapter {
    Chapter {
        title: std::mem::take(&mut c.title),
        id: std::mem::take(&mut c.id),
        toc: std::mem::take(&mut c.toc),
        body: std::mem::take(&mut c.body),
    }
}

fn extra_id(s: &str) -> String {
    s.split("id=\"").nth(1).and_then(|r| r.split('"').next()).unwrap_or("").to_string()
}

/// HTML-escape text.
fn esc(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            _ => o.push(c),
        }
    }
    o
}

fn unique_id(ids: &mut BTreeSet<String>, text: &str) -> String {
    let mut base: String = text
        .to_lowercase()
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    base = base.split('-').filter(|s| !s.is_empty()).collect::<Vec<_>>().join("-");
    if base.is_empty() {
        base = "s".into();
    }
    let mut id = base.clone();
    let mut k = 2;
    while !ids.insert(id.clone()) {
        id = format!("{base}-{k}");
        k += 1;
    }
    id
}

/// A link target relative to the root: relative targets get the folder prefix.
fn target(url: &str, prefix: &str) -> String {
    if url.contains(':') || url.starts_with('#') || url.starts_with('/') {
        url.to_string()
    } else {
        format!("{prefix}{url}")
    }
}

/// Inline Markdown: `code`, **bold**, [text](url), ![alt](src).
fn inline(s: &str, prefix: &str) -> String {
    let mut o = String::new();
    let mut rest = s;
    while let Some(c) = rest.chars().next() {
        if c == '`' {
            if let Some(end) = rest[1..].find('`') {
                let _ = write!(o, "<code>{}</code>", esc(&rest[1..1 + end]));
                rest = &rest[end + 2..];
                continue;
            }
        }
        if rest.starts_with("**") {
            if let Some(end) = rest[2..].find("**") {
                let _ = write!(o, "<strong>{}</strong>", inline(&rest[2..2 + end], prefix));
                rest = &rest[end + 4..];
                continue;
            }
        }
        let image = rest.starts_with("![");
        if image || c == '[' {
            let open = if image { 2 } else { 1 };
            if let Some(close) = rest.find("](") {
                if let Some(end) = rest[close + 2..].find(')') {
                    let label = &rest[open..close];
                    let url = target(&rest[close + 2..close + 2 + end], prefix);
                    if image {
                        let _ = write!(o, "<img src=\"{}\" alt=\"{}\">", esc(&url), esc(label));
                    } else {
                        let _ =
                            write!(o, "<a href=\"{}\">{}</a>", esc(&url), inline(label, prefix));
                    }
                    rest = &rest[close + 3 + end..];
                    continue;
                }
            }
        }
        o.push_str(&esc(&c.to_string()));
        rest = &rest[c.len_utf8()..];
    }
    o
}

fn cells(line: &str) -> Vec<String> {
    let t = line.trim().trim_start_matches('|').trim_end_matches('|');
    t.split('|').map(|c| c.trim().to_string()).collect()
}

/// `Some((ours, reference))` for a cell "a (b)"; `Some((a, ""))` for a plain number or "-".
fn split_pair(cell: &str) -> Option<(String, String)> {
    let plain = |s: &str| {
        let t = s.trim().trim_matches('*');
        t == "-" || t.trim_end_matches('%').parse::<f64>().is_ok()
    };
    if let Some(open) = cell.rfind(" (") {
        let (a, b) = (&cell[..open], cell[open + 2..].strip_suffix(')')?);
        return (plain(a) && plain(b)).then(|| (a.to_string(), b.to_string()));
    }
    plain(cell).then(|| (cell.to_string(), String::new()))
}

/// A Markdown table as a sortable (and, from six rows, filterable) HTML table.
fn table(lines: &[&str], prefix: &str, reference: &str) -> String {
    let header = cells(lines[0]);
    let body: Vec<Vec<String>> = lines.iter().skip(2).map(|l| cells(l)).collect();
    // Columns whose every cell is "ours (reference)" or a plain number, at least one a pair.
    let split: Vec<bool> = (0..header.len())
        .map(|c| {
            let col: Vec<&str> =
                body.iter().map(|r| r.get(c).map(String::as_str).unwrap_or("")).collect();
            c > 0
                && col.iter().all(|x| split_pair(x).is_some())
                && col.iter().any(|x| x.ends_with(')'))
        })
        .collect();
    let class = if body.len() >= 6 { "sortable filterable" } else { "sortable" };
    let mut o = format!("<div class=\"tablewrap\"><table class=\"{class}\">\n<thead><tr>");
    for (c, h) in header.iter().enumerate() {
        if split[c] {
            let _ = write!(o, "<th>{} <span class=\"who\">ours</span></th><th class=\"ref\">{} <span class=\"who\">{}</span></th>", inline(h, prefix), inline(h, prefix), esc(reference));
        } else {
            let _ = write!(o, "<th>{}</th>", inline(h, prefix));
        }
    }
    o.push_str("</tr></thead>\n<tbody>\n");
    for r in &body {
        o.push_str("<tr>");
        for c in 0..header.len() {
            let cell = r.get(c).map(String::as_str).unwrap_or("");
            if split[c] {
                let (a, b) = split_pair(cell).unwrap_or_default();
                let _ = write!(
                    o,
                    "<td>{}</td><td class=\"ref\">{}</td>",
                    inline(&a, prefix),
                    inline(&b, prefix)
                );
            } else {
                let _ = write!(o, "<td>{}</td>", inline(cell, prefix));
            }
        }
        o.push_str("</tr>\n");
    }
    o.push_str("</tbody></table></div>\n");
    o
}

/// Render one chapter's Markdown. `demote` lowers its headings (a sub-folder's REPORT.md).
fn render_chapter(
    title: &str,
    md: &str,
    prefix: &str,
    demote: usize,
    ids: &mut BTreeSet<String>,
    shown: &mut BTreeSet<String>,
) -> Chapter {
    let id = unique_id(ids, title);
    let mut toc = Vec::new();
    let mut o = String::new();
    let lines: Vec<&str> = md.lines().collect();
    let mut para: Vec<&str> = Vec::new();
    // The reference column's name: the paper for the other seeds' reports, else the thesis.
    let mut reference = "thesis";
    let flush = |para: &mut Vec<&str>, o: &mut String| {
        if !para.is_empty() {
            let _ = writeln!(o, "<p>{}</p>", inline(&para.join(" "), prefix));
            para.clear();
        }
    };
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let t = line.trim();
        if t.is_empty() {
            flush(&mut para, &mut o);
        } else if t == "---" {
            flush(&mut para, &mut o);
            o.push_str("<hr>\n");
        } else if t.starts_with('#') {
            flush(&mut para, &mut o);
            let hashes = t.chars().take_while(|&c| c == '#').count();
            let text = t[hashes..].trim();
            let level = (hashes + demote).clamp(2, 6);
            let hid = unique_id(ids, &format!("{title} {text}"));
            let _ = writeln!(o, "<h{level} id=\"{hid}\">{}</h{level}>", inline(text, prefix));
            if level <= 4 {
                toc.push((level, text.to_string(), hid));
            }
        } else if t.starts_with('|') {
            flush(&mut para, &mut o);
            let start = i;
            while i < lines.len() && lines[i].trim().starts_with('|') {
                i += 1;
            }
            if i - start >= 2 {
                o.push_str(&table(&lines[start..i], prefix, reference));
            }
            continue;
        } else if let Some(item) = t.strip_prefix("- ") {
            flush(&mut para, &mut o);
            o.push_str("<ul>\n");
            let mut item = item.to_string();
            i += 1;
            loop {
                let next = lines.get(i).map(|l| l.trim());
                match next {
                    Some(n)
                        if n.starts_with("- ")
                            || n.is_empty()
                            || n.starts_with('#')
                            || n.starts_with('|') =>
                    {
                        let _ = writeln!(o, "<li>{}</li>", inline(&item, prefix));
                        match n.strip_prefix("- ") {
                            Some(rest) => {
                                item = rest.to_string();
                                i += 1;
                            }
                            None => break,
                        }
                    }
                    Some(n) => {
                        item.push(' ');
                        item.push_str(n);
                        i += 1;
                    }
                    None => {
                        let _ = writeln!(o, "<li>{}</li>", inline(&item, prefix));
                        break;
                    }
                }
            }
            o.push_str("</ul>\n");
            continue;
        } else if t.starts_with("![") && t.ends_with(')') && !t[2..].contains("![") {
            flush(&mut para, &mut o);
            if let Some(close) = t.find("](") {
                let src = target(&t[close + 2..t.len() - 1], prefix);
                shown.insert(src.clone());
                let _ = writeln!(o, "<figure class=\"shown\"><a href=\"{0}\"><img src=\"{0}\" alt=\"{1}\"></a><figcaption>{1}</figcaption></figure>", esc(&src), esc(&t[2..close]));
            }
        } else {
            if t.contains("ours (paper)") || t.contains("paper's own") {
                reference = "paper";
            } else if t.contains("ours (thesis)") {
                reference = "thesis";
            }
            para.push(t);
        }
        i += 1;
    }
    flush(&mut para, &mut o);
    Chapter { title: title.to_string(), id, toc, body: o }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sha2::{Digest, Sha256};

    #[test]
    fn vendored_plotly_is_the_pinned_release() {
        assert_eq!(hex::encode(Sha256::digest(PLOTLY_JS)), PLOTLY_SHA256);
        let head = String::from_utf8_lossy(&PLOTLY_JS[..200]);
        assert!(head.contains("plotly.js (gl3d - minified) v4.1.1"), "{head}");
        assert!(String::from_utf8_lossy(PLOTLY_LICENSE).starts_with("MIT License"));
    }

    #[test]
    fn pairs_split_into_ours_and_reference() {
        let t = table(
            &["| data | QE |", "|---|---|", "| cube | 0.0085 (0.0023) |", "| sphere | 0.5 |"],
            "",
            "thesis",
        );
        assert!(t.contains("<td>0.0085</td><td class=\"ref\">0.0023</td>"), "{t}");
        assert!(t.contains("<td>0.5</td><td class=\"ref\"></td>"), "{t}");
        assert!(t.contains("QE <span class=\"who\">thesis</span>"), "{t}");
        // A column of words is left whole.
        let t = table(&["| claim | here |", "|---|---|", "| a (b) | 1/2 |"], "", "thesis");
        assert!(t.contains("<td>a (b)</td><td>1/2</td>"), "{t}");
    }

    #[test]
    fn inline_markdown_and_relative_links() {
        let s = inline("**holds** see [`x/`](x/REPORT.md) & ![p](png/a.png) <b>", "sub/");
        assert_eq!(s, "<strong>holds</strong> see <a href=\"sub/x/REPORT.md\"><code>x/</code></a> &amp; <img src=\"sub/png/a.png\" alt=\"p\"> &lt;b&gt;");
    }

    #[test]
    fn a_results_folder_becomes_one_page() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        std::fs::write(root.join("REPORT.md"), "# top\n\nIntro.\n\n## Claims\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n# spec1\n\n### Chapter\n\n- one\n- two\n\n![p.png](spec1/p.png)\n").unwrap();
        std::fs::create_dir_all(root.join("spec1/png")).unwrap();
        std::fs::write(root.join("spec1/REPORT.md"), "# spec1\n").unwrap();
        std::fs::write(root.join("spec1/p.png"), b"x").unwrap();
        std::fs::write(root.join("spec1/png/q.png"), b"x").unwrap();
        std::fs::create_dir_all(root.join("readings/r/spec1")).unwrap();
        std::fs::write(
            root.join("readings/r/spec1/REPORT.md"),
            "# somnurbs report: spec1\n\n### Chapter\n\n![z](z.png)\n",
        )
        .unwrap();
        std::fs::write(root.join("readings/r/spec1").join(views3d::FILE), "").unwrap();
        let path = write(root).unwrap();
        let html = std::fs::read_to_string(path).unwrap();
        assert!(html.contains("<h1 id=\"spec1\">spec1</h1>"), "{html}");
        assert!(html.contains("<h1 id=\"readings-r-spec1\">readings/r/spec1</h1>"), "{html}");
        assert!(html.contains("<img src=\"readings/r/spec1/z.png\""), "{html}");
        // p.png is shown in place, q.png only in the gallery.
        assert_eq!(html.matches("spec1/p.png").count(), 2, "{html}");
        assert!(html.contains("src=\"spec1/png/q.png\""), "{html}");
        assert!(html.contains("<script src=\"readings/r/spec1/views3d.js\" data-folder=\"readings/r/spec1\"></script>"), "{html}");
        assert!(html.contains("<li>one</li>\n<li>two</li>"), "{html}");
        assert_eq!(std::fs::read(root.join(PLOTLY_PATH)).unwrap(), PLOTLY_JS);
        assert!(
            !html.contains("http://") && !html.contains("https://"),
            "the page fetches nothing"
        );
    }
}
