//! Former section names: a family whose spec section was renamed (`[optim]` is `[optimise]`)
//! keeps reading specs, `--set` keys and reading sets written with the old name, with a one-line
//! note. The text is renamed line by line, so serde's file:line:col messages still point into the
//! file as written; the seeds do not move (cell keys carry their own prefixes, and a variant's
//! changes as written).

use super::family::Families;
use std::borrow::Cow;
use std::collections::BTreeSet;
use std::sync::Mutex;

/// The (old, new) names of the renamed sections.
type Renamed = [(&'static str, &'static str)];

/// A dotted path (`optim.pso`, `profiles.quick.optim.ga`, a `--set` key) whose part `at` is a
/// former section name, with that part renamed, and the (old, new) pair; else `None`.
fn rename_at(
    path: &str,
    at: usize,
    renamed: &Renamed,
) -> Option<(String, (&'static str, &'static str))> {
    let mut segs: Vec<String> = path.split('.').map(String::from).collect();
    let seg = segs.get(at)?;
    let name = seg.trim();
    let &(old, new) = renamed.iter().find(|(old, _)| *old == name)?;
    segs[at] = seg.replacen(old, new, 1);
    Some((segs.join("."), (old, new)))
}

/// Where a table header's path names a family section: its first segment, or the third of
/// `profiles.NAME.SECTION`.
fn section_at(path: &str) -> usize {
    let segs: Vec<&str> = path.split('.').map(str::trim).collect();
    if segs.len() >= 3 && segs[0] == "profiles" {
        2
    } else {
        0
    }
}

/// One line with a former section name replaced; `table` is the current table's path (`None`
/// before the first header), updated by a header line.
fn rename_line(
    line: &str,
    table: &mut Option<String>,
    renamed: &Renamed,
    made: &mut Vec<(&'static str, &'static str)>,
) -> String {
    let trimmed = line.trim_start();
    let indent = &line[..line.len() - trimmed.len()];
    if trimmed.starts_with('[') {
        let (open, close) = if trimmed.starts_with("[[") { ("[[", "]]") } else { ("[", "]") };
        if let Some(end) = trimmed[open.len()..].find(close) {
            let path = &trimmed[open.len()..open.len() + end];
            let rest = &trimmed[open.len() + end..];
            let new = rename_at(path, section_at(path), renamed);
            *table = Some(new.as_ref().map_or_else(|| path.to_string(), |n| n.0.clone()));
            if let Some((new, pair)) = new {
                made.push(pair);
                return format!("{indent}{open}{new}{rest}");
            }
        }
        return line.to_string();
    }
    // A dotted key at the top level or in a profile's table names a section by its first part.
    let in_profile = table.as_deref().is_some_and(|t| {
        let segs: Vec<&str> = t.split('.').map(str::trim).collect();
        segs.len() == 2 && segs[0] == "profiles"
    });
    if table.is_none() || in_profile {
        if let Some((key, value)) = trimmed.split_once('=') {
            if !key.contains('#') && !key.contains('"') {
                if let Some((new, pair)) = rename_at(key, 0, renamed) {
                    made.push(pair);
                    return format!("{indent}{new}={value}");
                }
            }
        }
    }
    line.to_string()
}

/// A spec's text with every former section name replaced, line by line (line endings and line
/// count kept), and the renames it made (each once).
pub(crate) fn canonical_text<F: Families>(
    text: &str,
) -> (Cow<'_, str>, Vec<(&'static str, &'static str)>) {
    let renamed = F::renamed();
    if !renamed.iter().any(|(old, _)| text.contains(old)) {
        return (Cow::Borrowed(text), Vec::new());
    }
    let (mut table, mut made) = (None, Vec::new());
    let mut out = String::with_capacity(text.len() + 64);
    for line in text.split_inclusive('\n') {
        let (body, end) = match line.strip_suffix('\n') {
            Some(b) => match b.strip_suffix('\r') {
                Some(b) => (b, "\r\n"),
                None => (b, "\n"),
            },
            None => (line, ""),
        };
        out.push_str(&rename_line(body, &mut table, renamed, &mut made));
        out.push_str(end);
    }
    if made.is_empty() {
        return (Cow::Borrowed(text), made);
    }
    made.sort_unstable();
    made.dedup();
    (Cow::Owned(out), made)
}

/// A `--set`/`--sweep`/reading-set key with a former section name replaced (`optim.de.f` ->
/// `optimise.de.f`).
pub(crate) fn canonical_key<F: Families>(key: &str) -> Cow<'_, str> {
    match renamed_key::<F>(key) {
        Some((new, _)) => Cow::Owned(new),
        None => Cow::Borrowed(key),
    }
}

/// A key whose section is a former name: the key under the present name and the (old, new)
/// pair, for [`note`]; `None` for a key written with the present name.
pub(crate) fn renamed_key<F: Families>(
    key: &str,
) -> Option<(String, (&'static str, &'static str))> {
    rename_at(key, 0, F::renamed())
}

/// The message for one key written under both its former and its present section name (`optim.de.f`
/// and `optimise.de.f`): the two spellings and the rename, `None` when `a` and `b` are not
/// such a pair.
pub(crate) fn both_spellings<F: Families>(a: &str, b: &str) -> Option<String> {
    if a == b || canonical_key::<F>(a) != canonical_key::<F>(b) {
        return None;
    }
    // The former spelling first, whichever came first.
    let (former, present) = if renamed_key::<F>(a).is_some() { (a, b) } else { (b, a) };
    let (old, new) = renamed_key::<F>(former)?.1;
    Some(format!(
        "`{former}` and `{present}` are one key ([{old}] is the former name of [{new}]); give it \
         once"
    ))
}

/// Say once per file and former name that the name changed.
pub(crate) fn note(path: &str, made: &[(&'static str, &'static str)]) {
    static SAID: Mutex<BTreeSet<(String, &'static str)>> = Mutex::new(BTreeSet::new());
    let Ok(mut said) = SAID.lock() else { return };
    for &(old, new) in made {
        if said.insert((path.to_string(), old)) {
            crate::notice::emit(&format!(
                "somnurbs: note: {path}: [{old}] is now called [{new}]; the old name still works"
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RENAMED: &[(&str, &str)] = &[("optim", "optimise"), ("seed003", "cuckoo_bezier")];

    fn canon(text: &str) -> String {
        let (mut table, mut made) = (None, Vec::new());
        let lines: Vec<String> =
            text.lines().map(|l| rename_line(l, &mut table, RENAMED, &mut made)).collect();
        lines.join("\n")
    }

    #[test]
    fn headers_profiles_and_dotted_keys_are_renamed_line_for_line() {
        let text = "name = \"t\"\noptim.generations = 3\n[optim]   # c\ngrid = \"optim\"\n\
                    [optim.pso]\nk = 1\n[[optim.group]]\n[profiles.quick]\noptim.repeats = 2\n\
                    [profiles.quick.optim]\nrepeats = 1\n[profiles.optim]\n[optimiser]\n\
                    [seed003]\n[som]\noptim = 1\n";
        let want = "name = \"t\"\noptimise.generations = 3\n[optimise]   # c\ngrid = \"optim\"\n\
                    [optimise.pso]\nk = 1\n[[optimise.group]]\n[profiles.quick]\n\
                    optimise.repeats = 2\n[profiles.quick.optimise]\nrepeats = 1\n\
                    [profiles.optim]\n[optimiser]\n[cuckoo_bezier]\n[som]\noptim = 1";
        assert_eq!(canon(text), want);
        assert_eq!(canon(text).lines().count(), text.lines().count());
    }

    #[test]
    fn keys_are_renamed_by_their_first_part_only() {
        let renamed = rename_at("optim.de.f", 0, RENAMED);
        assert_eq!(renamed, Some(("optimise.de.f".to_string(), ("optim", "optimise"))));
        assert_eq!(rename_at("som.optim", 0, RENAMED), None);
        assert_eq!(rename_at("optimise.de.f", 0, RENAMED), None);
    }
}
