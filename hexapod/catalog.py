"""The names the command line offers before it loads anything heavy, written once: the
ground-force policies and the work-precision problems. Importing this module imports nothing,
so ``hexapod --help`` stays quick; the classes and studies read their names from here."""

#: The ground-force policies (:class:`hexapod.scene.contacts.GroundForces`).
POLICIES = ("min-wrench", "min-effort", "friction")
#: The most faces of a friction pyramid, in a scene file as on the command line (``--faces``):
#: with 1000 faces it is within 5e-6 of the cone (the exact cone, 0, is cheaper still).
MAX_FACES = 1000

#: The problems of ``hexapod bench``, in the order the study runs them
#: (:mod:`hexapod.benchmarks.work_precision` builds them).
PROBLEMS = ("andrews", "seed002", "pendulum", "front-leg")
