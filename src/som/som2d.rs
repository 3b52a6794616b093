//! The 2-D SOM: one `nx x ny` map (thesis 2.4; the model with holes on closed surfaces).

use super::{EdgeGroup, Lattice, Model, NeuronCounts, Topology};

pub(crate) struct Som2d {
    nx: usize,
    ny: usize,
    lattice: Lattice,
}

impl Som2d {
    pub(crate) fn new(nx: usize, ny: usize) -> Som2d {
        let mut index = Vec::with_capacity(nx * ny);
        for i in 0..nx {
            for j in 0..ny {
                index.push([i as i32, j as i32, 0]);
            }
        }
        Som2d { nx, ny, lattice: Lattice::new([nx, ny, 1], index) }
    }
}

impl Topology for Som2d {
    fn model(&self) -> Model {
        Model::Som2d
    }
    fn lattice(&self) -> &Lattice {
        &self.lattice
    }
    fn sigma0(&self) -> f64 {
        self.nx.min(self.ny) as f64 / 2.0
    }
    fn counts(&self) -> NeuronCounts {
        let n = self.nx * self.ny;
        NeuronCounts { non: n, nov: n, nor: 0 }
    }
    fn edge_groups(&self) -> Vec<EdgeGroup> {
        vec![EdgeGroup { label: "map".into(), edges: self.lattice.unit_edges() }]
    }
}
