//! Units placed at integer index vectors, with O(1) look-up by index vector so that a winner's
//! neighbourhood is enumerated over a small box instead of over every unit.

/// Units at distinct index vectors inside a box `dims[0] x dims[1] x dims[2]`.
#[derive(Debug, Clone)]
pub struct Lattice {
    dims: [usize; 3],
    index: Vec<[i32; 3]>,
    lookup: Vec<u32>,
}

const NONE: u32 = u32::MAX;

impl Lattice {
    /// Build from the index vectors of the units in unit order; duplicates are a programming error.
    pub fn new(dims: [usize; 3], index: Vec<[i32; 3]>) -> Lattice {
        let mut lookup = vec![NONE; dims[0] * dims[1] * dims[2]];
        for (u, iv) in index.iter().enumerate() {
            let at = Self::flat(dims, *iv);
            assert_eq!(lookup[at], NONE, "two units at index vector {iv:?}");
            lookup[at] = u as u32;
        }
        Lattice { dims, index, lookup }
    }

    #[inline]
    fn flat(dims: [usize; 3], iv: [i32; 3]) -> usize {
        (iv[0] as usize * dims[1] + iv[1] as usize) * dims[2] + iv[2] as usize
    }

    pub fn len(&self) -> usize {
        self.index.len()
    }

    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Index vector of a unit.
    #[inline]
    pub fn index_vector(&self, unit: usize) -> [i32; 3] {
        self.index[unit]
    }

    /// The unit at an index vector, if any.
    #[inline]
    pub fn unit_at(&self, iv: [i32; 3]) -> Option<usize> {
        for a in 0..3 {
            if iv[a] < 0 || iv[a] as usize >= self.dims[a] {
                return None;
            }
        }
        let u = self.lookup[Self::flat(self.dims, iv)];
        (u != NONE).then_some(u as usize)
    }

    /// Squared index-space distance dist^2 = I^2 + J^2 + K^2 (Eq. 4.4-4.7).
    #[inline]
    pub fn dist2(&self, a: usize, b: usize) -> i32 {
        let (p, q) = (self.index[a], self.index[b]);
        let (di, dj, dk) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
        di * di + dj * dj + dk * dk
    }

    /// Call `f(unit, dist2)` for every unit whose index distance to `centre` is below `radius`
    /// (strictly: dist < radius, the thesis' "dist smaller than the radius decay"), skipping units
    /// whose k index differs from the centre's by exactly `skip_dk`.
    #[inline]
    pub fn for_each_within(
        &self,
        centre: usize,
        radius: f64,
        skip_dk: Option<i32>,
        mut f: impl FnMut(usize, i32),
    ) {
        let skip = skip_dk.unwrap_or(-1);
        let c = self.index[centre];
        let r2 = radius * radius;
        let reach = (radius.ceil() as i32 - 1).max(0);
        let lo = |a: usize| (c[a] - reach).max(0);
        let hi = |a: usize| (c[a] + reach).min(self.dims[a] as i32 - 1);
        for i in lo(0)..=hi(0) {
            let di = i - c[0];
            for j in lo(1)..=hi(1) {
                let dj = j - c[1];
                let dij = di * di + dj * dj;
                if (dij as f64) >= r2 {
                    continue;
                }
                let row = (i as usize * self.dims[1] + j as usize) * self.dims[2];
                for k in lo(2)..=hi(2) {
                    let dk = k - c[2];
                    if dk.abs() == skip {
                        continue;
                    }
                    let d2 = dij + dk * dk;
                    if (d2 as f64) < r2 {
                        let u = self.lookup[row + k as usize];
                        if u != NONE {
                            f(u as usize, d2);
                        }
                    }
                }
            }
        }
    }

    /// Every pair of units at index distance exactly 1 (the lattice's 6-neighbourhood).
    pub fn unit_edges(&self) -> Vec<(u32, u32)> {
        let mut edges = Vec::new();
        for (u, iv) in self.index.iter().enumerate() {
            for a in 0..3 {
                let mut n = *iv;
                n[a] += 1;
                if let Some(v) = self.unit_at(n) {
                    edges.push((u as u32, v as u32));
                }
            }
        }
        edges
    }

    /// The edges of [`Lattice::unit_edges`] that lie on the box's outer faces (both ends share a
    /// face coordinate 0 or dims - 1 on an axis the edge does not run along): the lattice's
    /// outer shell, as a picture can show it.
    pub fn shell_edges(&self) -> Vec<(u32, u32)> {
        let on_face = |a: usize, c: i32| c == 0 || c as usize + 1 == self.dims[a];
        self.unit_edges()
            .into_iter()
            .filter(|&(u, v)| {
                let (p, q) = (self.index[u as usize], self.index[v as usize]);
                (0..3).any(|a| p[a] == q[a] && on_face(a, p[a]))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shell_of_a_cube_lattice_has_12_times_n_minus_1_squared_edges() {
        // Six faces of 2n(n-1) edges each, the 12 cube edges' n-1 edges shared by two faces.
        for n in [2usize, 4, 7] {
            let mut index = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    for k in 0..n {
                        index.push([i as i32, j as i32, k as i32]);
                    }
                }
            }
            let l = Lattice::new([n, n, n], index);
            assert_eq!(l.unit_edges().len(), 3 * n * n * (n - 1));
            assert_eq!(l.shell_edges().len(), 12 * (n - 1) * (n - 1), "n = {n}");
        }
    }

    #[test]
    fn neighbourhood_matches_brute_force() {
        let mut index = Vec::new();
        for i in 0..6 {
            for j in 0..5 {
                for k in 0..4 {
                    if (i + j + k) % 3 != 0 {
                        index.push([i, j, k]);
                    }
                }
            }
        }
        let lat = Lattice::new([6, 5, 4], index);
        for centre in 0..lat.len() {
            for radius in [0.5, 1.0, 1.5, 2.0, 2.3, 3.7, 9.0] {
                for skip in [None, Some(1), Some(2)] {
                    let mut got = Vec::new();
                    lat.for_each_within(centre, radius, skip, |u, d2| got.push((u, d2)));
                    got.sort();
                    let ck = lat.index_vector(centre)[2];
                    let want: Vec<_> = (0..lat.len())
                        .filter(|&u| (lat.dist2(centre, u) as f64).sqrt() < radius)
                        .filter(|&u| skip != Some((lat.index_vector(u)[2] - ck).abs()))
                        .map(|u| (u, lat.dist2(centre, u)))
                        .collect();
                    assert_eq!(got, want, "centre {centre} radius {radius} skip {skip:?}");
                }
            }
        }
    }
}
