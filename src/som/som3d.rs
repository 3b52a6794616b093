//! The 3-D SOM: an `n x n x n` lattice whose every neuron is output, internal ones included
//! (thesis 2.4; the model with the connectivity problem).

use super::{EdgeGroup, Lattice, Model, NeuronCounts, Topology};
use serde::Deserialize;

/// Which units of the `n x n x n` lattice count as adjacent for the topographic error (Eq. 4.16:
/// "if the first winning neuron and the second winning neuron of x(t) is not adjacent"); the
/// thesis does not say for the 3-D lattice (spec key `som.som3d_adjacency`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LatticeAdjacency {
    /// Index distance 1 (Eq. 4.8, dist = 1): the 6-neighbourhood.
    #[default]
    N6,
    /// dist^2 in {1, 2}: the 18-neighbourhood (faces and edges of the unit cube).
    N18,
    /// Chebyshev distance 1: the 26-neighbourhood (faces, edges and corners).
    N26,
    /// Index distance 1 within one k layer: the lattice read as n stacked n x n 2-D SOMs
    /// (Section 4.3: the 3-D SOM is "made up of n ... 2-D SOMs").
    Layer,
    /// Index distance 1 between two units of the lattice's outer shell: adjacency along its six
    /// 2-D faces only; an internal unit is adjacent to none.
    Shell,
}

impl LatticeAdjacency {
    /// The spec values, in the order of the enum.
    pub const NAMES: [&'static str; 5] = ["n6", "n18", "n26", "layer", "shell"];

    /// Whether units `a` and `b` (distinct) of an `n`-sided lattice are adjacent.
    pub fn holds(self, lattice: &Lattice, n: usize, a: usize, b: usize) -> bool {
        let (p, q) = (lattice.index_vector(a), lattice.index_vector(b));
        let d = [(p[0] - q[0]).abs(), (p[1] - q[1]).abs(), (p[2] - q[2]).abs()];
        let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let outer = |v: [i32; 3]| v.iter().any(|&c| c == 0 || c as usize + 1 == n);
        match self {
            LatticeAdjacency::N6 => d2 == 1,
            LatticeAdjacency::N18 => d2 == 1 || d2 == 2,
            LatticeAdjacency::N26 => d2 >= 1 && d.iter().all(|&c| c <= 1),
            LatticeAdjacency::Layer => d2 == 1 && d[2] == 0,
            LatticeAdjacency::Shell => d2 == 1 && outer(p) && outer(q),
        }
    }
}

pub(crate) struct Som3d {
    n: usize,
    lattice: Lattice,
    adjacency: LatticeAdjacency,
}

impl Som3d {
    #[cfg(test)]
    pub(crate) fn new(n: usize) -> Som3d {
        Som3d::with_adjacency(n, LatticeAdjacency::default())
    }

    /// The lattice with the topographic error's adjacency `adjacency`.
    pub(crate) fn with_adjacency(n: usize, adjacency: LatticeAdjacency) -> Som3d {
        let mut index = Vec::with_capacity(n * n * n);
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    index.push([i as i32, j as i32, k as i32]);
                }
            }
        }
        Som3d { n, lattice: Lattice::new([n, n, n], index), adjacency }
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
    fn adjacent(&self, a: usize, b: usize) -> bool {
        self.adjacency.holds(&self.lattice, self.n, a, b)
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
    fn each_adjacency_gives_its_neighbour_count_at_the_centre_and_a_corner() {
        // n = 5: the centre (2,2,2) has 6/18/26 neighbours, 4 in its layer, none on the shell; the
        // corner (0,0,0) has 3/6/7, 2 in its layer, 3 on the shell.
        let n = 5;
        let unit = |i: usize, j: usize, k: usize| (i * n + j) * n + k;
        let want = [
            (LatticeAdjacency::N6, 6, 3),
            (LatticeAdjacency::N18, 18, 6),
            (LatticeAdjacency::N26, 26, 7),
            (LatticeAdjacency::Layer, 4, 2),
            (LatticeAdjacency::Shell, 0, 3),
        ];
        for (adjacency, centre, corner) in want {
            let t = Som3d::with_adjacency(n, adjacency);
            let count = |u: usize| (0..n * n * n).filter(|&v| v != u && t.adjacent(u, v)).count();
            assert_eq!(count(unit(2, 2, 2)), centre, "{adjacency:?} centre");
            assert_eq!(count(unit(0, 0, 0)), corner, "{adjacency:?} corner");
            // Symmetric, and never a unit with itself.
            for (a, b) in [(unit(1, 2, 3), unit(2, 3, 3)), (unit(0, 1, 1), unit(0, 1, 2))] {
                assert_eq!(t.adjacent(a, b), t.adjacent(b, a));
            }
            assert!(!t.adjacent(unit(1, 1, 1), unit(1, 1, 1)));
        }
    }

    #[test]
    fn the_default_adjacency_is_index_distance_one() {
        let t = Som3d::new(4);
        for a in 0..64 {
            for b in 0..64 {
                assert_eq!(t.adjacent(a, b), t.lattice().dist2(a, b) == 1);
            }
        }
    }

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
