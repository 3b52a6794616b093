//! Cubic B-spline ("NURBS with all weights 1") approximation of the DNSOM surfaces (thesis
//! Chapter 5): basis functions, parameterisation, knots, least-squares control nets, the
//! conventional and improved two-surface approaches, and CAD export. Pure: no file I/O.

pub(crate) mod approach;
pub(crate) mod basis;
pub(crate) mod bezier;
pub(crate) mod closed;
pub(crate) mod conic;
pub(crate) mod control_net;
pub(crate) mod export;
pub(crate) mod fit;
pub(crate) mod geometry;
pub(crate) mod knots;
pub(crate) mod open_surface;
pub(crate) mod param;
pub(crate) mod rational_bezier;
pub(crate) mod surface;

pub(crate) use approach::{ControlNetParts, ErrorA, FitOptions, TwoSurfaceFit, TwoViewGrid};
pub(crate) use geometry::{DenseGeometry, DENSE_FACTOR};
pub(crate) use param::{ParamReading, ParamRows};
pub(crate) use surface::BSplineSurface;

pub use approach::{fit_two_view, Approach};
pub use basis::SparseBasis;
pub use bezier::{example3, franke, height_grid, peaks, BezierParamProblem, Layout};
pub use control_net::{BoxSpec, ControlNetProblem};
pub use export::parse_iges_128;
pub use knots::KnotRule;
pub use param::Parameterisation;
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
