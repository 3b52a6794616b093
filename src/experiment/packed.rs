//! A compact float array for cell records: the exact little-endian bytes of each f64 in base64
//! (32 characters per 3-D point instead of about 60 as JSON numbers), so a resumed run restores
//! bit-identical values from a log a third the size.

use serde::{Deserialize, Deserializer, Serialize, Serializer};

const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Points written as `"f64le:<base64>"` (or, with `single`, `"f32le:<base64>"` of each value
/// as an f32: for values already rounded to single precision, half the size and still exact);
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

const TAG: &str = "f64le:";
const TAG32: &str = "f32le:";

fn encode(bytes: &[u8]) -> String {
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

fn decode(s: &str) -> Result<Vec<u8>, String> {
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
            return s.serialize_str(&format!("{TAG32}{}", encode(&bytes)));
        }
        let bytes: Vec<u8> = values.flat_map(|v| v.to_le_bytes()).collect();
        s.serialize_str(&format!("{TAG}{}", encode(&bytes)))
    }
}

impl<'de> Deserialize<'de> for PackedPoints {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let text = String::deserialize(d)?;
        let (body, width) = match (text.strip_prefix(TAG), text.strip_prefix(TAG32)) {
            (Some(b), _) => (b, 8),
            (_, Some(b)) => (b, 4),
            _ => return Err(D::Error::custom("packed points must start with f64le: or f32le:")),
        };
        let bytes = decode(body).map_err(D::Error::custom)?;
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
/// (`"f64le:<base64>"` of each f64's exact bytes, any length; a non-finite value makes it a plain
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
        s.serialize_str(&format!("{TAG}{}", encode(&bytes)))
    }
}

impl<'de> Deserialize<'de> for PackedFloats {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let text = String::deserialize(d)?;
        let body = text
            .strip_prefix(TAG)
            .ok_or_else(|| D::Error::custom("packed floats must start with f64le:"))?;
        let bytes = decode(body).map_err(D::Error::custom)?;
        if !bytes.len().is_multiple_of(8) {
            return Err(D::Error::custom(format!("{} bytes are not whole f64s", bytes.len())));
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
        assert!(json.starts_with("\"f64le:"), "{json}");
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
        assert!(json.starts_with("\"f64le:"), "{json}");
        let back: PackedPoints = serde_json::from_str(&json).unwrap();
        let bits = |p: &PackedPoints| -> Vec<u64> {
            p.points.iter().flatten().map(|v| v.to_bits()).collect()
        };
        assert_eq!(bits(&back), bits(&pts));
        // Single precision: the rounded values come back exactly, in half the characters.
        let one = PackedPoints::single(&pts.points);
        assert_eq!(one.points[0][0], f64::from(0.1f32));
        let json1 = serde_json::to_string(&one).unwrap();
        assert!(json1.starts_with("\"f32le:") && json1.len() < json.len() * 2 / 3 + 8, "{json1}");
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
}
