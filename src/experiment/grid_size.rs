//! The size of a SOM grid or a control net, `nx x ny`, as specs write it ("20x12", or "20"
//! for 20x20).

use serde::Deserialize;
use std::fmt;
use std::str::FromStr;

/// Grid or control-net size `nx x ny`, written "20x12" (or "20" for 20x20).
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
        let bad = || format!("`{s}` is not a grid size (write NXxNY, e.g. \"20x12\")");
        let parts: Vec<&str> = s.trim().split(['x', 'X']).collect();
        let num = |p: &str| p.trim().parse::<usize>().map_err(|_| bad());
        match parts.as_slice() {
            [n] => {
                let n = num(n)?;
                Ok(GridSize { nx: n, ny: n })
            }
            [a, b] => Ok(GridSize { nx: num(a)?, ny: num(b)? }),
            _ => Err(bad()),
        }
    }
}

impl<'de> Deserialize<'de> for GridSize {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            Text(String),
            Square(usize),
        }
        match Raw::deserialize(d)? {
            Raw::Text(s) => s.parse().map_err(serde::de::Error::custom),
            Raw::Square(n) => Ok(GridSize { nx: n, ny: n }),
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
        assert_eq!("7".parse::<GridSize>().unwrap(), GridSize { nx: 7, ny: 7 });
        assert!("20y12".parse::<GridSize>().is_err());
    }
}
