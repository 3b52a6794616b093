//! Fritzke's Growing Grid (B. Fritzke, "Growing Grid - a self-organizing network with constant
//! neighborhood range and adaptation strength", Neural Processing Letters 2(5), 1995), used by
//! seed 001 to organise open-surface data into a rectangular map.
//!
//! The algorithm, with every constant in [`GrowingGridParams`]:
//! 1. Start with a 2 x 2 grid whose weights are four data points drawn uniformly (with
//!    replacement) from the data.
//! 2. Growth phase. Repeat: run `lambda_g * N` adaptation steps (N = current number of units) with
//!    constant learning rate `eps_g` and constant Gaussian neighbourhood
//!    h = exp(-d^2 / (2 sigma^2)) over the grid index distance d (units with d^2 > `reach2` are
//!    not moved); every step adds |x - w_c|^2 to the winner's resource counter tau_c. Then take
//!    the unit q with the largest tau, its direct (4-)neighbour f with the largest weight distance
//!    |w_q - w_f| among the directions that may still grow, and insert a whole row (f above or
//!    below q) or column (f left or right of q) between them; the new units' weights are the
//!    means of their two neighbours in that direction. All counters are reset. Stopping rule: a
//!    direction may grow while its side is below the target side; the phase ends when the grid
//!    has the target size `nx x ny`.
//! 3. Fine-tuning phase: `lambda_f * N` steps with the same neighbourhood and a learning rate
//!    decaying exponentially from `eps_f0` to `eps_f1`, eps(t) = eps_f0 (eps_f1/eps_f0)^(t/T).
//!
//! Random draws in order: the four initial data indices, then one data index per step.
//!
//! The growing grid does not implement [`super::Topology`]: that trait describes a lattice of fixed
//! size trained by the shared loop in [`super::train`] with a shrinking radius, whereas this map
//! changes its size during training and keeps its radius constant. The finished map is a plain
//! `nx x ny` 2-D SOM lattice, so its quality is measured by the shared
//! [`super::final_map_metrics`] on [`super::som2d::Som2d`] (QE: mean distance to the winner; TE:
//! share of points whose two best units are not 4-neighbours).

use super::som2d::Som2d;
use super::{final_map_metrics, FinalMetrics};
use crate::geom::{self, Point3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Constants of the growing grid. Defaults: Fritzke's constant sigma of the neighbourhood and
/// lambda_g = 30 steps per unit between insertions; the learning rates are this project's choice
/// (the surviving seed gives none), see the module doc.
///
/// A spec's `[growing_grid.growth]` table reads the constants (the target size is its `grid`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GrowingGridParams {
    /// Target size (rows nx along i, columns ny along j); both at least 2.
    #[serde(skip)]
    pub nx: usize,
    #[serde(skip)]
    pub ny: usize,
    /// Adaptation steps per unit between two insertions.
    pub lambda_g: usize,
    /// Constant learning rate of the growth phase.
    pub eps_g: f64,
    /// Fine-tuning steps per unit of the final grid.
    pub lambda_f: usize,
    /// Fine-tuning learning rate: start and end of the exponential decay.
    pub eps_f0: f64,
    pub eps_f1: f64,
    /// Width of the Gaussian neighbourhood (grid units), constant in both phases.
    pub sigma: f64,
    /// Units with squared index distance above this are not moved (the Gaussian is below 0.02
    /// there for sigma = 0.7 and reach2 = 4).
    pub reach2: i32,
}

impl Default for GrowingGridParams {
    fn default() -> Self {
        GrowingGridParams {
            nx: 20,
            ny: 20,
            lambda_g: 30,
            eps_g: 0.05,
            lambda_f: 100,
            eps_f0: 0.05,
            eps_f1: 0.0005,
            sigma: 0.7,
            reach2: 4,
        }
    }
}

/// A grown map: `nx x ny` weights, row-major (unit (i, j) at `i * ny + j`).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct GrowingGrid {
    pub(crate) nx: usize,
    pub(crate) ny: usize,
    pub(crate) weights: Vec<Point3>,
    /// Rows and columns inserted.
    pub(crate) insertions: usize,
    /// Adaptation steps of the growth and fine-tuning phases.
    pub(crate) growth_steps: usize,
    pub(crate) fine_steps: usize,
}

impl GrowingGrid {
    /// QE and TE over the data with the shared 2-D SOM definitions.
    pub(crate) fn metrics(&self, data: &[Point3]) -> FinalMetrics {
        final_map_metrics(&Som2d::new(self.nx, self.ny), &self.weights, data)
    }
}

impl GrowingGridParams {
    pub fn validate(&self) -> Result<(), String> {
        if self.nx < 2 || self.ny < 2 {
            return Err(format!(
                "target grid {}x{} is too small: both sides must be at least 2",
                self.nx, self.ny
            ));
        }
        if self.lambda_g == 0 {
            return Err("lambda_g must be at least 1".into());
        }
        for (k, v) in [("eps_g", self.eps_g), ("eps_f0", self.eps_f0), ("eps_f1", self.eps_f1)] {
            if !(v > 0.0 && v <= 1.0) {
                return Err(format!("{k} must be in (0, 1], got {v}"));
            }
        }
        if !(self.sigma > 0.0 && self.sigma.is_finite()) {
            return Err(format!("sigma must be a positive number, got {}", self.sigma));
        }
        if self.reach2 < 0 {
            return Err(format!("reach2 must be >= 0, got {}", self.reach2));
        }
        Ok(())
    }
}

fn mid(a: Point3, b: Point3) -> Point3 {
    geom::scale(geom::add(a, b), 0.5)
}

struct State {
    nx: usize,
    ny: usize,
    w: Vec<Point3>,
    tau: Vec<f64>,
}

impl State {
    fn winner(&self, x: Point3) -> usize {
        let mut best = (0, f64::INFINITY);
        for (u, w) in self.w.iter().enumerate() {
            let d = geom::dist2(*w, x);
            if d < best.1 {
                best = (u, d);
            }
        }
        best.0
    }

    fn adapt(&mut self, x: Point3, eps: f64, p: &GrowingGridParams, gauss: &[f64]) {
        let c = self.winner(x);
        self.tau[c] += geom::dist2(self.w[c], x);
        let (ci, cj) = ((c / self.ny) as i32, (c % self.ny) as i32);
        let r = (p.reach2 as f64).sqrt().floor() as i32;
        for i in (ci - r).max(0)..=(ci + r).min(self.nx as i32 - 1) {
            for j in (cj - r).max(0)..=(cj + r).min(self.ny as i32 - 1) {
                let d2 = (i - ci) * (i - ci) + (j - cj) * (j - cj);
                if d2 > p.reach2 {
                    continue;
                }
                let h = eps * gauss[d2 as usize];
                let w = &mut self.w[i as usize * self.ny + j as usize];
                for k in 0..3 {
                    w[k] += h * (x[k] - w[k]);
                }
            }
        }
    }

    /// Insert a row (axis 0) or column (axis 1) between index `a` and `a + 1`.
    fn insert(&mut self, axis: usize, a: usize) {
        let (nx, ny) = (self.nx, self.ny);
        let mut w = Vec::with_capacity((nx + 1) * (ny + 1));
        if axis == 0 {
            for i in 0..=nx {
                for j in 0..ny {
                    w.push(match i.cmp(&(a + 1)) {
                        std::cmp::Ordering::Less => self.w[i * ny + j],
                        std::cmp::Ordering::Equal => {
                            mid(self.w[a * ny + j], self.w[(a + 1) * ny + j])
                        }
                        std::cmp::Ordering::Greater => self.w[(i - 1) * ny + j],
                    });
                }
            }
            self.nx += 1;
        } else {
            for i in 0..nx {
                for j in 0..=ny {
                    w.push(match j.cmp(&(a + 1)) {
                        std::cmp::Ordering::Less => self.w[i * ny + j],
                        std::cmp::Ordering::Equal => {
                            mid(self.w[i * ny + a], self.w[i * ny + a + 1])
                        }
                        std::cmp::Ordering::Greater => self.w[i * ny + j - 1],
                    });
                }
            }
            self.ny += 1;
        }
        self.w = w;
        self.tau = vec![0.0; self.w.len()];
    }
}

/// Grow a grid over `data` (at least one point) with the stream `rng`.
pub(crate) fn grow(
    data: &[Point3],
    p: &GrowingGridParams,
    rng: &mut ChaCha8Rng,
) -> Result<GrowingGrid, String> {
    p.validate()?;
    if data.is_empty() {
        return Err("no data points".into());
    }
    let gauss: Vec<f64> =
        (0..=p.reach2).map(|d2| (-(d2 as f64) / (2.0 * p.sigma * p.sigma)).exp()).collect();
    let mut s = State {
        nx: 2,
        ny: 2,
        w: (0..4).map(|_| data[rng.gen_range(0..data.len())]).collect(),
        tau: vec![0.0; 4],
    };
    let (mut insertions, mut growth_steps) = (0, 0);
    while s.nx < p.nx || s.ny < p.ny {
        let steps = p.lambda_g * s.w.len();
        for _ in 0..steps {
            let x = data[rng.gen_range(0..data.len())];
            s.adapt(x, p.eps_g, p, &gauss);
        }
        growth_steps += steps;
        // The unit with the largest resource; ties go to the lower index.
        let q = (0..s.tau.len()).fold(0, |b, u| if s.tau[u] > s.tau[b] { u } else { b });
        let (qi, qj) = (q / s.ny, q % s.ny);
        let mut best: Option<(f64, usize, usize)> = None; // (distance, axis, lower index)
        let mut consider = |axis: usize, ni: usize, nj: usize, low: usize| {
            let d = geom::dist2(s.w[q], s.w[ni * s.ny + nj]);
            if best.is_none_or(|b| d > b.0) {
                best = Some((d, axis, low));
            }
        };
        if s.nx < p.nx {
            if qi > 0 {
                consider(0, qi - 1, qj, qi - 1);
            }
            if qi + 1 < s.nx {
                consider(0, qi + 1, qj, qi);
            }
        }
        if s.ny < p.ny {
            if qj > 0 {
                consider(1, qi, qj - 1, qj - 1);
            }
            if qj + 1 < s.ny {
                consider(1, qi, qj + 1, qj);
            }
        }
        let (_, axis, low) = best.ok_or("no direction may grow")?;
        s.insert(axis, low);
        insertions += 1;
    }
    let fine_steps = p.lambda_f * s.w.len();
    for t in 0..fine_steps {
        let eps = p.eps_f0 * (p.eps_f1 / p.eps_f0).powf(t as f64 / fine_steps as f64);
        let x = data[rng.gen_range(0..data.len())];
        s.adapt(x, eps, p, &gauss);
    }
    Ok(GrowingGrid { nx: s.nx, ny: s.ny, weights: s.w, insertions, growth_steps, fine_steps })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn plane(n: usize) -> Vec<Point3> {
        // An n x n lattice on the unit square in the plane z = 0.3 x + 0.1 y.
        (0..n * n)
            .map(|k| {
                let (x, y) = ((k / n) as f64 / (n - 1) as f64, (k % n) as f64 / (n - 1) as f64);
                [x, y, 0.3 * x + 0.1 * y]
            })
            .collect()
    }

    #[test]
    fn grows_to_target_and_orders_a_plane_patch() {
        let data = plane(40);
        let p = GrowingGridParams { nx: 8, ny: 6, ..GrowingGridParams::default() };
        let g = grow(&data, &p, &mut ChaCha8Rng::seed_from_u64(7)).unwrap();
        assert_eq!((g.nx, g.ny, g.weights.len()), (8, 6, 48));
        assert_eq!(g.insertions, 6 + 4);
        assert_eq!(g.fine_steps, 100 * 48);
        let m = g.metrics(&data);
        assert!(m.te < 0.05, "topographic error {}", m.te);
        // 48 units over a unit-square patch: spacing ~ 1/7 x 1/5; QE well below one spacing.
        assert!(m.qe < 0.08, "quantisation error {}", m.qe);
        // Ordered: along every row and every column the map is monotone in one data coordinate.
        let mut row_mono = 0;
        for i in 0..g.nx {
            let row: Vec<Point3> = (0..g.ny).map(|j| g.weights[i * g.ny + j]).collect();
            let inc = (0..2).any(|k| {
                row.windows(2).all(|w| w[1][k] > w[0][k])
                    || row.windows(2).all(|w| w[1][k] < w[0][k])
            });
            row_mono += inc as usize;
        }
        assert_eq!(row_mono, g.nx, "every row should be monotone in x or y");
    }

    #[test]
    fn deterministic_per_seed() {
        let data = plane(20);
        let p = GrowingGridParams { nx: 5, ny: 4, lambda_f: 20, ..GrowingGridParams::default() };
        let a = grow(&data, &p, &mut ChaCha8Rng::seed_from_u64(3)).unwrap();
        let b = grow(&data, &p, &mut ChaCha8Rng::seed_from_u64(3)).unwrap();
        let c = grow(&data, &p, &mut ChaCha8Rng::seed_from_u64(4)).unwrap();
        assert_eq!(a, b);
        assert_ne!(a.weights, c.weights);
    }

    #[test]
    fn insertion_averages_neighbours_and_validation_names_the_constant() {
        let mut s = State {
            nx: 2,
            ny: 2,
            w: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [1.0, 2.0, 0.0]],
            tau: vec![0.0; 4],
        };
        s.insert(0, 0);
        assert_eq!((s.nx, s.ny), (3, 2));
        assert_eq!(s.w[2], [0.0, 1.0, 0.0]);
        assert_eq!(s.w[3], [1.0, 1.0, 0.0]);
        s.insert(1, 0);
        assert_eq!(s.w[4], [0.5, 1.0, 0.0]);
        let bad = GrowingGridParams { eps_g: 0.0, ..GrowingGridParams::default() };
        assert!(bad.validate().unwrap_err().contains("eps_g"));
        assert!(
            grow(&[], &GrowingGridParams::default(), &mut ChaCha8Rng::seed_from_u64(1)).is_err()
        );
    }
}
