"""Design sweeps (layer 6): one study file, many cases (gaits, speeds, duty factors, robots,
ground-force settings), run in this process or as tasks of ``dask.distributed``, gathered in one
table with figures.

* :mod:`~hexapod.sweeps.spec`: the study file and its cases;
* :mod:`~hexapod.sweeps.cases`: one case, from its scene to its row;
* :mod:`~hexapod.sweeps.metrics`: what a case keeps;
* :mod:`~hexapod.sweeps.table`: the table and its files;
* :mod:`~hexapod.sweeps.folder`: the output folder, written beside and swapped in whole;
* :mod:`~hexapod.sweeps.cluster`: the Dask cluster, and a scheduler's address and wait;
* :mod:`~hexapod.sweeps.run`: running a study, resuming it;
* :mod:`~hexapod.sweeps.design`, :mod:`~hexapod.sweeps.design_parameters` and
  :mod:`~hexapod.sweeps.metric_derivatives`: design by derivatives (``hexapod
  sensitivity``, ``docs/design.md``), and :mod:`~hexapod.sweeps.optimize` (``hexapod
  optimize``).

``hexapod.sweep`` is :func:`hexapod.sweeps.run.sweep`; ``docs/sweeps.md`` is the user's guide.
"""

from hexapod._support.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod.sweeps.spec": ["Case", "Parameter", "Study", "read_study", "study_from_document"],
    "hexapod.sweeps.run": ["Progress", "SweepRun", "load_study", "run_study", "sweep"],
    "hexapod.sweeps.table": ["SweepTable"],
    "hexapod.sweeps.metrics": ["FAMILIES", "inverse_metrics"],
    "hexapod.sweeps.design": ["SensitivityRun", "sensitivity_run"],
    "hexapod.sweeps.design_parameters": ["inertia_parameters", "moved_model"],
    "hexapod.sweeps.cases": ["with_scene_keys"],
    "hexapod.sweeps.optimize": ["OptimizationRun", "OptimizationStudy", "optimize",
                                "read_optimization"],
    "hexapod.sweeps.metric_derivatives": ["SENSITIVE_FAMILIES", "metric_sensitivities"],
})
