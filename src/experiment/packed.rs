//! A compact float array for cell records: the exact little-endian bytes of each f64 in base64
//! (32 characters per 3-D point instead of about 60 as JSON numbers), so a resumed run restores
//! bit-identical values from a log a third the size. The bytes are written by byte plane (every
//! value's first byte, then every value's second, ...): the sign, exponent and leading mantissa
//! bytes of nearby values repeat, which the gzip-compressed log then holds in about a fifth less
//! (`f64bp:`, `f32bp:`); the value-by-value form (`f64le:`, `f32le:`) of older logs still reads.

use serde::{Deserialize, Deserializer, Serialize, Serializer};

const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Points written as `"f64bp:<base64>"` (or, with `single`, `"f32bp:<base64>"` of each value
/// as an f32: for values already rounded to single precision, half the size and still exact),
/// the bytes by byte plane ([`planes`]);
/// a non-finite coordinate is written as a plain number array instead, so the record's
/// finiteness check ([`super::finite`]) finds it by path.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct PackedPoints {
    pub(crate) points: Vec<[f64; 3]>,
    pub(crate) single: bool,
}

impl PackedPoints {
    /// Every value exactly (f64).
    #[cfg(test)]
    pub(crate) fn exact(points: Vec<[f64; 3]>) -> Self {
        PackedPoints { points, single: false }
    }

    /// Every value rounded to the nearest f32 (as an f64), written as f32.
    pub(crate) fn single(points: &[[f64; 3]]) -> Self {
        let r = |v: f64| f64::from(v as f32);
        PackedPoints {
            points: points.iter().map(|p| [r(p[0]), r(p[1]), r(p[2])]).collect(),
            single: true,
        }
    }
}

const TAG: &str = "f64bp:";
const TAG32: &str = "f32bp:";
/// The value-by-value form of older logs, read but no longer written.
const TAG_LE: &str = "f64le:";
const TAG32_LE: &str = "f32le:";

/// The little-endian bytes of values `width` bytes wide, by byte plane: every value's first byte,
/// then every value's second, and so on (a whole number of values).
fn planes(bytes: &[u8], width: usize) -> Vec<u8> {
    let n = bytes.len() / width;
    let mut out = vec![0; n * width];
    for (i, value) in bytes.chunks_exact(width).enumerate() {
        for (k, &b) in value.iter().enumerate() {
            out[k * n + i] = b;
        }
    }
    out
}

/// The inverse of [`planes`]: the values' little-endian bytes one value after another.
fn unplanes(planes: &[u8], width: usize) -> Vec<u8> {
    let n = planes.len() / width;
    let mut out = vec![0; n * width];
    for (k, plane) in planes.chunks_exact(n.max(1)).take(width).enumerate() {
        for (i, &b) in plane.iter().enumerate() {
            out[i * width + k] = b;
        }
    }
    out
}

/// The bytes of a packed string and the width of its values (8: f64, 4: f32), in value order;
/// `what` names the array in the error of an unknown tag.
fn unpack(text: &str, what: &str) -> Result<(Vec<u8>, usize), String> {
    let tagged = [(TAG, 8, true), (TAG32, 4, true), (TAG_LE, 8, false), (TAG32_LE, 4, false)];
    let Some((body, width, by_plane)) =
        tagged.iter().find_map(|&(tag, w, p)| text.strip_prefix(tag).map(|b| (b, w, p)))
    else {
        return Err(format!("packed {what} must start with f64bp:, f32bp:, f64le: or f32le:"));
    };
    let bytes = decode(body)?;
    if !bytes.len().is_multiple_of(width) {
        return Err(format!("{} bytes are not whole values of {width} bytes", bytes.len()));
    }
    Ok((if by_plane { unplanes(&bytes, width) } else { bytes }, width))
}

/// Standard base64 (RFC 4648, padded) of `bytes`.
pub(crate) fn encode(bytes: &[u8]) -> String {
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                s.push(ALPHABET[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// The bytes of standard base64 text ([`encode`]'s inverse).
pub(crate) fn decode(s: &str) -> Result<Vec<u8>, String> {
    let s = s.as_bytes();
    if !s.len().is_multiple_of(4) {
        return Err(format!("base64 length {} is not a multiple of 4", s.len()));
    }
    let mut out = Vec::with_capacity(s.len() / 4 * 3);
    for (q, quad) in s.chunks(4).enumerate() {
        let pad = quad.iter().rev().take_while(|&&c| c == b'=').count();
        if pad > 2 || (pad > 0 && (q + 1) * 4 != s.len()) {
            return Err("misplaced base64 padding".into());
        }
        let mut n = 0u32;
        for &c in &quad[..4 - pad] {
            let v = ALPHABET
                .iter()
                .position(|&a| a == c)
                .ok_or_else(|| format!("{:?} is not a base64 character", char::from(c)))?;
            n = (n << 6) | v as u32;
        }
        n <<= 6 * pad as u32;
        out.extend_from_slice(&[(n >> 16) as u8, (n >> 8) as u8, n as u8][..3 - pad]);
    }
    Ok(out)
}

impl Serialize for PackedPoints {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let values = self.points.iter().flatten();
        if values.clone().any(|v| !v.is_finite()) {
            return self.points.serialize(s);
        }
        if self.single {
            let bytes: Vec<u8> = values.flat_map(|&v| (v as f32).to_le_bytes()).collect();
            return s.serialize_str(&format!("{TAG32}{}", encode(&planes(&bytes, 4))));
        }
        let bytes: Vec<u8> = values.flat_map(|v| v.to_le_bytes()).collect();
        s.serialize_str(&format!("{TAG}{}", encode(&planes(&bytes, 8))))
    }
}

impl<'de> Deserialize<'de> for PackedPoints {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let text = String::deserialize(d)?;
        let (bytes, width) = unpack(&text, "points").map_err(D::Error::custom)?;
        if !bytes.len().is_multiple_of(3 * width) {
            return Err(D::Error::custom(format!(
                "{} bytes are not whole 3-D points",
                bytes.len()
            )));
        }
        let value = |b: &[u8]| -> f64 {
            if width == 8 {
                f64::from_le_bytes(b.try_into().unwrap_or([0; 8]))
            } else {
                f64::from(f32::from_le_bytes(b.try_into().unwrap_or([0; 4])))
            }
        };
        let points = bytes
            .chunks_exact(3 * width)
            .map(|p| [value(&p[..width]), value(&p[width..2 * width]), value(&p[2 * width..])])
            .collect();
        Ok(PackedPoints { points, single: width == 4 })
    }
}

/// A flat float array for cell records, written as [`PackedPoints`] writes its values
/// (`"f64bp:<base64>"` of the f64s' exact bytes by plane, any length; a non-finite value makes it a plain
/// number array, found by the finiteness check): for values that are not 3-D points (2-D
/// outlines, conic control points and weights).
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct PackedFloats(pub(crate) Vec<f64>);

impl Serialize for PackedFloats {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.0.iter().any(|v| !v.is_finite()) {
            return self.0.serialize(s);
        }
        let bytes: Vec<u8> = self.0.iter().flat_map(|v| v.to_le_bytes()).collect();
        s.serialize_str(&format!("{TAG}{}", encode(&planes(&bytes, 8))))
    }
}

impl<'de> Deserialize<'de> for PackedFloats {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let text = String::deserialize(d)?;
        let (bytes, width) = unpack(&text, "floats").map_err(D::Error::custom)?;
        if width != 8 {
            return Err(D::Error::custom("packed floats must be f64 (f64bp: or f64le:)"));
        }
        Ok(PackedFloats(
            bytes
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
                .collect(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648_test_vectors() {
        // RFC 4648, section 10.
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(encode(plain.as_bytes()), coded);
            assert_eq!(decode(coded).unwrap(), plain.as_bytes());
        }
        for bad in ["Zg=", "Z===", "Zg==Zg==", "Zm9*"] {
            assert!(decode(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn floats_round_trip_bit_for_bit() {
        let v = PackedFloats(vec![0.1, -2.5e-300, 1.0 / 3.0, -0.0, 5e-324]);
        let json = serde_json::to_string(&v).unwrap();
        assert!(json.starts_with("\"f64bp:"), "{json}");
        let back: PackedFloats = serde_json::from_str(&json).unwrap();
        let bits = |p: &PackedFloats| -> Vec<u64> { p.0.iter().map(|v| v.to_bits()).collect() };
        assert_eq!(bits(&back), bits(&v));
        assert!(
            crate::experiment::finite::first_non_finite(&PackedFloats(vec![f64::NAN])).is_some()
        );
        assert!(serde_json::from_str::<PackedFloats>("\"f64le:AAAA\"").is_err());
    }

    #[test]
    fn points_round_trip_bit_for_bit_and_non_finite_stays_visible() {
        let pts =
            PackedPoints::exact(vec![[0.1, -2.5e-300, 1.0 / 3.0], [f64::MIN_POSITIVE, -0.0, 7.0]]);
        let json = serde_json::to_string(&pts).unwrap();
        assert!(json.starts_with("\"f64bp:"), "{json}");
        let back: PackedPoints = serde_json::from_str(&json).unwrap();
        let bits = |p: &PackedPoints| -> Vec<u64> {
            p.points.iter().flatten().map(|v| v.to_bits()).collect()
        };
        assert_eq!(bits(&back), bits(&pts));
        // Single precision: the rounded values come back exactly, in half the characters.
        let one = PackedPoints::single(&pts.points);
        assert_eq!(one.points[0][0], f64::from(0.1f32));
        let json1 = serde_json::to_string(&one).unwrap();
        assert!(json1.starts_with("\"f32bp:") && json1.len() < json.len() * 2 / 3 + 8, "{json1}");
        let back1: PackedPoints = serde_json::from_str(&json1).unwrap();
        assert_eq!((bits(&back1), back1.single), (bits(&one), true));
        let bad = PackedPoints::exact(vec![[0.0, f64::NAN, 1.0]]);
        assert_eq!(
            crate::experiment::finite::first_non_finite(&bad).as_deref().map(|s| s.contains("NaN")),
            Some(true)
        );
        assert!(serde_json::from_str::<PackedPoints>("\"f64le:AAAA\"").is_err());
        assert!(serde_json::from_str::<PackedPoints>("\"xyz\"").is_err());
    }

    /// The value-by-value form of older logs (`f64le:`, `f32le:`) reads as before, to the same
    /// values as the byte-plane form written now.
    #[test]
    fn older_value_by_value_logs_still_read() {
        let values: [f64; 6] = [0.1, -2.5e-300, 1.0 / 3.0, 7.0, -0.0, 5e-324];
        let old64 = encode(&values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>());
        let floats: PackedFloats = serde_json::from_str(&format!("\"f64le:{old64}\"")).unwrap();
        assert_eq!(floats, PackedFloats(values.to_vec()));
        let points: PackedPoints = serde_json::from_str(&format!("\"f64le:{old64}\"")).unwrap();
        assert_eq!(points.points, vec![[0.1, -2.5e-300, 1.0 / 3.0], [7.0, -0.0, 5e-324]]);
        let old32 =
            encode(&values.iter().flat_map(|&v| (v as f32).to_le_bytes()).collect::<Vec<u8>>());
        let single: PackedPoints = serde_json::from_str(&format!("\"f32le:{old32}\"")).unwrap();
        assert_eq!((single.points[0][0], single.single), (f64::from(0.1f32), true));
        assert_eq!(serde_json::to_string(&single).unwrap().get(..7), Some("\"f32bp:"));
        assert!(serde_json::from_str::<PackedFloats>(&format!("\"f32bp:{old64}\"")).is_err());
    }

    /// By byte plane, a smooth array (a trained map's weights, an optimised net) compresses
    /// clearly smaller than value by value, and its planes come back in value order.
    #[test]
    fn byte_planes_compress_smaller_and_invert() {
        use std::io::Write as _;
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let points: Vec<[f64; 3]> = (0..2000)
            .map(|k| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let t = k as f64 / 2000.0;
                let noise = (state >> 11) as f64 / (1u64 << 53) as f64 * 1e-3;
                [t.sin() * 0.5 + noise, t.cos() * 0.5, 0.25 + t * t + noise]
            })
            .collect();
        let bytes: Vec<u8> = points.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        assert_eq!(unplanes(&planes(&bytes, 8), 8), bytes);
        assert_eq!(planes(&[1, 2, 3, 4, 5, 6, 7, 8], 4), vec![1, 5, 2, 6, 3, 7, 4, 8]);
        let gz = |text: &str| {
            let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::new(6));
            enc.write_all(text.as_bytes()).unwrap();
            enc.finish().unwrap().len()
        };
        let by_plane = gz(&serde_json::to_string(&PackedPoints::exact(points)).unwrap());
        let by_value = gz(&format!("\"f64le:{}\"", encode(&bytes)));
        assert!(by_plane * 10 < by_value * 9, "{by_plane} vs {by_value} bytes");
    }
}
