"""somnurbs: the thesis' surface-fitting problems as a benchmark suite.

Every control-net problem of a Chapter 6 spec (SOM map of a data set, cubic B-spline control net,
parameterisation, knot reading), built by the same Rust code that ``somnurbs run`` uses, so that
``p.f(x)`` is bit for bit the CLI's fitness on the same machine::

    import somnurbs
    for p in somnurbs.problems("ch6_same", profile="quick"):
        print(p.name, p.dimension, p.b, p.f(p.x0))

``p.f`` takes one point (1-D array) or a batch (2-D array, one point per row; read in place when
C-contiguous float64) and releases the GIL. ``p.lower``/``p.upper`` is the spec's box (the thesis'
B +- 5e-6), ``p.lower_data``/``p.upper_data`` the data-range box, ``p.exact()`` the certified
optimum and lower bound. ``somnurbs.ioh_adapter`` makes IOHexperimenter problems and loggers whose
folders ``somnurbs compare --external`` reads. See docs/python.md.
"""

from ._native import SPECS, Problem, __version__, problems

# SPECS: the shipped specs with control-net problems, carried inside the package (a clone's
# experiments/<name>.toml is preferred when run from its top): Chapter 6's, and seed 001's open
# surfaces (one view, no exact solver). Notes and progress lines (a map recomputed) go to the
# `logging` logger "somnurbs".

__all__ = ["Problem", "problems", "SPECS", "__version__"]
