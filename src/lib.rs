//! somnurbs: reproduce, from seeds, SOM + cubic B-spline surface reconstruction experiments.
pub mod double_net;
pub mod geom;
pub mod som;
