"""somnurbs problems in IOHexperimenter (the ``ioh`` package).

``wrap(p)`` makes an ``ioh`` real-valued problem of a :class:`somnurbs.Problem`: its name and
function id (the IOHprofiler name and id ``somnurbs run`` writes, e.g. ``f1`` and
``cube_20x20_6x6_chord_length``: the problem's place in the spec's order), its
dimension, its box per coordinate and its certified optimum (``p.exact()``). ``Logger`` is an
``ioh.logger.Analyzer`` set up so that ``somnurbs compare --external FOLDER`` can match its
problems with a Chapter 6 results folder: improvements logged at full precision, the suite's
metadata as experiment attributes (spec, profile, reading, box) and each problem's B error,
certified optimum and lower bound as run attributes::

    import somnurbs, somnurbs.ioh_adapter as sio
    log = sio.Logger("ioh_data", "my-optimiser")
    for p in somnurbs.problems("ch6_same", profile="quick"):
        f = sio.wrap(p)
        log.attach(f, p)
        for run in range(3):
            my_optimiser(f, f.bounds.lb, f.bounds.ub, p.x0)
            f.reset()
    log.close()
"""

import ioh

#: The run attributes ``Logger`` writes for every run (``compare`` reads them); the last two only
#: for problems with an exact solver (all of Chapter 6's, none of seed 001's).
RUN_ATTRIBUTES = ("somnurbs_b", "somnurbs_optimum", "somnurbs_bound")
#: The experiment attributes (strings) ``Logger`` writes once per folder.
EXPERIMENT_ATTRIBUTES = ("somnurbs_spec", "somnurbs_profile", "somnurbs_reading", "somnurbs_box")


def box_arrays(problem, box="spec"):
    """(lower, upper) of a box: "spec" (the spec's, what ``somnurbs run`` searches) or "data"."""
    if box == "spec":
        return problem.lower, problem.upper
    if box == "data":
        return problem.lower_data, problem.upper_data
    raise ValueError(f"box must be 'spec' or 'data', got {box!r}")


def box_label(problem, box="spec"):
    """The box in the words ``compare`` checks: the spec's label, or "cover+0e0" for "data"."""
    box_arrays(problem, box)
    return problem.box_label if box == "spec" else "cover+0e0"


def wrap(problem, box="spec", instance=1):
    """An ``ioh`` problem of ``problem`` in ``box`` ("spec" or "data"), minimised, with the
    certified optimum of that box (computed on first use, a second or less per problem; seed
    001's open surfaces have none, and ioh's default stands)."""
    lower, upper = box_arrays(problem, box)
    extra = {}
    if problem.has_exact_solver:
        exact = problem.exact(box)
        x_opt, f_opt = [float(v) for v in exact["x"]], float(exact["f"])
        extra["calculate_objective"] = lambda _instance, _dimension: ioh.RealSolution(x_opt, f_opt)
    fitness = problem.f
    wrapped = ioh.wrap_problem(
        lambda x: fitness(x),
        name=problem.name,
        dimension=problem.dimension,
        instance=instance,
        lb=0.0,
        ub=1.0,
        **extra,
    )
    wrapped.bounds.lb = lower
    wrapped.bounds.ub = upper
    # One numbering with `somnurbs run`'s ioh/: the problem's place in the spec (ioh would give a
    # wrapped problem the first free id of its registry, f1121 and up).
    wrapped.set_id(problem.function_id)
    return wrapped


class Logger:
    """An ``ioh.logger.Analyzer`` writing ``root/folder_name`` (default: the algorithm's name),
    one JSON + ``.dat`` per problem, for ``somnurbs compare --external``. All problems attached
    to one logger must come from one suite (spec, profile, reading) and one box."""

    def __init__(self, root, algorithm_name, algorithm_info="", folder_name=None):
        self.analyzer = ioh.logger.Analyzer(
            triggers=[ioh.logger.trigger.ON_IMPROVEMENT],
            root=str(root),
            folder_name=folder_name or algorithm_name,
            algorithm_name=algorithm_name,
            algorithm_info=algorithm_info,
            store_positions=False,
        )
        self.analyzer.full_precision = True
        self._suite = None
        self._exact = None

    @property
    def output_directory(self):
        return self.analyzer.output_directory

    def attach(self, wrapped, problem, box="spec"):
        """Log ``wrapped`` (from :func:`wrap` of ``problem`` in ``box``) from now on."""
        suite = (problem.spec, problem.profile or "", problem.reading, box_label(problem, box))
        if self._suite is None:
            for name, value in zip(EXPERIMENT_ATTRIBUTES, suite):
                self.analyzer.add_experiment_attribute(name, value)
            self._exact = problem.has_exact_solver
            for name in RUN_ATTRIBUTES if self._exact else RUN_ATTRIBUTES[:1]:
                self.analyzer.add_run_attribute(name, 0.0)
            self._suite = suite
        elif suite != self._suite:
            raise ValueError(
                f"{problem.name}: (spec, profile, reading, box) {suite} differs from this "
                f"logger's {self._suite}: use one Logger per suite"
            )
        exact = problem.exact(box) if self._exact else None
        wrapped.attach_logger(self.analyzer)
        self.analyzer.set_run_attribute("somnurbs_b", float(problem.b))
        if exact is not None:
            self.analyzer.set_run_attribute("somnurbs_optimum", float(exact["f"]))
            self.analyzer.set_run_attribute("somnurbs_bound", float(exact["lower_bound"]))

    def close(self):
        self.analyzer.close()
