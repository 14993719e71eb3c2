"""The cases with independent references and the studies on them (layer 6): the extreme-case
check and the work-precision study.

The extreme-case suite: every builder returns a :class:`Case` (a scene, how long to run it, what is
extreme about it, and a reference independent of the engine; :mod:`hexapod.benchmarks.reference`
says how the references are built), and :func:`suite` lists them all.

====================================  ==========  =============================================
case                                  category    reference
====================================  ==========  =============================================
:func:`stiff_slider` (k = 1e3..1e9)   stiff       damped oscillator, closed form
:func:`stiff_spring_pendulum`         stiff       2-DOF Lagrange (theta, s) by hand, DOP853
:func:`flyball_governor` (A05)        stiff       symmetric reduction (Routh), Radau at 1e-12
:func:`n_four_bar` (A02)              singular /  1-DOF equation of the parallelogram chain,
                                      redundant   DOP853 at 1e-12
:func:`bricard` (A04)                 redundant   1-DOF Lagrange on the closed-form configuration
                                                  curve ``sin t1 + sin t2 + sin t1 sin t2 = 0``
:func:`four_bar_dead_points`          singular    1-DOF Lagrange on the anti-parallelogram's
                                                  rational branch (free or driven)
:func:`mass_ratio`                    mass-ratio  5-DOF joint-coordinate Lagrange (Kane)
:func:`mass_ratio_pendulum`           mass-ratio  double pendulum, Lagrange in closed form
:func:`stretched_leg`                 singular    1-DOF Lagrange by hand (free) or closed
                                                  form (driven)
:func:`long_pendulum`                 long        Jacobi elliptic functions
:func:`large_step_pendulum`           large-step  Jacobi elliptic functions
====================================  ==========  =============================================

The modules: :mod:`~hexapod.benchmarks.reference` (the case and the minimal-coordinate machinery)
and :mod:`~hexapod.benchmarks.jets` (Taylor jets) below the cases, one module per category
(:mod:`~hexapod.benchmarks.stiff`, :mod:`~hexapod.benchmarks.singular`,
:mod:`~hexapod.benchmarks.redundant`, :mod:`~hexapod.benchmarks.mass_ratios`,
:mod:`~hexapod.benchmarks.pendulums`, which also holds the exact pendulum :func:`pendulum_exact`
and the closed-loop pendulum of Richard, Anderson and Andrews, :class:`ClosedLoopPendulum`, used
by the studies), and :mod:`~hexapod.benchmarks.cases` for :func:`suite`. The case modules import
nothing of the engine but the scene layer. The studies are the extreme-case check
(:mod:`~hexapod.benchmarks.check`, with :mod:`~hexapod.benchmarks.stable_steps`) and the
work-precision study (:mod:`~hexapod.benchmarks.work_precision`).
"""

from hexapod._support.lazy import attach

# lazy, so that the command line reads the catalogue of studies without loading NumPy
__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod.benchmarks.cases": ["suite"],
    "hexapod.benchmarks.mass_ratios": ["mass_ratio", "mass_ratio_pendulum"],
    "hexapod.benchmarks.pendulums": ["ClosedLoopPendulum", "large_step_pendulum", "long_pendulum",
                                     "pendulum_exact", "pendulum_period"],
    "hexapod.benchmarks.redundant": ["bricard"],
    "hexapod.benchmarks.reference": ["CATEGORIES", "Case"],
    "hexapod.benchmarks.singular": ["four_bar_dead_points", "n_four_bar", "stretched_leg"],
    "hexapod.benchmarks.stiff": ["flyball_governor", "stiff_slider", "stiff_spring_pendulum"],
    "hexapod.benchmarks.work_precision": ["andrews_problem"],
})
