//! The Cube Kohonen SOM of Lim & Haron: the surface of a lattice cube, six merged faces.
//!
//! Face (a, b), a in 0..nx, b in 0..ny, sits at index vector bottom (a, b, 0), top (a, b, L),
//! left (0, a, b), right (L, a, b), front (a, 0, b), back (a, L, b), with L = max(nx, ny) - 1.
//! Positions shared by two or three faces (edges, corners) are one unit, so for n x n:
//! NON = 6 n^2, NOV = 6 n^2 - 12 n + 8 (Table 4.9). With nx != ny the faces no longer meet along
//! every edge and the map has holes, as the thesis shows (Fig. 4.9, 4.10); its own Table 4.13 counts
//! for that case come from an unpublished construction and are not reproduced.

use super::{EdgeGroup, Lattice, Model, NeuronCounts, Topology};
use std::collections::HashMap;

pub(crate) struct Cksom {
    nx: usize,
    ny: usize,
    lattice: Lattice,
}

impl Cksom {
    pub(crate) fn new(nx: usize, ny: usize) -> Cksom {
        let l = nx.max(ny) as i32 - 1;
        let mut seen: HashMap<[i32; 3], usize> = HashMap::new();
        let mut index = Vec::new();
        for face in 0..6 {
            for a in 0..nx as i32 {
                for b in 0..ny as i32 {
                    let iv = match face {
                        0 => [a, b, 0],
                        1 => [a, b, l],
                        2 => [0, a, b],
                        3 => [l, a, b],
                        4 => [a, 0, b],
                        _ => [a, l, b],
                    };
                    seen.entry(iv).or_insert_with(|| {
                        index.push(iv);
                        index.len() - 1
                    });
                }
            }
        }
        let side = l as usize + 1;
        Cksom { nx, ny, lattice: Lattice::new([side, side, side], index) }
    }
}

impl Topology for Cksom {
    fn model(&self) -> Model {
        Model::Cksom
    }
    fn lattice(&self) -> &Lattice {
        &self.lattice
    }
    fn sigma0(&self) -> f64 {
        self.nx.min(self.ny) as f64 / 2.0
    }
    fn counts(&self) -> NeuronCounts {
        let non = 6 * self.nx * self.ny;
        let nov = self.lattice.len();
        NeuronCounts { non, nov, nor: non - nov }
    }
    fn edge_groups(&self) -> Vec<EdgeGroup> {
        vec![EdgeGroup { label: "surface".into(), edges: self.lattice.unit_edges() }]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_4_9_counts() {
        for (n, non, nov, nor) in
            [(10, 600, 488, 112), (20, 2400, 2168, 232), (30, 5400, 5048, 352)]
        {
            let c = Cksom::new(n, n).counts();
            assert_eq!((c.non, c.nov, c.nor), (non, nov, nor));
        }
    }

    #[test]
    fn every_unit_on_the_cube_surface() {
        let ck = Cksom::new(7, 7);
        for u in 0..ck.lattice.len() {
            let iv = ck.lattice.index_vector(u);
            assert!(iv.iter().any(|&c| c == 0 || c == 6), "{iv:?} is interior");
        }
    }
}
