//! Self-organising maps (thesis Chapter 4): four topologies over one training loop.
//!
//! Every model is a set of *units* (distinct weight vectors) placed at integer index vectors
//! (i, j, k) of a lattice. The models differ only in which index vectors exist, which units a
//! winner may update, which units count as adjacent (for the topographic error) and how the units
//! are drawn. The shared loop in [`train`] does the rest, so a new model is one file.

pub(crate) mod cksom;
pub(crate) mod dnsom;
pub(crate) mod growing_grid;
pub(crate) mod lattice;
pub(crate) mod som2d;
pub(crate) mod som3d;
pub(crate) mod train;

use std::fmt;
use std::str::FromStr;

pub(crate) use lattice::Lattice;
pub(crate) use som3d::LatticeAdjacency;
pub(crate) use train::{final_map_metrics, FinalMetrics, OnlineMetrics};
pub use train::{train, SomParams};

/// The four SOM models compared in Chapter 4 (Table 4.1) (in a spec by name, as [`FromStr`]
/// reads it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Deserialize)]
#[serde(try_from = "String")]
pub enum Model {
    Som2d,
    Som3d,
    Cksom,
    Dnsom,
}

impl Model {
    pub const ALL: [Model; 4] = [Model::Som2d, Model::Som3d, Model::Cksom, Model::Dnsom];

    /// Short name used in specs, file names and the thesis' CSV column suffixes.
    pub fn key(self) -> &'static str {
        match self {
            Model::Som2d => "som2d",
            Model::Som3d => "som3d",
            Model::Cksom => "cksom",
            Model::Dnsom => "dnsom",
        }
    }

    /// Name as printed in the thesis.
    pub fn label(self) -> &'static str {
        match self {
            Model::Som2d => "2-D SOM",
            Model::Som3d => "3-D SOM",
            Model::Cksom => "CKSOM",
            Model::Dnsom => "DNSOM",
        }
    }

    /// Build the model's topology for an `nx x ny` grid.
    pub fn topology(self, nx: usize, ny: usize) -> Result<Box<dyn Topology>, String> {
        self.topology_with(nx, ny, LatticeAdjacency::default())
    }

    /// [`Model::topology`] with the 3-D lattice's adjacency for the topographic error
    /// (`som.som3d_adjacency`; the other models ignore it).
    pub fn topology_with(
        self,
        nx: usize,
        ny: usize,
        som3d_adjacency: LatticeAdjacency,
    ) -> Result<Box<dyn Topology>, String> {
        if nx < 2 || ny < 2 {
            return Err(format!("grid {nx}x{ny} is too small: both sides must be at least 2"));
        }
        Ok(match self {
            Model::Som2d => Box::new(som2d::Som2d::new(nx, ny)),
            Model::Som3d => {
                if nx != ny {
                    return Err(format!(
                        "3-D SOM needs an n x n x n lattice, got grid {nx}x{ny} (use a square grid)"
                    ));
                }
                Box::new(som3d::Som3d::with_adjacency(nx, som3d_adjacency))
            }
            Model::Cksom => Box::new(cksom::Cksom::new(nx, ny)),
            Model::Dnsom => Box::new(dnsom::Dnsom::new(nx, ny)),
        })
    }
}

impl fmt::Display for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.key())
    }
}

impl TryFrom<String> for Model {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().replace(['-', '_', ' '], "").as_str() {
            "som2d" | "2dsom" => Ok(Model::Som2d),
            "som3d" | "3dsom" => Ok(Model::Som3d),
            "cksom" => Ok(Model::Cksom),
            "dnsom" => Ok(Model::Dnsom),
            _ => {
                Err(format!("unknown SOM model `{s}` (expected one of som2d, som3d, cksom, dnsom)"))
            }
        }
    }
}

/// Neuron counts of a model (Tables 4.9, 4.13, 4.14): total neurons, output (distinct) neurons,
/// redundant neurons.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NeuronCounts {
    pub non: usize,
    pub nov: usize,
    pub nor: usize,
}

/// A group of wireframe edges drawn in one colour (DNSOM: one group per view).
#[derive(Debug, Clone)]
pub struct EdgeGroup {
    pub label: String,
    pub edges: Vec<(u32, u32)>,
}

/// What distinguishes one SOM model from another; the training loop is shared.
pub trait Topology: Send + Sync {
    fn model(&self) -> Model;
    /// The units and their index vectors.
    fn lattice(&self) -> &Lattice;
    /// Initial neighbourhood radius sigma0 (Table 4.1: half the grid size; half the smaller side
    /// when nx != ny).
    fn sigma0(&self) -> f64;
    /// Neuron counts (NON, NOV, NOR).
    fn counts(&self) -> NeuronCounts;
    /// A winner never moves units whose k index differs from its own by exactly this much
    /// (DNSOM: K = 2, the opposite view's interior; Section 4.2.4). `None`: no such rule.
    fn frozen_k_distance(&self) -> Option<i32> {
        None
    }
    /// Whether `unit` may learn when `winner` wins.
    fn may_update(&self, winner: usize, unit: usize) -> bool {
        let (w, u) = (self.lattice().index_vector(winner), self.lattice().index_vector(unit));
        self.frozen_k_distance() != Some((w[2] - u[2]).abs())
    }
    /// Whether two units are adjacent for the topographic error.
    fn adjacent(&self, a: usize, b: usize) -> bool {
        self.lattice().dist2(a, b) == 1
    }
    /// The units a picture draws, in order (default: all); [`Topology::edge_groups`] indexes
    /// into this list.
    fn drawn_units(&self) -> Vec<usize> {
        (0..self.lattice().len()).collect()
    }
    /// Wireframe edges over the drawn units, grouped by colour.
    fn edge_groups(&self) -> Vec<EdgeGroup>;
}
