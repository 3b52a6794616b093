"""Worked example (issue 39): two optimisers from the Python field on the quick Chapter 6 problems
with certified optima (``ch6_exact --profile quick``: sphere and spindle, 6x6 and 12x12 nets, 156
and 732 variables, the thesis' box B +- 5e-6), logged with ``ioh`` through
``somnurbs.ioh_adapter``, ready to be compared with somnurbs' GA, DE and PSO:

    python python/examples/external_optimisers.py --out target/ioh_external
    somnurbs run experiments/ch6_exact.toml --profile quick --out target/ch6_exact_quick
    somnurbs compare target/ch6_exact_quick --external target/ioh_external

The optimisers, each started as the thesis starts GA, DE and PSO (40 individuals at
B + U[-5e-6, 5e-6] per coordinate, or B itself for CMA-ES's mean), with the same evaluation
budget as the quick protocol (40 + 100 x 40 = 4040 per run) and 3 seeded runs per problem:

- pycma's CMA-ES (``cma``), population 40, step size 0.3 of the box's half-width, in the box
  scaled to [-1, 1] per coordinate; its separable (diagonal) variant above 200 variables, where
  learning a full covariance matrix from a few thousand evaluations is hopeless;
- scipy's ``differential_evolution`` (its default strategy best1bin), the 40-row
  initial population given, no polishing, no early stop.
"""

import argparse
import sys
import time

import numpy as np

import somnurbs
import somnurbs.ioh_adapter as sio

POPULATION = 40
INIT_RANGE = 5e-6


def initial_population(p, lower, upper, rng):
    """The thesis' start: B + U[-r, r] per coordinate, clamped to the box."""
    x = p.x0 + rng.uniform(-INIT_RANGE, INIT_RANGE, size=(POPULATION, p.dimension))
    return np.clip(x, lower, upper)


def run_cma(f, p, lower, upper, budget, seed):
    import warnings

    with warnings.catch_warnings():  # pycma's note that matplotlib (its plots) is missing
        warnings.simplefilter("ignore", UserWarning)
        import cma

    mid, half = (lower + upper) / 2, (upper - lower) / 2
    opts = {
        "bounds": [-1.0, 1.0],
        "popsize": POPULATION,
        "maxfevals": budget,
        "seed": seed,
        "verbose": -9,
        "CMA_diagonal": p.dimension > 200,
        "tolfun": 0,
        "tolx": 0,
        "tolflatfitness": 10**9,
    }
    es = cma.CMAEvolutionStrategy((p.x0 - mid) / half, 0.3, opts)
    used = 0
    while used + POPULATION <= budget:
        z = es.ask()
        es.tell(z, [f(mid + half * np.clip(zi, -1.0, 1.0)) for zi in z])
        used += len(z)


def run_scipy_de(f, p, lower, upper, budget, seed):
    from scipy.optimize import Bounds, differential_evolution

    rng = np.random.default_rng(seed)
    differential_evolution(
        f,
        Bounds(lower, upper),
        init=initial_population(p, lower, upper, rng),
        maxiter=budget // POPULATION - 1,
        polish=False,
        tol=0,
        atol=0,
        seed=seed,
    )


OPTIMISERS = {
    "cma-es": (run_cma, "pycma CMA-ES, popsize 40, sigma0 0.3 of the half box, diagonal above 200 variables"),
    "scipy-de": (run_scipy_de, "scipy differential_evolution best1bin, 40 individuals at B + U[-5e-6, 5e-6], no polish"),
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, help="IOH root folder (one sub-folder per optimiser)")
    ap.add_argument("--spec", default="ch6_exact")
    ap.add_argument("--profile", default="quick")
    ap.add_argument("--evaluations", type=int, default=4040, help="per run (default 4040)")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--optimisers", default=",".join(OPTIMISERS))
    a = ap.parse_args(argv)
    problems = somnurbs.problems(a.spec, profile=a.profile)
    for name in a.optimisers.split(","):
        run, info = OPTIMISERS[name]
        log = sio.Logger(a.out, name, info)
        t0 = time.perf_counter()
        for p in problems:
            f = sio.wrap(p)
            log.attach(f, p)
            lower, upper = p.lower, p.upper
            bests = []
            for r in range(a.runs):
                run(f, p, lower, upper, a.evaluations, 1000 * (r + 1) + 1)
                bests.append(f.state.current_best.y)
                f.reset()
            ex = p.exact()
            print(
                f"{name:9s} {p.name:34s} dim {p.dimension:4d}: B {p.b:.9f}, best of {a.runs} runs "
                f"{min(bests):.9f} (mean {np.mean(bests):.9f}), certified optimum {ex['f']:.9f} "
                f"(bound {ex['lower_bound']:.9f})"
            )
        log.close()
        print(f"{name}: {time.perf_counter() - t0:.1f} s, logged in {log.output_directory}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
