//! The 3-D SOM: an `n x n x n` lattice whose every neuron is output, internal ones included
//! (thesis 2.4; the model with the connectivity problem).

use super::{EdgeGroup, Lattice, Model, NeuronCounts, Topology};

pub struct Som3d {
    n: usize,
    lattice: Lattice,
}

impl Som3d {
    pub fn new(n: usize) -> Som3d {
        let mut index = Vec::with_capacity(n * n * n);
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    index.push([i as i32, j as i32, k as i32]);
                }
            }
        }
        Som3d { n, lattice: Lattice::new([n, n, n], index) }
    }
}

impl Topology for Som3d {
    fn model(&self) -> Model {
        Model::Som3d
    }
    fn lattice(&self) -> &Lattice {
        &self.lattice
    }
    fn sigma0(&self) -> f64 {
        self.n as f64 / 2.0
    }
    fn counts(&self) -> NeuronCounts {
        let n = self.n * self.n * self.n;
        NeuronCounts { non: n, nov: n, nor: 0 }
    }
    fn edge_groups(&self) -> Vec<EdgeGroup> {
        vec![EdgeGroup { label: "lattice".into(), edges: self.lattice.unit_edges() }]
    }
}
