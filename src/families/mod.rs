//! The experiment families, one folder each: `mod.rs` implements [`Family`] for the family's
//! spec section, `report.rs` writes its tables, pictures and REPORT.md section. This file holds
//! the only list of families: a new one is its folder plus one line here.

pub mod closed_cylinder;
pub mod cuckoo_bezier;
pub mod fit;
pub mod growing_grid;
pub mod optimise;
pub mod rational_bezier;
pub mod som;

use crate::experiment::family::Family;

/// Every family the harness knows, in the order their sections are named in messages.
pub static FAMILIES: &[&dyn Family] = &[
    &som::Som,
    &fit::Fit,
    &optimise::Optim,
    &growing_grid::Seed001,
    &rational_bezier::Seed002,
    &cuckoo_bezier::Seed003,
    &closed_cylinder::Seed004,
];
