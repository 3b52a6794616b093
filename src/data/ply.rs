//! PLY reader: `format ascii 1.0`, `binary_little_endian 1.0` and `binary_big_endian 1.0`;
//! returns the x, y, z of the `vertex` element. Other vertex properties and other elements (faces
//! with list properties) are skipped. Every count in the header is checked against the bytes the
//! file has left before anything is allocated or looped over, and list counts must be of an
//! integer type (a count stored as a float would shift every later offset).

use super::DataError;
use crate::geom::Point3;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The value of `b` (exactly `size()` bytes), little or big endian.
    fn read(self, b: &[u8], big: bool) -> f64 {
        let mut x = [0u8; 8];
        x[..b.len()].copy_from_slice(b);
        if big {
            x[..b.len()].reverse();
        }
        match self {
            Scalar::I8 => x[0] as i8 as f64,
            Scalar::U8 => x[0] as f64,
            Scalar::I16 => i16::from_le_bytes([x[0], x[1]]) as f64,
            Scalar::U16 => u16::from_le_bytes([x[0], x[1]]) as f64,
            Scalar::I32 => i32::from_le_bytes([x[0], x[1], x[2], x[3]]) as f64,
            Scalar::U32 => u32::from_le_bytes([x[0], x[1], x[2], x[3]]) as f64,
            Scalar::F32 => f32::from_le_bytes([x[0], x[1], x[2], x[3]]) as f64,
            Scalar::F64 => f64::from_le_bytes(x),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Binary { big: bool },
}

#[derive(Debug, Clone)]
enum Property {
    Scalar { name: String, ty: Scalar },
    List { count: Scalar, item: Scalar },
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

fn err(ctx: String, msg: &str) -> DataError {
    DataError::parse(ctx, msg.to_string())
}

/// The header's text lines up to `end_header`, and the offset of the first byte after it.
fn header_lines(bytes: &[u8]) -> Result<(Vec<String>, usize), DataError> {
    let mut pos = 0;
    let mut lines = Vec::new();
    loop {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| err("header".into(), "no end_header line"))?;
        let line = String::from_utf8_lossy(&bytes[pos..pos + end]).trim().to_string();
        pos += end + 1;
        let done = line == "end_header";
        lines.push(line);
        if done {
            return Ok((lines, pos));
        }
    }
}

/// One `property` line of the header.
fn property(w: &[&str], ctx: String) -> Result<Property, DataError> {
    if w.get(1) == Some(&"list") {
        let count = w
            .get(2)
            .and_then(|t| Scalar::parse(t))
            .ok_or_else(|| err(ctx.clone(), "bad list count type"))?;
        if !count.is_integer() {
            return Err(err(
                ctx,
                "a list's count type must be an integer type (uchar, ushort, uint, ...)",
            ));
        }
        let item = w
            .get(3)
            .and_then(|t| Scalar::parse(t))
            .ok_or_else(|| err(ctx, "bad list item type"))?;
        Ok(Property::List { count, item })
    } else {
        let ty = w
            .get(1)
            .and_then(|t| Scalar::parse(t))
            .ok_or_else(|| err(ctx, "unknown property type"))?;
        Ok(Property::Scalar { name: w.get(2).unwrap_or(&"").to_string(), ty })
    }
}

/// The header's format and elements.
fn parse_header(lines: &[String]) -> Result<(Format, Vec<Element>), DataError> {
    if lines.first().map(|l| l.as_str()) != Some("ply") {
        return Err(err("line 1".into(), "not a PLY file (first line is not `ply`)"));
    }
    let mut binary = None;
    let mut elements: Vec<Element> = Vec::new();
    for (n, line) in lines.iter().enumerate().skip(1) {
        let ctx = format!("header line {}", n + 1);
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first().copied() {
            Some("format") => {
                binary = Some(match w.get(1).copied() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::Binary { big: false },
                    Some("binary_big_endian") => Format::Binary { big: true },
                    _ => return Err(err(ctx, "unknown format")),
                })
            }
            Some("element") => {
                let count: usize = w
                    .get(2)
                    .and_then(|c| c.parse().ok())
                    .ok_or_else(|| err(ctx.clone(), "element needs a name and a count"))?;
                if w.len() > 3 {
                    return Err(err(ctx, "element takes a name and a count only"));
                }
                elements.push(Element {
                    name: w.get(1).unwrap_or(&"").to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            Some("property") => {
                let el = elements
                    .last_mut()
                    .ok_or_else(|| err(ctx.clone(), "property before any element"))?;
                el.props.push(property(&w, ctx)?);
            }
            Some("comment") | Some("obj_info") | Some("end_header") | None => {}
            Some(other) => return Err(err(ctx, &format!("unknown header keyword `{other}`"))),
        }
    }
    let format = binary.ok_or_else(|| err("header".into(), "no format line"))?;
    Ok((format, elements))
}

/// Every element up to the vertices must fit in the `left` bytes after the header: at least its
/// scalar bytes plus its list counts' bytes (binary), or one value and a separator per property
/// (ascii), per item. Checked before anything is allocated or looped over.
fn check_sizes(elements: &[Element], format: Format, left: usize) -> Result<(), DataError> {
    let mut need: usize = 0;
    for el in elements {
        if el.props.is_empty() && el.count > 0 {
            return Err(err(format!("element {}", el.name), "has items but no properties"));
        }
        let per = match format {
            Format::Binary { .. } => el
                .props
                .iter()
                .map(|p| match p {
                    Property::Scalar { ty, .. } => ty.size(),
                    Property::List { count, .. } => count.size(),
                })
                .sum(),
            Format::Ascii => 2 * el.props.len().max(1),
        };
        need = per.checked_mul(el.count).and_then(|n| n.checked_add(need)).filter(|&n| n <= left).ok_or_else(|| {
            err(format!("element {}", el.name), &format!("the header says {} items, more than the {left} bytes after the header can hold", el.count))
        })?;
    }
    Ok(())
}

/// The vertices of a binary body: the elements before them skipped, item by item. `axes` are
/// the x, y, z properties' positions in the vertex element (the last of `elements`).
fn read_binary(
    bytes: &[u8],
    mut at: usize,
    elements: &[Element],
    axes: [usize; 3],
    big: bool,
) -> Result<Vec<Point3>, DataError> {
    let vi = elements.len() - 1;
    let mut points = Vec::with_capacity(elements[vi].count);
    for (e, el) in elements.iter().enumerate() {
        for k in 0..el.count {
            let mut vals = [0.0f64; 3];
            for (p, prop) in el.props.iter().enumerate() {
                let short =
                    || err(format!("{} {}", el.name, k + 1), "file ends inside this element");
                match prop {
                    Property::Scalar { ty, .. } => {
                        let b = bytes.get(at..at + ty.size()).ok_or_else(short)?;
                        if e == vi {
                            if let Some(a) = axes.iter().position(|&i| i == p) {
                                vals[a] = ty.read(b, big);
                            }
                        }
                        at += ty.size();
                    }
                    Property::List { count, item } => {
                        let b = bytes.get(at..at + count.size()).ok_or_else(short)?;
                        let n = count.read(b, big);
                        if n < 0.0 {
                            return Err(err(
                                format!("{} {}", el.name, k + 1),
                                &format!("negative list count {n}"),
                            ));
                        }
                        at += count.size() + n as usize * item.size();
                        if at > bytes.len() {
                            return Err(short());
                        }
                    }
                }
            }
            if e == vi {
                points.push(vals);
            }
        }
    }
    Ok(points)
}

/// The vertices of an ASCII body (one item per non-empty line; `header_lines` for the line
/// numbers of messages).
fn read_ascii(
    body: &[u8],
    header_lines: usize,
    elements: &[Element],
    axes: [usize; 3],
) -> Result<Vec<Point3>, DataError> {
    let vi = elements.len() - 1;
    let mut points = Vec::with_capacity(elements[vi].count);
    let text = String::from_utf8_lossy(body);
    let mut rows = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    for (e, el) in elements.iter().enumerate() {
        for k in 0..el.count {
            let (n, line) = rows.next().ok_or_else(|| {
                err(format!("{} {}", el.name, k + 1), "file ends before this element")
            })?;
            if e == vi {
                let ctx = format!("line {}", header_lines + n + 1);
                let w: Vec<&str> = line.split_whitespace().collect();
                let get = |p: usize| -> Result<f64, DataError> {
                    w.get(p)
                        .ok_or_else(|| err(ctx.clone(), "too few values"))?
                        .parse::<f64>()
                        .map_err(|_| err(ctx.clone(), &format!("`{}` is not a number", w[p])))
                };
                points.push([get(axes[0])?, get(axes[1])?, get(axes[2])?]);
            }
        }
    }
    Ok(points)
}

/// Parse a PLY file's bytes into the vertex positions.
pub fn parse_ply(bytes: &[u8]) -> Result<Vec<Point3>, DataError> {
    let (lines, pos) = header_lines(bytes)?;
    let (format, elements) = parse_header(&lines)?;
    let vi = elements
        .iter()
        .position(|e| e.name == "vertex")
        .ok_or_else(|| err("header".into(), "no vertex element"))?;
    let axis = |name: &str| {
        elements[vi]
            .props
            .iter()
            .position(|p| matches!(p, Property::Scalar { name: n, .. } if n == name))
            .ok_or_else(|| {
                err("header".into(), &format!("vertex element has no `{name}` property"))
            })
    };
    let axes = [axis("x")?, axis("y")?, axis("z")?];
    let upto = &elements[..=vi];
    check_sizes(upto, format, bytes.len() - pos)?;
    match format {
        Format::Binary { big } => read_binary(bytes, pos, upto, axes, big),
        Format::Ascii => read_ascii(&bytes[pos..], lines.len(), upto, axes),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const VERTS: [[f64; 3]; 4] = [
        [-0.0378297, 0.12794, 0.00447467],
        [1.5, -2.25, 3.0],
        [0.0, 0.0, 0.0],
        [1e-3, 2e-3, -3e-3],
    ];

    fn binary_ply() -> Vec<u8> {
        let mut b = b"ply\nformat binary_little_endian 1.0\ncomment made by a test\nelement vertex 4\nproperty float x\nproperty double y\nproperty float z\nproperty uchar red\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
        for v in VERTS {
            b.extend((v[0] as f32).to_le_bytes());
            b.extend(v[1].to_le_bytes());
            b.extend((v[2] as f32).to_le_bytes());
            b.push(200);
        }
        for face in [[0i32, 1, 2], [1, 2, 3]] {
            b.push(3);
            for i in face {
                b.extend(i.to_le_bytes());
            }
        }
        b
    }

    #[test]
    fn ascii_and_binary_agree() {
        let mut a = String::from("ply\nformat ascii 1.0\ncomment x\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n");
        for v in VERTS {
            a.push_str(&format!("{} {} {} 200\n", v[0] as f32, v[1], v[2] as f32));
        }
        a.push_str("3 0 1 2\n");
        let from_ascii = parse_ply(a.as_bytes()).unwrap();
        let from_binary = parse_ply(&binary_ply()).unwrap();
        assert_eq!(from_ascii.len(), 4);
        for (p, q) in from_ascii.iter().zip(&from_binary) {
            for k in 0..3 {
                assert!((p[k] - q[k]).abs() < 1e-6, "{p:?} {q:?}");
            }
        }
        assert_eq!(from_binary[1], [1.5, -2.25, 3.0]);
    }

    #[test]
    fn errors_name_the_place() {
        let bad = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 oops 1\n";
        let e = parse_ply(bad.as_bytes()).unwrap_err().to_string();
        assert!(e.contains("line 9") && e.contains("oops"), "{e}");
        let mut short = binary_ply();
        short.truncate(short.len() - 20);
        assert!(parse_ply(&short).is_ok(), "faces after the vertices are not needed");
        let mut cut = binary_ply();
        let header_end = cut.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        cut.truncate(header_end + 20);
        let e = parse_ply(&cut).unwrap_err().to_string();
        assert!(e.contains("vertex"), "{e}");
        let e =
            parse_ply(b"ply\nformat binary_big_endian 1.0\nend_header\n").unwrap_err().to_string();
        assert!(e.contains("no vertex element"), "{e}");
    }

    #[test]
    fn big_endian_reads_the_same_points() {
        let mut b = b"ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\nproperty double y\nproperty float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
        for v in VERTS {
            b.extend((v[0] as f32).to_be_bytes());
            b.extend(v[1].to_be_bytes());
            b.extend((v[2] as f32).to_be_bytes());
            b.push(200);
        }
        b.push(3);
        for i in [0i32, 1, 2] {
            b.extend(i.to_be_bytes());
        }
        assert_eq!(parse_ply(&b).unwrap(), parse_ply(&binary_ply()).unwrap());
    }

    #[test]
    fn counts_beyond_the_file_and_float_list_counts_are_refused_at_once() {
        let head = |fmt: &str, count: &str| {
            format!("ply\nformat {fmt} 1.0\nelement vertex {count}\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n")
        };
        for fmt in ["ascii", "binary_little_endian", "binary_big_endian"] {
            let e = parse_ply(head(fmt, "1000000000000").as_bytes()).unwrap_err().to_string();
            assert!(e.contains("1000000000000 items"), "{e}");
        }
        // An element of no properties and 10^18 items before the vertices: refused, not looped.
        let t = std::time::Instant::now();
        let e = parse_ply(b"ply\nformat binary_little_endian 1.0\nelement junk 1000000000000000000\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n123456789012").unwrap_err().to_string();
        assert!(t.elapsed().as_secs() < 1 && e.contains("junk"), "{e}");
        let e = parse_ply(b"ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list double int vertex_indices\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n").unwrap_err().to_string();
        assert!(e.contains("integer type"), "{e}");
    }
}
