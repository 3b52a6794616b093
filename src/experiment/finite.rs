//! Find a non-finite number anywhere in a serialisable value (a cell's record), by the path to
//! it (`0.qe`, `1[3].1`): a result with `inf` or `NaN` in it is an error naming the cell, never a
//! row (JSON would even turn it into `null`).

use serde::ser::{self, Serialize};
use std::fmt;

/// The path and value of the first non-finite float in `value`, if any.
pub(crate) fn first_non_finite<T: Serialize + ?Sized>(value: &T) -> Option<String> {
    let mut f = Finder { path: Vec::new() };
    match value.serialize(&mut f) {
        Err(Stop::Found(s)) => Some(s),
        _ => None,
    }
}

struct Finder {
    path: Vec<String>,
}

#[derive(Debug)]
enum Stop {
    Found(String),
    Other,
}

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stop::Found(s) => f.write_str(s),
            Stop::Other => f.write_str("not serialisable"),
        }
    }
}

impl std::error::Error for Stop {}

impl ser::Error for Stop {
    fn custom<M: fmt::Display>(_: M) -> Self {
        Stop::Other
    }
}

impl Finder {
    fn float(&self, v: f64) -> Result<(), Stop> {
        if v.is_finite() {
            return Ok(());
        }
        let at = self.path.concat();
        Err(Stop::Found(if at.is_empty() {
            format!("{v}")
        } else {
            format!("{} = {v}", at.trim_start_matches('.'))
        }))
    }

    fn at<T: Serialize + ?Sized>(&mut self, step: String, v: &T) -> Result<(), Stop> {
        self.path.push(step);
        let r = v.serialize(&mut *self);
        self.path.pop();
        r
    }
}

macro_rules! ok {
    ($($name:ident: $ty:ty),*) => {
        $(fn $name(self, _: $ty) -> Result<(), Stop> { Ok(()) })*
    };
}

impl<'a> ser::Serializer for &'a mut Finder {
    type Ok = ();
    type Error = Stop;
    type SerializeSeq = Seq<'a>;
    type SerializeTuple = Seq<'a>;
    type SerializeTupleStruct = Seq<'a>;
    type SerializeTupleVariant = Seq<'a>;
    type SerializeMap = Seq<'a>;
    type SerializeStruct = Seq<'a>;
    type SerializeStructVariant = Seq<'a>;

    ok!(serialize_bool: bool, serialize_i8: i8, serialize_i16: i16, serialize_i32: i32, serialize_i64: i64, serialize_u8: u8, serialize_u16: u16, serialize_u32: u32, serialize_u64: u64, serialize_char: char, serialize_str: &str, serialize_bytes: &[u8], serialize_unit_struct: &'static str);

    fn serialize_f32(self, v: f32) -> Result<(), Stop> {
        self.float(v as f64)
    }
    fn serialize_f64(self, v: f64) -> Result<(), Stop> {
        self.float(v)
    }
    fn serialize_none(self) -> Result<(), Stop> {
        Ok(())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> Result<(), Stop> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<(), Stop> {
        Ok(())
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, _: &'static str) -> Result<(), Stop> {
        Ok(())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        v: &T,
    ) -> Result<(), Stop> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(
        self,
        _: &'static str,
        _: u32,
        variant: &'static str,
        v: &T,
    ) -> Result<(), Stop> {
        self.at(format!(".{variant}"), v)
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Seq<'a>, Stop> {
        Ok(Seq { f: self, index: 0, bracket: true })
    }
    fn serialize_tuple(self, _: usize) -> Result<Seq<'a>, Stop> {
        Ok(Seq { f: self, index: 0, bracket: false })
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Seq<'a>, Stop> {
        Ok(Seq { f: self, index: 0, bracket: false })
    }
    fn serialize_tuple_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Seq<'a>, Stop> {
        Ok(Seq { f: self, index: 0, bracket: false })
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Seq<'a>, Stop> {
        Ok(Seq { f: self, index: 0, bracket: true })
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Seq<'a>, Stop> {
        Ok(Seq { f: self, index: 0, bracket: false })
    }
    fn serialize_struct_variant(
        self,
        _: &'static str,
        _: u32,
        _: &'static str,
        _: usize,
    ) -> Result<Seq<'a>, Stop> {
        Ok(Seq { f: self, index: 0, bracket: false })
    }
}

/// Any compound value: elements are named by index (`[k]` in sequences and maps, `.k` in
/// tuples) and fields by name.
struct Seq<'a> {
    f: &'a mut Finder,
    index: usize,
    bracket: bool,
}

impl Seq<'_> {
    fn element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), Stop> {
        let step =
            if self.bracket { format!("[{}]", self.index) } else { format!(".{}", self.index) };
        self.index += 1;
        self.f.at(step, v)
    }
}

macro_rules! compound {
    ($($tr:ident :: $m:ident),*) => {
        $(impl ser::$tr for Seq<'_> {
            type Ok = ();
            type Error = Stop;
            fn $m<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), Stop> {
                self.element(v)
            }
            fn end(self) -> Result<(), Stop> {
                Ok(())
            }
        })*
    };
}

compound!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field
);

impl ser::SerializeMap for Seq<'_> {
    type Ok = ();
    type Error = Stop;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, _: &T) -> Result<(), Stop> {
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), Stop> {
        self.element(v)
    }
    fn end(self) -> Result<(), Stop> {
        Ok(())
    }
}

macro_rules! named_fields {
    ($($tr:ident),*) => {
        $(impl ser::$tr for Seq<'_> {
            type Ok = ();
            type Error = Stop;
            fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, v: &T) -> Result<(), Stop> {
                self.f.at(format!(".{key}"), v)
            }
            fn end(self) -> Result<(), Stop> {
                Ok(())
            }
        })*
    };
}

named_fields!(SerializeStruct, SerializeStructVariant);

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize)]
    struct Row {
        name: String,
        qe: f64,
        te: Option<f64>,
    }

    #[test]
    fn names_the_first_non_finite_number() {
        let ok = (Row { name: "a".into(), qe: 1.0, te: None }, vec![(1u64, 2.0f64)]);
        assert_eq!(first_non_finite(&ok), None);
        let bad = (Row { name: "a".into(), qe: f64::INFINITY, te: None }, vec![(1u64, 2.0f64)]);
        assert_eq!(first_non_finite(&bad).unwrap(), "0.qe = inf");
        let bad = (
            Row { name: "a".into(), qe: 1.0, te: Some(f64::NAN) },
            vec![(1u64, 2.0f64), (3, f64::NEG_INFINITY)],
        );
        assert_eq!(first_non_finite(&bad).unwrap(), "0.te = NaN");
        let bad = (
            Row { name: "a".into(), qe: 1.0, te: None },
            vec![(1u64, 2.0f64), (3, f64::NEG_INFINITY)],
        );
        assert_eq!(first_non_finite(&bad).unwrap(), "1[1].1 = -inf");
        assert_eq!(first_non_finite(&vec![vec![0.0f32, f32::NAN]]).unwrap(), "[0][1] = NaN");
    }
}
