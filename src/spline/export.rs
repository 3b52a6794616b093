//! CAD and graphics export of fitted surfaces: IGES 5.3 (entity 128, rational B-spline surface
//! with all weights 1) in the fixed 80-column layout, a reader for it (to test the round trip),
//! and Wavefront OBJ meshes of the evaluated surfaces. Pure: functions return text.

use super::{BSplineSurface, SplineError};
use std::fmt::Write;

/// An IGES real: the shortest text that reads back to the same f64, with a decimal point and an
/// upper-case exponent (e.g. 0.5, 1.0E-7).
fn real(x: f64) -> String {
    let s = format!("{x:?}");
    match s.split_once('e') {
        Some((m, e)) => format!("{}{}E{e}", m, if m.contains('.') { "" } else { ".0" }),
        None => s,
    }
}

/// Hollerith string nH...
fn hollerith(s: &str) -> String {
    format!("{}H{s}", s.len())
}

/// Lines of one section, columns 1-72 text, 73 the letter, 74-80 the sequence number.
fn section_lines(text_lines: &[String], letter: char, out: &mut String) {
    for (k, l) in text_lines.iter().enumerate() {
        let _ = writeln!(out, "{:<72}{letter}{:>7}", l, k + 1);
    }
}

/// Pack delimited tokens into lines of at most `width` characters without splitting a token.
fn pack(tokens: &[String], width: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for (k, t) in tokens.iter().enumerate() {
        let delim = if k + 1 == tokens.len() { ';' } else { ',' };
        let piece = format!("{t}{delim}");
        if lines.last().map(|l| l.len() + piece.len() > width).unwrap_or(false) {
            lines.push(String::new());
        }
        lines.last_mut().unwrap().push_str(&piece);
    }
    lines
}

/// The length unit of exported coordinates: one of IGES 5.3's unit flags (global parameter 14,
/// with its name, parameter 15), or unknown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Units {
    /// Not known (a scan's numbers as they are, or a normalised box): written as flag 2 (MM), the
    /// flag CAD readers expect, and the start section says the flag is nominal. (Flag 3, a unit
    /// named in parameter 15, would need a name the reader knows, which "unknown" is not.)
    Unknown,
    /// A known unit: IGES flag and name.
    Flag(u8, &'static str),
}

impl std::str::FromStr for Units {
    type Err = String;
    fn from_str(s: &str) -> Result<Units, String> {
        Ok(match s {
            "unknown" => Units::Unknown,
            "in" => Units::Flag(1, "IN"),
            "mm" => Units::Flag(2, "MM"),
            "ft" => Units::Flag(4, "FT"),
            "m" => Units::Flag(6, "M"),
            "um" => Units::Flag(9, "UM"),
            "cm" => Units::Flag(10, "CM"),
            _ => return Err(format!("unknown unit `{s}` (unknown, mm, cm, m, um, in, ft)")),
        })
    }
}

impl Units {
    /// The sentence the IGES start section carries.
    pub(crate) fn describe(self) -> String {
        match self {
            Units::Unknown => format!("{}; the IGES unit flag 2 (MM) is nominal.", self.line()),
            Units::Flag(..) => format!("{}.", self.line()),
        }
    }

    /// `Units: ...` without the IGES flag (an OBJ comment).
    pub(crate) fn line(self) -> String {
        match self {
            Units::Unknown => "Units: unknown (the numbers as they are)".into(),
            Units::Flag(_, name) => format!("Units: {name}"),
        }
    }

    fn flag_and_name(self) -> (u8, &'static str) {
        match self {
            Units::Unknown => (2, "MM"),
            Units::Flag(f, n) => (f, n),
        }
    }
}

/// `text` in lines of at most `width` characters, broken at spaces (a longer word is cut).
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let chars: Vec<char> =
            word.chars().filter(|c| c.is_ascii() && !c.is_ascii_control()).collect();
        for piece in chars.chunks(width) {
            let piece: String = piece.iter().collect();
            if !line.is_empty() && line.len() + 1 + piece.len() > width {
                lines.push(std::mem::take(&mut line));
            }
            if !line.is_empty() {
                line.push(' ');
            }
            line.push_str(&piece);
        }
    }
    if !line.is_empty() || lines.is_empty() {
        lines.push(line);
    }
    lines
}

/// Days since 1970-01-01 as a civil (proleptic Gregorian) date (year, month, day): the
/// days-from-civil algorithm's inverse (H. Hinnant, "chrono-Compatible Low-Level Date
/// Algorithms", `civil_from_days`).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097); // [0, 146096]
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365; // [0, 399]
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100); // [0, 365]
    let mp = (5 * doy + 2) / 153; // [0, 11], March first
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

/// The latest second IGES 5.3's four-digit year can say (9999-12-31 23:59:59 UTC).
const MAX_IGES_SECONDS: i64 = 253_402_300_799;

/// IGES 5.3's date and time of a file (global parameter 18): `YYYYMMDD.HHNNSS`, UTC, of `unix`
/// seconds since 1970 (in [0, 9999-12-31 23:59:59]).
pub(crate) fn iges_date(unix: i64) -> Result<String, String> {
    if !(0..=MAX_IGES_SECONDS).contains(&unix) {
        return Err(format!(
            "{unix} seconds since 1970 is outside the years 1970-9999 an IGES date can say"
        ));
    }
    let (year, month, day) = civil_from_days(unix.div_euclid(86_400));
    let s = unix.rem_euclid(86_400);
    Ok(format!("{year:04}{month:02}{day:02}.{:02}{:02}{:02}", s / 3600, s / 60 % 60, s % 60))
}

/// When an export is generated, in seconds since 1970: `SOURCE_DATE_EPOCH` when set (the
/// reproducible-builds convention, so that a file can be made byte for byte again), else now.
pub(crate) fn generation_time() -> Result<i64, String> {
    match std::env::var("SOURCE_DATE_EPOCH") {
        Ok(v) if !v.is_empty() => v.trim().parse::<i64>().map_err(|_| {
            format!("SOURCE_DATE_EPOCH: `{v}` is not a whole number of seconds since 1970 (unset it, or set e.g. 1700000000)")
        }),
        _ => Ok(std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| i64::try_from(d.as_secs()).unwrap_or(i64::MAX))),
    }
}

/// IGES 5.3 text with one entity 128 per surface; `units` in the global section, and `notes`
/// (say, the coordinate frame) in the start section after the line naming the writer. `date` is
/// the file's generation time ([`iges_date`]); the maximum coordinate value (global parameter
/// 20) is the largest absolute coordinate of the control points.
pub(crate) fn write_iges(
    surfaces: &[(&str, &BSplineSurface)],
    units: Units,
    notes: &[String],
    date: &str,
) -> String {
    let mut start =
        vec!["somnurbs: cubic B-spline surfaces (entity 128, all weights 1)".to_string()];
    for note in notes.iter().cloned().chain([units.describe()]) {
        start.extend(wrap(&note, 72));
    }
    let (flag, unit_name) = units.flag_and_name();
    let max_coordinate = surfaces
        .iter()
        .flat_map(|(_, s)| s.control.iter().flatten())
        .fold(0.0f64, |m, &x| m.max(x.abs()));
    // The global section's parameters, 1 to 24 in IGES 5.3's order.
    let global_tokens: Vec<String> = vec![
        "1H,".into(),
        "1H;".into(),
        hollerith("somnurbs"),
        hollerith("surfaces.igs"),
        hollerith("somnurbs"),
        hollerith(env!("CARGO_PKG_VERSION")),
        "32".into(),
        "38".into(),
        "6".into(),
        "308".into(),
        "15".into(),
        hollerith("somnurbs"),
        "1.0".into(),
        flag.to_string(),
        hollerith(unit_name),
        "1".into(),
        "1.0".into(),
        hollerith(date), // 18: date and time of exchange file generation
        "1.0E-9".into(),
        real(max_coordinate), // 20: maximum coordinate value
        hollerith("somnurbs"),
        hollerith("somnurbs"),
        "11".into(),
        "0".into(),
    ];
    let global = pack(&global_tokens, 72);
    let mut directory = Vec::new();
    let mut params = String::new();
    let mut p_count = 0usize;
    for (e, (name, s)) in surfaces.iter().enumerate() {
        let de = 2 * e + 1;
        let (k1, k2) = (s.cn_x - 1, s.cn_y - 1);
        let mut t: Vec<String> = [
            "128",
            &k1.to_string(),
            &k2.to_string(),
            &s.p.to_string(),
            &s.q.to_string(),
            "0",
            "0",
            "1",
            "0",
            "0",
        ]
        .iter()
        .map(|x| x.to_string())
        .collect();
        t.extend(s.knots_u.iter().map(|&x| real(x)));
        t.extend(s.knots_v.iter().map(|&x| real(x)));
        t.extend(std::iter::repeat_n("1.0".to_string(), s.cn_x * s.cn_y));
        // Control points with the first (u) index varying fastest.
        for b in 0..s.cn_y {
            for a in 0..s.cn_x {
                t.extend(s.control[a * s.cn_y + b].iter().map(|&x| real(x)));
            }
        }
        t.extend([real(0.0), real(1.0), real(0.0), real(1.0)]);
        let lines = pack(&t, 64);
        let first = p_count + 1;
        for l in &lines {
            p_count += 1;
            let _ = writeln!(params, "{:<64} {:>7}P{:>7}", l, de, p_count);
        }
        let label: String = name
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .take(8)
            .collect::<String>()
            .to_uppercase();
        directory.push(format!(
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}",
            128, first, 0, 0, 0, 0, 0, 0, "00000000"
        ));
        directory.push(format!(
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}",
            128,
            0,
            0,
            lines.len(),
            0,
            "",
            "",
            label,
            e + 1
        ));
    }
    let mut out = String::new();
    section_lines(&start, 'S', &mut out);
    section_lines(&global, 'G', &mut out);
    section_lines(&directory, 'D', &mut out);
    out.push_str(&params);
    let _ = writeln!(
        out,
        "{:<72}T{:>7}",
        format!("S{:>7}G{:>7}D{:>7}P{:>7}", start.len(), global.len(), directory.len(), p_count),
        1
    );
    out
}

/// Read back every entity 128 of an IGES file written with `,` and `;` delimiters.
pub fn parse_iges_128(text: &str) -> Result<Vec<BSplineSurface>, SplineError> {
    let mut data: Vec<(usize, String)> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        if line.len() < 73 {
            return Err(SplineError::Iges(format!("line {} is shorter than 73 columns", n + 1)));
        }
        if &line[72..73] == "P" {
            let de: usize = line[65..72]
                .trim()
                .parse()
                .map_err(|_| SplineError::Iges(format!("line {}: bad DE pointer", n + 1)))?;
            match data.last_mut() {
                Some((d, s)) if *d == de => s.push_str(&line[..64]),
                _ => data.push((de, line[..64].to_string())),
            }
        }
    }
    let mut out = Vec::new();
    for (de, body) in data {
        let body = body.split(';').next().unwrap_or("");
        let v: Vec<&str> = body.split(',').map(|s| s.trim()).collect();
        let bad = |what: &str| SplineError::Iges(format!("entity at DE {de}: {what}"));
        let int = |k: usize| {
            v.get(k)
                .and_then(|s| s.parse::<usize>().ok())
                .ok_or_else(|| bad(&format!("field {k} is not an integer")))
        };
        if int(0)? != 128 {
            continue;
        }
        let (k1, k2, m1, m2) = (int(1)?, int(2)?, int(3)?, int(4)?);
        let num = |k: usize| {
            v.get(k)
                .and_then(|s| s.replace('D', "E").parse::<f64>().ok())
                .ok_or_else(|| bad(&format!("field {k} is not a number")))
        };
        let mut at = 10;
        let mut take = |n: usize| -> Result<Vec<f64>, SplineError> {
            let r = (at..at + n).map(num).collect::<Result<Vec<f64>, SplineError>>()?;
            at += n;
            Ok(r)
        };
        let knots_u = take(k1 + m1 + 2)?;
        let knots_v = take(k2 + m2 + 2)?;
        let weights = take((k1 + 1) * (k2 + 1))?;
        if weights.iter().any(|&w| w != 1.0) {
            return Err(bad("weights other than 1 are not read"));
        }
        let xyz = take(3 * (k1 + 1) * (k2 + 1))?;
        let (cn_x, cn_y) = (k1 + 1, k2 + 1);
        let mut control = vec![[0.0; 3]; cn_x * cn_y];
        for b in 0..cn_y {
            for a in 0..cn_x {
                let k = 3 * (b * cn_x + a);
                control[a * cn_y + b] = [xyz[k], xyz[k + 1], xyz[k + 2]];
            }
        }
        out.push(BSplineSurface { p: m1, q: m2, knots_u, knots_v, cn_x, cn_y, control });
    }
    Ok(out)
}

/// Wavefront OBJ: each surface evaluated on a uniform `samples_u x samples_v` parameter grid, as
/// an object of quads; `notes` are `#` comment lines after the one naming the writer.
pub(crate) fn write_obj(
    surfaces: &[(&str, &BSplineSurface)],
    samples_u: usize,
    samples_v: usize,
    notes: &[String],
) -> String {
    let (su, sv) = (samples_u.max(2), samples_v.max(2));
    let mut out = String::from("# somnurbs: evaluated cubic B-spline surfaces\n");
    for note in notes {
        for line in note.lines() {
            let _ = writeln!(out, "# {line}");
        }
    }
    let mut base = 1;
    for (name, s) in surfaces {
        let _ = writeln!(out, "o {name}");
        for i in 0..su {
            for j in 0..sv {
                let p = s.eval(i as f64 / (su - 1) as f64, j as f64 / (sv - 1) as f64);
                let _ = writeln!(out, "v {:?} {:?} {:?}", p[0], p[1], p[2]);
            }
        }
        for i in 0..su - 1 {
            for j in 0..sv - 1 {
                let a = base + i * sv + j;
                let _ = writeln!(out, "f {} {} {} {}", a, a + sv, a + sv + 1, a + 1);
            }
        }
        base += su * sv;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spline::knots::{knot_vector, KnotRule};
    use rand::{Rng, SeedableRng};

    fn surface(cn_x: usize, cn_y: usize, seed: u64) -> BSplineSurface {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let t =
            |n: usize| (0..n).map(|k| (k as f64 / (n - 1) as f64).powf(1.3)).collect::<Vec<f64>>();
        BSplineSurface {
            p: 3,
            q: 3,
            knots_u: knot_vector(&t(20), cn_x, 3, KnotRule::NurbsBook).unwrap(),
            knots_v: knot_vector(&t(30), cn_y, 3, KnotRule::NurbsBook).unwrap(),
            cn_x,
            cn_y,
            control: (0..cn_x * cn_y)
                .map(|_| [rng.gen::<f64>() * 100.0 - 50.0, rng.gen::<f64>() * 1e-6, rng.gen()])
                .collect(),
        }
    }

    #[test]
    fn iges_round_trip_re_evaluates_the_same_points() {
        let (a, b) = (surface(6, 18, 1), surface(16, 28, 2));
        let long = format!("Frame: the data's own coordinates, from {}", "/very/long".repeat(12));
        let text = write_iges(&[("bottom", &a), ("top", &b)], Units::Unknown, &[long], DATE);
        for (n, line) in text.lines().enumerate() {
            assert_eq!(line.len(), 80, "line {} is not 80 columns: {line:?}", n + 1);
        }
        let start: Vec<&str> = text.lines().filter(|l| &l[72..73] == "S").collect();
        assert!(start.len() >= 4 && start[1].starts_with("Frame: the data's own"), "{start:?}");
        assert!(start.iter().any(|l| l.contains("Units: unknown")), "{start:?}");
        assert!(text.lines().last().unwrap().starts_with(&format!("S{:>7}G", start.len())));
        // Units are global parameters 14 and 15.
        let global = |t: &str| -> String {
            t.lines().filter(|l| &l[72..73] == "G").map(|l| l[..72].trim_end()).collect()
        };
        assert!(global(&text).contains(",1.0,2,2HMM,"), "{text}");
        let inches = write_iges(&[("s", &a)], "in".parse().unwrap(), &[], DATE);
        assert!(global(&inches).contains(",1.0,1,2HIN,"), "{inches}");
        assert!(inches.contains("Units: IN."), "{inches}");
        assert!("yards".parse::<Units>().is_err());
        let back = parse_iges_128(&text).unwrap();
        assert_eq!(back.len(), 2);
        for (orig, read) in [(&a, &back[0]), (&b, &back[1])] {
            assert_eq!(orig, read);
            for s in 0..=10 {
                let (u, v) = (s as f64 / 10.0, (s as f64 / 10.0).sqrt());
                let (p, q) = (orig.eval(u, v), read.eval(u, v));
                for c in 0..3 {
                    assert!((p[c] - q[c]).abs() <= 1e-12);
                }
            }
        }
        assert_eq!(real(1e-7), "1.0E-7");
        assert_eq!(real(0.25), "0.25");
    }

    const DATE: &str = "20260101.000000";

    /// The global section's parameters (1-indexed: `g[18]` is parameter 18), split at its `,`
    /// delimiters (Hollerith strings read whole).
    fn global_parameters(text: &str) -> Vec<String> {
        let g: String =
            text.lines().filter(|l| &l[72..73] == "G").map(|l| l[..72].trim_end()).collect();
        let (mut out, mut rest) = (vec![String::new()], g.as_str());
        while !rest.is_empty() && !rest.starts_with(';') {
            let digits = rest.chars().take_while(char::is_ascii_digit).count();
            let len = if rest[digits..].starts_with('H') && digits > 0 {
                digits + 1 + rest[..digits].parse::<usize>().unwrap()
            } else {
                rest.find([',', ';']).unwrap_or(rest.len())
            };
            out.push(rest[..len].to_string());
            rest = &rest[len..];
            rest = rest.strip_prefix(',').unwrap_or(rest);
        }
        out
    }

    #[test]
    fn civil_dates_of_known_days() {
        for (unix, date) in [
            (0, "19700101.000000"),
            (951_782_400, "20000229.000000"),
            (1_700_000_000, "20231114.221320"),
            (1_709_251_199, "20240229.235959"),
            (4_107_542_400, "21000301.000000"),
            (MAX_IGES_SECONDS, "99991231.235959"),
        ] {
            assert_eq!(iges_date(unix).unwrap(), date, "{unix}");
        }
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert!(iges_date(-1).is_err() && iges_date(MAX_IGES_SECONDS + 1).is_err());
    }

    #[test]
    fn global_section_carries_the_date_and_the_largest_coordinate() {
        let (mut a, b) = (surface(6, 8, 1), surface(5, 5, 2));
        a.control[7] = [1.0, -286.25, 3.0];
        let text =
            write_iges(&[("bottom", &a), ("top", &b)], Units::Unknown, &[], "20240229.235959");
        let g = global_parameters(&text);
        assert_eq!(g.len(), 25, "{g:?}");
        assert_eq!((g[1].as_str(), g[2].as_str(), g[14].as_str()), ("1H,", "1H;", "2"));
        assert_eq!(g[18], "15H20240229.235959");
        assert_eq!(g[19], "1.0E-9");
        assert_eq!(g[20], "286.25");
        assert_eq!(g[23], "11");
    }

    #[test]
    fn obj_counts_and_points_on_the_surface() {
        let s = surface(5, 7, 3);
        let text = write_obj(&[("s", &s)], 11, 9, &["frame: the normalised unit box".into()]);
        assert_eq!(text.lines().nth(1), Some("# frame: the normalised unit box"));
        assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), 99);
        assert_eq!(text.lines().filter(|l| l.starts_with("f ")).count(), 80);
        let v: Vec<f64> = text.lines().find(|l| l.starts_with("v ")).unwrap()[2..]
            .split(' ')
            .map(|x| x.parse().unwrap())
            .collect();
        assert_eq!(v, s.eval(0.0, 0.0).to_vec());
    }
}
