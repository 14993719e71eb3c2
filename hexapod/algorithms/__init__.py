"""The algorithms (layer 3): saddle-point solves, kinematics, forward and inverse dynamics,
liaison forces, balance and topology. Each reads a ``Model`` and a ``Data`` workspace, never a
``Scene``, and never writes to the model."""
