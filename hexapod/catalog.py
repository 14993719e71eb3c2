"""The names the command line offers before it loads anything heavy, written once: the
ground-force policies and the work-precision problems. Importing this module imports nothing,
so ``hexapod --help`` stays quick; the classes and studies read their names from here."""

#: The ground-force policies (:class:`hexapod.scene.contacts.GroundForces`).
POLICIES = ("min-wrench", "min-effort", "friction")

#: The problems of ``hexapod bench``, in the order the study runs them
#: (:mod:`hexapod.benchmarks.work_precision` builds them).
PROBLEMS = ("andrews", "seed002", "pendulum", "front-leg")
