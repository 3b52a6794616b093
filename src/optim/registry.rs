//! What the one list of optimisers (`optimisers!` in `optim/mod.rs`, read as [`REGISTRY`]) gives:
//! the checked name a spec writes ([`Name`]), the parameter tables a spec section holds
//! ([`Tables`]) and each chart colour. A new optimiser is its own file implementing [`Optimiser`]
//! plus one line in that list; every section that runs optimisers on a problem then offers it,
//! with its table.

use super::Optimiser;
pub(crate) use super::REGISTRY;
use serde::de::{self, DeserializeOwned, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use std::fmt;
use std::sync::{Arc, LazyLock};

/// One optimiser the harness knows: how to make it with its default parameters (thesis Table
/// 6.1, seed 003, seed 004), how to read its parameter table from a spec, and its colour in every
/// chart (Okabe-Ito, as RGB).
pub(crate) struct Registered {
    pub(crate) make: fn() -> Box<dyn Optimiser>,
    read: fn(toml::Value) -> Result<Box<dyn Optimiser>, String>,
    pub(crate) colour: [u8; 3],
}

impl Registered {
    /// The entry of optimiser type `T`: its `Default` parameters, its serde table, `colour`.
    pub(crate) const fn of<T: Optimiser + Default + DeserializeOwned + 'static>(
        colour: [u8; 3],
    ) -> Self {
        Registered { make: make::<T>, read: read::<T>, colour }
    }
}

fn make<T: Optimiser + Default + 'static>() -> Box<dyn Optimiser> {
    Box::new(T::default())
}

fn read<T: Optimiser + DeserializeOwned + 'static>(
    table: toml::Value,
) -> Result<Box<dyn Optimiser>, String> {
    T::deserialize(table).map(|t| Box::new(t) as Box<dyn Optimiser>).map_err(|e| e.to_string())
}

/// Declares each optimiser's module (a file in `src/optim/`) and makes [`REGISTRY`] from the list,
/// in its order (that of tables and legends): `module: Type [r, g, b], ...;` per file.
macro_rules! optimisers {
    ($($module:ident: $($ty:ident $colour:expr),+;)*) => {
        $(pub(crate) mod $module;)*

        /// Every optimiser the harness knows, in the order of tables and legends.
        pub(crate) static REGISTRY: &[registry::Registered] =
            &[$($(registry::Registered::of::<$module::$ty>($colour),)+)*];
    };
}
pub(crate) use optimisers;

/// The registered names, in [`REGISTRY`]'s order.
static NAMES: LazyLock<Vec<&'static str>> =
    LazyLock::new(|| REGISTRY.iter().map(|r| (r.make)().name()).collect());

/// The registered optimiser named `name`.
pub(crate) fn registered(name: &str) -> Option<&'static Registered> {
    NAMES.iter().position(|n| *n == name).map(|i| &REGISTRY[i])
}

/// The optimisers by name with their default parameters.
pub fn default_optimiser(name: &str) -> Option<Box<dyn Optimiser>> {
    registered(name).map(|r| (r.make)())
}

/// "ga, de, ... or binary_ga", for messages.
fn expected() -> String {
    match NAMES.split_last() {
        Some((last, [])) => last.to_string(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
        None => String::new(),
    }
}

/// A registered optimiser's name, checked against [`REGISTRY`] when a spec is read, so a cell
/// never looks an optimiser up by a string that might be wrong. Ordered as its text.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct Name(usize);

impl Name {
    /// The name as written in specs and tables (`de`).
    pub(crate) fn as_str(self) -> &'static str {
        NAMES[self.0]
    }

    /// Every registered name, in [`REGISTRY`]'s order.
    pub(crate) fn all() -> impl Iterator<Item = Name> {
        (0..REGISTRY.len()).map(Name)
    }
}

impl fmt::Display for Name {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl PartialOrd for Name {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Name {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.as_str().cmp(other.as_str())
    }
}

impl std::str::FromStr for Name {
    type Err = String;
    fn from_str(s: &str) -> Result<Name, String> {
        NAMES
            .iter()
            .position(|n| *n == s)
            .map(Name)
            .ok_or_else(|| format!("unknown optimiser `{s}` (expected {})", expected()))
    }
}

impl<'de> Deserialize<'de> for Name {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Name, D::Error> {
        let s = String::deserialize(d)?;
        s.parse().map_err(de::Error::custom)
    }
}

/// The parameter tables of every registered optimiser in a spec section (`[optimise.de]`, ...),
/// each the optimiser's defaults where the spec has no table. A section holds it as
/// `#[serde(flatten)]`: it takes the section's keys that name an optimiser and refuses any other
/// key the section does not know.
#[derive(Clone)]
pub(crate) struct Tables(Vec<Arc<dyn Optimiser>>);

impl Default for Tables {
    fn default() -> Tables {
        Tables(REGISTRY.iter().map(|r| Arc::from((r.make)())).collect())
    }
}

impl fmt::Debug for Tables {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.debug_list().entries(self.0.iter()).finish()
    }
}

impl Tables {
    /// The optimiser `name` with the section's parameters.
    pub(crate) fn get(&self, name: Name) -> &dyn Optimiser {
        self.0[name.0].as_ref()
    }

    /// Every registered optimiser with the section's parameters, in [`REGISTRY`]'s order.
    pub(crate) fn all(&self) -> Vec<&dyn Optimiser> {
        self.0.iter().map(|o| o.as_ref()).collect()
    }
}

impl<'de> Deserialize<'de> for Tables {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Tables, D::Error> {
        struct TablesVisitor;
        impl<'de> Visitor<'de> for TablesVisitor {
            type Value = Tables;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("optimiser parameter tables")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Tables, A::Error> {
                let mut tables = Tables::default();
                while let Some(key) = map.next_key::<String>()? {
                    let Some(i) = NAMES.iter().position(|n| *n == key) else {
                        return Err(de::Error::custom(format!(
                            "unknown field `{key}`: neither a key of this section nor an \
                             optimiser's table ({})",
                            expected()
                        )));
                    };
                    let value: toml::Value = map.next_value()?;
                    let opt = (REGISTRY[i].read)(value)
                        .map_err(|e| de::Error::custom(format!("table `{key}`: {}", e.trim())))?;
                    tables.0[i] = Arc::from(opt);
                }
                Ok(tables)
            }
        }
        d.deserialize_map(TablesVisitor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_knows_the_six() {
        let six = ["ga", "de", "pso", "csa", "icsa", "binary_ga"];
        assert!(six.iter().all(|n| NAMES.contains(n)), "{:?}", *NAMES);
        let unique = |v: Vec<String>| v.iter().collect::<std::collections::HashSet<_>>().len();
        assert_eq!(unique(NAMES.iter().map(|n| n.to_string()).collect()), REGISTRY.len());
        let colours = REGISTRY.iter().map(|r| format!("{:?}", r.colour)).collect();
        assert_eq!(unique(colours), REGISTRY.len(), "one colour each");
        let tables = Tables::default();
        for name in six {
            assert_eq!(default_optimiser(name).unwrap().name(), name);
            let n: Name = name.parse().unwrap();
            assert_eq!((n.as_str(), tables.get(n).name()), (name, name));
        }
        assert!(default_optimiser("sa").is_none());
        let e = "sa".parse::<Name>().unwrap_err();
        assert!(e.starts_with("unknown optimiser `sa` (expected ga, de, pso, csa, icsa"), "{e}");
        let mut sorted: Vec<Name> = six.iter().map(|n| n.parse().unwrap()).collect();
        sorted.sort();
        let sorted: Vec<&str> = sorted.iter().map(|n| n.as_str()).collect();
        assert_eq!(sorted, ["binary_ga", "csa", "de", "ga", "icsa", "pso"], "ordered as text");
    }

    /// A table read through a section keeps its values, refuses an unknown key of an optimiser
    /// and a key that is neither the section's nor an optimiser's.
    #[test]
    fn tables_read_as_a_flattened_section() {
        #[derive(Debug, Deserialize)]
        struct Section {
            #[allow(dead_code)]
            repeats: usize,
            #[serde(flatten)]
            tables: Tables,
        }
        let read = |t: &str| toml::from_str::<Section>(t).map_err(|e| e.message().to_string());
        let s = read("repeats = 3\n[ga]\ntournament = 7\n").unwrap();
        assert_eq!(s.tables.get("ga".parse().unwrap()).min_population().n, 7);
        assert_eq!(s.tables.get("de".parse().unwrap()).min_population().n, 4, "defaults");
        let e = read("repeats = 3\n[de]\ncrr = 0.25\n").unwrap_err();
        assert!(e.starts_with("table `de`: unknown field `crr`"), "{e}");
        let e = read("repeats = 3\nrepeat = 4\n").unwrap_err();
        assert!(e.contains("unknown field `repeat`: neither a key of this section"), "{e}");
        assert!(e.contains("binary_ga"), "{e}");
    }
}
