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
    /// The outer shell only: the whole lattice's edges draw a solid block at n = 20, 30.
    fn drawn_units(&self) -> Vec<usize> {
        let outer = |c: i32| c == 0 || c as usize + 1 == self.n;
        (0..self.lattice.len())
            .filter(|&u| self.lattice.index_vector(u).iter().any(|&c| outer(c)))
            .collect()
    }
    fn edge_groups(&self) -> Vec<EdgeGroup> {
        // The shell's edges, numbered by position in `drawn_units`.
        let drawn = self.drawn_units();
        let mut at = vec![u32::MAX; self.lattice.len()];
        for (k, &u) in drawn.iter().enumerate() {
            at[u] = k as u32;
        }
        let edges = self
            .lattice
            .shell_edges()
            .into_iter()
            .map(|(a, b)| (at[a as usize], at[b as usize]))
            .collect();
        vec![EdgeGroup { label: "outer shell".into(), edges }]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_drawn_shell_is_the_lattice_surface_and_its_edges_index_it() {
        for n in [2usize, 5, 10] {
            let t = Som3d::new(n);
            let drawn = t.drawn_units();
            // n^3 - (n - 2)^3 units on the surface of the cube.
            assert_eq!(drawn.len(), n * n * n - (n - 2).pow(3), "n = {n}");
            let edges = &t.edge_groups()[0].edges;
            assert_eq!(edges.len(), 12 * (n - 1) * (n - 1));
            assert!(edges
                .iter()
                .all(|&(a, b)| (a as usize) < drawn.len() && (b as usize) < drawn.len()));
        }
    }
}
