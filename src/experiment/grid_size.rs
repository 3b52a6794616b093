//! The size of a SOM grid or a control net, `nx x ny`, as specs and `fit --cn` write it:
//! "20x12", "20x20" (one spelling).

use serde::Deserialize;
use std::fmt;
use std::str::FromStr;

/// Grid or control-net size `nx x ny`, written "20x12".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GridSize {
    pub nx: usize,
    pub ny: usize,
}

impl fmt::Display for GridSize {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.nx, self.ny)
    }
}

impl FromStr for GridSize {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        // One spelling: digits, `x`, digits (a square is written in full, "20x20").
        let bad = || format!("`{s}` is not a grid size (write NXxNY, e.g. \"20x12\" or \"20x20\")");
        let num = |p: &str| {
            if p.is_empty() || !p.bytes().all(|b| b.is_ascii_digit()) {
                return Err(bad());
            }
            p.parse::<usize>().map_err(|_| bad())
        };
        match s.split_once('x') {
            Some((a, b)) => Ok(GridSize { nx: num(a)?, ny: num(b)? }),
            None => Err(bad()),
        }
    }
}

impl<'de> Deserialize<'de> for GridSize {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Text(String),
            Number(i64),
        }
        match Raw::deserialize(d)? {
            Raw::Text(s) => s.parse().map_err(serde::de::Error::custom),
            Raw::Number(n) => Err(serde::de::Error::custom(format!(
                "{n} is not a grid size (write NXxNY as a string, e.g. \"{n}x{n}\")"
            ))),
        }
    }
}

impl serde::Serialize for GridSize {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_sizes() {
        assert_eq!("20x12".parse::<GridSize>().unwrap(), GridSize { nx: 20, ny: 12 });
        assert_eq!("7x7".parse::<GridSize>().unwrap(), GridSize { nx: 7, ny: 7 });
        for other in ["20y12", "7", "20X12", " 20x12", "20 x 12", "+20x12", "x12", "20x"] {
            assert!(other.parse::<GridSize>().is_err(), "{other}");
        }
        #[derive(Debug, Deserialize)]
        struct S {
            #[allow(dead_code)]
            grid: GridSize,
        }
        let e = toml::from_str::<S>("grid = 18").unwrap_err().to_string();
        assert!(e.contains("write NXxNY as a string, e.g. \"18x18\""), "{e}");
        assert!(toml::from_str::<S>("grid = \"18x18\"").is_ok());
    }
}
