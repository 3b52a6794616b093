//! The training loop shared by every model (Section 4.2.6, Eq. 4.9-4.14) and its metrics.
//!
//! Order of random draws (fixed, so a seed reproduces a run): the initial weights, three uniforms
//! in [0,1) per unit in unit order; then one uniform data index per iteration.

use super::Topology;
use crate::geom::Point3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Learning parameters (Table 4.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SomParams {
    /// Maximum iteration T.
    pub iterations: usize,
    /// Initial learning rate alpha0.
    pub alpha0: f64,
    /// Initial radius sigma0; `None` = the model's default (half the smaller grid side).
    pub sigma0: Option<f64>,
    /// Which 3-D SOM units are adjacent for TE (Eq. 4.16): the topology a cell is trained on is
    /// built with it ([`super::Model::topology_with`]); [`train`] asks the topology.
    pub som3d_adjacency: super::LatticeAdjacency,
}

impl Default for SomParams {
    fn default() -> Self {
        SomParams {
            iterations: 30_000,
            alpha0: 0.9,
            sigma0: None,
            som3d_adjacency: super::LatticeAdjacency::N6,
        }
    }
}

/// Metrics taken over the training iterations, as the thesis did (Eq. 4.15, 4.16).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnlineMetrics {
    /// QE = (1/T) sum_t |X(t) - W_c(t)|, measured before the update of iteration t (Eq. 4.15).
    pub qe: f64,
    /// TE = share of iterations whose first and second winners are not adjacent (Eq. 4.16).
    pub te: f64,
    /// min_t |X(t) - W_c(t)|.
    pub min_error: f64,
    /// max_t |X(t) - W_c(t)|.
    pub max_error: f64,
}

/// Standard metrics of the trained map over all data points (MiniSom's definitions of QE: mean
/// Euclidean distance to the best-matching unit; TE: share of points whose two best units are not
/// adjacent, with the model's own adjacency).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FinalMetrics {
    pub(crate) qe: f64,
    pub(crate) te: f64,
}

#[derive(Debug, Clone)]
pub struct TrainResult {
    /// One weight vector per unit.
    pub weights: Vec<Point3>,
    pub online: OnlineMetrics,
}

/// Structure-of-arrays weights: the winner search vectorises over units.
struct Weights {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    d: Vec<f64>,
}

impl Weights {
    fn from_points(points: &[Point3]) -> Weights {
        Weights {
            x: points.iter().map(|p| p[0]).collect(),
            y: points.iter().map(|p| p[1]).collect(),
            z: points.iter().map(|p| p[2]).collect(),
            d: vec![0.0; points.len()],
        }
    }

    /// (winner, its squared distance, second winner); ties go to the lower unit index.
    #[inline]
    fn two_best(&mut self, p: Point3) -> (usize, f64, usize) {
        let n = self.d.len();
        let (xs, ys, zs, ds) = (&self.x[..n], &self.y[..n], &self.z[..n], &mut self.d[..n]);
        for u in 0..n {
            let (dx, dy, dz) = (p[0] - xs[u], p[1] - ys[u], p[2] - zs[u]);
            ds[u] = dx * dx + dy * dy + dz * dz;
        }
        let (mut b1, mut d1, mut b2, mut d2) = (0, f64::INFINITY, 0, f64::INFINITY);
        for (u, &d) in ds.iter().enumerate() {
            if d < d2 {
                if d < d1 {
                    b2 = b1;
                    d2 = d1;
                    b1 = u;
                    d1 = d;
                } else {
                    b2 = u;
                    d2 = d;
                }
            }
        }
        (b1, d1, b2)
    }
}

/// Train `topology` on `data` (Eq. 4.10-4.14): alpha(t) = alpha0 e^{-t/tau},
/// sigma(t) = sigma0 e^{-t/tau}, tau = T / ln sigma0, t = 1..T; every unit u with index distance
/// dist(winner, u) < sigma(t) that the model allows moves by alpha(t) e^{-dist^2 / 2 sigma(t)^2} (X - W_u).
pub fn train(
    topology: &dyn Topology,
    data: &[Point3],
    params: &SomParams,
    rng: &mut ChaCha8Rng,
) -> Result<TrainResult, String> {
    let lattice = topology.lattice();
    let units = lattice.len();
    if data.is_empty() {
        return Err("no data points to train on".into());
    }
    if units < 2 {
        return Err("a map needs at least two units".into());
    }
    let sigma0 = params.sigma0.unwrap_or_else(|| topology.sigma0());
    if sigma0.is_nan() || sigma0 <= 1.0 {
        return Err(format!(
            "initial radius sigma0 = {sigma0} must exceed 1 (tau = T / ln sigma0)"
        ));
    }
    let t_max = params.iterations;
    if t_max == 0 {
        return Err("iterations must be at least 1".into());
    }
    let tau = t_max as f64 / sigma0.ln();

    let init: Vec<Point3> =
        (0..units).map(|_| [rng.gen::<f64>(), rng.gen::<f64>(), rng.gen::<f64>()]).collect();
    let mut w = Weights::from_points(&init);

    let (mut sum_err, mut not_adjacent) = (0.0, 0usize);
    let mut gains: Vec<f64> = Vec::new();
    let frozen = topology.frozen_k_distance();
    let (mut min_err, mut max_err) = (f64::INFINITY, 0.0f64);
    for t in 1..=t_max {
        let x = data[rng.gen_range(0..data.len())];
        let (win, d2, second) = w.two_best(x);
        let err = d2.sqrt();
        sum_err += err;
        min_err = min_err.min(err);
        max_err = max_err.max(err);
        if !topology.adjacent(win, second) {
            not_adjacent += 1;
        }
        let decay = (-(t as f64) / tau).exp();
        let alpha = params.alpha0 * decay;
        let sigma = sigma0 * decay;
        let inv_two_sigma2 = 1.0 / (2.0 * sigma * sigma);
        // dist^2 is an integer below sigma^2: tabulate the gains once per iteration (the same
        // expression, so the same bits, as computing each one on its own).
        gains.clear();
        gains.extend(
            (0..=(sigma * sigma).ceil() as usize)
                .map(|d2| alpha * (-(d2 as f64) * inv_two_sigma2).exp()),
        );
        lattice.for_each_within(win, sigma, frozen, |u, dist2| {
            let g = gains[dist2 as usize];
            w.x[u] += g * (x[0] - w.x[u]);
            w.y[u] += g * (x[1] - w.y[u]);
            w.z[u] += g * (x[2] - w.z[u]);
        });
    }
    let weights = (0..units).map(|u| [w.x[u], w.y[u], w.z[u]]).collect();
    let online = OnlineMetrics {
        qe: sum_err / t_max as f64,
        te: not_adjacent as f64 / t_max as f64,
        min_error: min_err,
        max_error: max_err,
    };
    Ok(TrainResult { weights, online })
}

/// QE and TE of a trained map over every data point.
pub(crate) fn final_map_metrics(
    topology: &dyn Topology,
    weights: &[Point3],
    data: &[Point3],
) -> FinalMetrics {
    let mut w = Weights::from_points(weights);
    let (mut sum, mut bad) = (0.0, 0usize);
    for &p in data {
        let (b1, d1, b2) = w.two_best(p);
        sum += d1.sqrt();
        if !topology.adjacent(b1, b2) {
            bad += 1;
        }
    }
    let n = data.len().max(1) as f64;
    FinalMetrics { qe: sum / n, te: bad as f64 / n }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::som::Model;
    use rand::SeedableRng;

    fn sphere_points(n: usize) -> Vec<Point3> {
        // Fibonacci sphere centred in the unit cube.
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|k| {
                let y = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
                let r = (1.0 - y * y).sqrt();
                let th = golden * k as f64;
                [0.5 + 0.5 * r * th.cos(), 0.5 + 0.5 * y, 0.5 + 0.5 * r * th.sin()]
            })
            .collect()
    }

    #[test]
    fn same_seed_same_map_and_training_reduces_error() {
        let data = sphere_points(2000);
        let topo = Model::Dnsom.topology(10, 10).unwrap();
        let p = SomParams { iterations: 4000, ..Default::default() };
        let a = train(topo.as_ref(), &data, &p, &mut ChaCha8Rng::seed_from_u64(7)).unwrap();
        let b = train(topo.as_ref(), &data, &p, &mut ChaCha8Rng::seed_from_u64(7)).unwrap();
        assert_eq!(a.weights, b.weights);
        assert_eq!(a.online, b.online);
        let random =
            final_map_metrics(
                topo.as_ref(),
                &a.weights[..0]
                    .iter()
                    .copied()
                    .chain((0..a.weights.len()).map(|u| {
                        [(u % 7) as f64 / 7.0, (u % 5) as f64 / 5.0, (u % 3) as f64 / 3.0]
                    }))
                    .collect::<Vec<_>>(),
                &data,
            );
        let trained = final_map_metrics(topo.as_ref(), &a.weights, &data);
        assert!(trained.qe < 0.5 * random.qe, "trained {trained:?} vs untrained {random:?}");
        assert!(a.online.min_error <= a.online.qe && a.online.qe <= a.online.max_error);
        assert!((0.0..=1.0).contains(&a.online.te));
    }

    #[test]
    fn all_units_within_radius_move_toward_input_once() {
        // With T = 1 the update is one step: check it against Eq. 4.10-4.11 by hand.
        let data = vec![[0.25, 0.5, 0.75]];
        let topo = Model::Som2d.topology(6, 6).unwrap();
        let p = SomParams { iterations: 1, alpha0: 0.9, ..Default::default() };
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let r = train(topo.as_ref(), &data, &p, &mut rng).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let init: Vec<Point3> = (0..36).map(|_| [rng.gen(), rng.gen(), rng.gen()]).collect();
        let win = (0..36)
            .min_by(|&a, &b| {
                crate::geom::dist2(init[a], data[0])
                    .total_cmp(&crate::geom::dist2(init[b], data[0]))
            })
            .unwrap();
        let (sigma0, tau) = (3.0f64, 1.0 / 3f64.ln());
        let decay = (-1.0 / tau).exp();
        let (alpha, sigma) = (0.9 * decay, sigma0 * decay);
        for u in 0..36 {
            let d2 = topo.lattice().dist2(win, u) as f64;
            let g =
                if d2.sqrt() < sigma { alpha * (-d2 / (2.0 * sigma * sigma)).exp() } else { 0.0 };
            for a in 0..3 {
                let want = init[u][a] + g * (data[0][a] - init[u][a]);
                assert!((r.weights[u][a] - want).abs() < 1e-15, "unit {u}");
            }
        }
    }

    #[test]
    fn dnsom_winner_never_moves_opposite_interior() {
        // T = 2, sigma0 = 16: step 1 has sigma = 4, step 2 sigma = 1 (only its winner moves).
        // Apart from step 2's winner, a unit moves iff dist < 4 and K != 2 (Section 4.2.4).
        let topo = Model::Dnsom.topology(6, 6).unwrap();
        let lat = topo.lattice();
        let p = SomParams { iterations: 2, alpha0: 0.9, sigma0: Some(16.0), ..Default::default() };
        let sigma = 4.0;
        let mut saw_blocked = false;
        for seed in 0..40 {
            let data = vec![[0.5, 0.5, (seed % 5) as f64 / 4.0]];
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let r = train(topo.as_ref(), &data, &p, &mut rng).unwrap();
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let init: Vec<Point3> =
                (0..lat.len()).map(|_| [rng.gen(), rng.gen(), rng.gen()]).collect();
            let win = (0..lat.len())
                .min_by(|&a, &b| {
                    crate::geom::dist2(init[a], data[0])
                        .total_cmp(&crate::geom::dist2(init[b], data[0]))
                })
                .unwrap();
            let win2 = (0..lat.len())
                .min_by(|&a, &b| {
                    crate::geom::dist2(r.weights[a], data[0])
                        .total_cmp(&crate::geom::dist2(r.weights[b], data[0]))
                })
                .unwrap();
            for u in (0..lat.len()).filter(|&u| u != win2) {
                let k_gap = (lat.index_vector(win)[2] - lat.index_vector(u)[2]).abs();
                let within = (lat.dist2(win, u) as f64).sqrt() < sigma;
                saw_blocked |= within && k_gap == 2;
                assert_eq!(r.weights[u] != init[u], within && k_gap != 2, "seed {seed} unit {u}");
            }
        }
        assert!(saw_blocked, "no case exercised the K != 2 rule");
    }
}
