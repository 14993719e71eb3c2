"""The names of the work-precision problems, importing nothing, so that the command line lists
them in its help without loading CasADi or SciPy (:mod:`hexapod.benchmarks.work_precision`
builds them)."""

#: The problems of ``hexapod bench``, in the order the study runs them.
PROBLEMS = ("andrews", "seed002", "pendulum", "front-leg")
