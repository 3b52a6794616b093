//! Cubic B-spline ("NURBS with all weights 1") approximation of the DNSOM surfaces (thesis
//! Chapter 5): basis functions, parameterisation, knots, least-squares control nets, the
//! conventional and improved two-surface approaches, and CAD export. Pure: no file I/O.

pub mod approach;
pub mod basis;
pub mod bezier;
pub mod closed;
pub mod conic;
pub mod control_net;
pub mod export;
pub mod fit;
pub mod geometry;
pub mod knots;
pub mod open_surface;
pub mod param;
pub mod rational_bezier;
pub mod surface;

pub use approach::{
    fit_two_view, Approach, ControlNetParts, ErrorA, FitOptions, TwoSurfaceFit, TwoViewGrid,
};
pub use basis::SparseBasis;
pub use control_net::{BoxSpec, ControlNetProblem};
pub use geometry::{DenseGeometry, DENSE_FACTOR};
pub use knots::KnotRule;
pub use param::{ParamReading, ParamRows, Parameterisation};
pub use surface::BSplineSurface;

use thiserror::Error;

#[derive(Debug, Error, PartialEq)]
pub enum SplineError {
    #[error("grid: {0}")]
    Grid(String),
    #[error("control net: {0}")]
    ControlNet(String),
    #[error("least squares: {0}")]
    Singular(String),
    #[error("IGES: {0}")]
    Iges(String),
}
