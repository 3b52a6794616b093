//! The Double Net SOM (the thesis' model, Section 4.2): two `nx x ny` maps, bottom and top view,
//! merged along their border.
//!
//! Units are the class numbers of [`DoubleNet`] (Table 4.3); a unit's index vector is that of its
//! first allocation, so border units have k = 1, bottom interior k = 0, top interior k = 2.
//! Neighbour rule (Section 4.2.4): a unit learns only if dist < sigma(t) AND K != 2, K = |k_w - k_u|
//! (a winner never moves the opposite view's interior). Adjacency for the topographic error is the
//! 4-neighbourhood on either map, taken over class numbers (so a border unit is adjacent to its
//! interior neighbours on both views, although their index distance is sqrt 2).

use super::{EdgeGroup, Lattice, Model, NeuronCounts, Topology};
use crate::double_net::{DoubleNet, View};

pub(crate) struct Dnsom {
    net: DoubleNet,
    lattice: Lattice,
    /// Sorted 4-neighbourhood of every unit over both views.
    adjacency: Vec<Vec<u32>>,
}

impl Dnsom {
    pub(crate) fn new(nx: usize, ny: usize) -> Dnsom {
        let net = DoubleNet::new(nx, ny).expect("DNSOM grid sides are at least 2");
        let index: Vec<[i32; 3]> = (0..net.nov())
            .map(|c| {
                let (view, i, j) = net.first_allocation(c);
                let iv = net.index_vector(view, i, j);
                [iv[0] as i32, iv[1] as i32, iv[2] as i32]
            })
            .collect();
        let mut adjacency = vec![Vec::new(); net.nov()];
        for (a, b) in grid_class_edges(&net, View::Bottom)
            .into_iter()
            .chain(grid_class_edges(&net, View::Top))
        {
            adjacency[a as usize].push(b);
            adjacency[b as usize].push(a);
        }
        for list in &mut adjacency {
            list.sort_unstable();
            list.dedup();
        }
        Dnsom { lattice: Lattice::new([nx, ny, 3], index), net, adjacency }
    }
}

/// Edges of one view's 4-neighbourhood grid, as pairs of classes.
fn grid_class_edges(net: &DoubleNet, view: View) -> Vec<(u32, u32)> {
    let mut edges = Vec::new();
    for i in 0..net.nx {
        for j in 0..net.ny {
            let c = net.class(view, i, j) as u32;
            if i + 1 < net.nx {
                edges.push((c, net.class(view, i + 1, j) as u32));
            }
            if j + 1 < net.ny {
                edges.push((c, net.class(view, i, j + 1) as u32));
            }
        }
    }
    edges
}

impl Topology for Dnsom {
    fn model(&self) -> Model {
        Model::Dnsom
    }
    fn lattice(&self) -> &Lattice {
        &self.lattice
    }
    fn sigma0(&self) -> f64 {
        self.net.nx.min(self.net.ny) as f64 / 2.0
    }
    fn counts(&self) -> NeuronCounts {
        NeuronCounts { non: self.net.non(), nov: self.net.nov(), nor: self.net.nor() }
    }
    fn frozen_k_distance(&self) -> Option<i32> {
        Some(2)
    }
    fn adjacent(&self, a: usize, b: usize) -> bool {
        self.adjacency[a].binary_search(&(b as u32)).is_ok()
    }
    fn edge_groups(&self) -> Vec<EdgeGroup> {
        View::BOTH
            .iter()
            .map(|&v| EdgeGroup { label: v.name().into(), edges: grid_class_edges(&self.net, v) })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Table 4.4: dist^2 from class number 7 of the 4 x 5 DNSOM to every class number.
    #[test]
    fn table_4_4_distances_from_class_7() {
        let d = Dnsom::new(4, 5);
        let want =
            [3, 2, 3, 6, 11, 2, 0, 1, 4, 10, 3, 1, 2, 5, 11, 6, 5, 6, 9, 14, 4, 5, 8, 5, 6, 9];
        for (c, &w) in want.iter().enumerate() {
            assert_eq!(d.lattice.dist2(6, c), w, "class number {}", c + 1);
        }
        // Class numbers 21-26 (top interior) are never updated by winner 7 (K = 2).
        for c in 0..26 {
            assert_eq!(d.may_update(6, c), c < 20, "class number {}", c + 1);
        }
    }

    #[test]
    fn adjacency_is_the_map_four_neighbourhood() {
        let d = Dnsom::new(4, 5);
        // Class 7 (1,1) bottom: neighbours 2, 6, 8, 12.
        assert_eq!(d.adjacency[6], vec![1, 5, 7, 11]);
        // Class 21 (1,1) top: neighbours 2, 6, 22, 24.
        assert_eq!(d.adjacency[20], vec![1, 5, 21, 23]);
        assert!(d.adjacent(1, 20) && d.adjacent(1, 6));
        assert!(!d.adjacent(6, 20));
    }
}
