//! The experiment families, one folder each: `mod.rs` implements `experiment::family::Experiment`
//! for the family's spec section, `report.rs` writes its tables, pictures and REPORT.md section.
//! This file holds the only list of families (the macro declares their modules too): a new one is
//! its folder plus one line here.

crate::experiment::spec::families! {
    /// Chapter 4: SOM models.
    som: som::spec::SomSpec => som::Som,
    /// Chapter 5: cubic B-spline fits of saved DNSOM maps.
    fit: fit::spec::FitSpec => fit::Fit,
    /// Chapter 6: optimisation of approach B's control points.
    optimise (optim): optimise::spec::OptimSpec => optimise::Optim,
    /// Seed 001: growing grid on open surfaces, one B-spline surface, GA/DE/PSO.
    growing_grid: growing_grid::spec::GrowingGridSpec => growing_grid::GrowingGrid,
    /// Seed 002 (Yahya): four-patch G1 rational bi-quadratic Bezier surfaces by GA/DE/PSO.
    rational_bezier (seed002): rational_bezier::spec::RationalBezierSpec => rational_bezier::RationalBezier,
    /// Seed 003 (Iglesias et al.): Bezier surfaces with CSA/ICSA-searched data parameters.
    cuckoo_bezier (seed003): cuckoo_bezier::CuckooBezierSpec => cuckoo_bezier::CuckooBezier,
    /// Seed 004: closed B-spline surface of a cylinder by a binary-coded GA.
    closed_cylinder (seed004): closed_cylinder::spec::ClosedCylinderSpec => closed_cylinder::ClosedCylinder,
}

pub(crate) mod maps;
pub mod suite;
