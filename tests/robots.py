"""The walking robot and the built-in scenes the tests read, each assembled once per test
process (one worker of the run).

A model is frozen, and what it builds as it is used (the phase plans of the inverse dynamics,
its evaluated functions) is kept with it: the tests that only read the same robot pay for its
assembly and those builds once, where each module used to pay for them again (the walking
robot's assembly and first inverse dynamics take one to three seconds). Each test still makes
its own workspace (``model.create_data()``, as every run does). A test about building itself (in
threads, into the cache, a fresh model's first call) assembles its own model.
"""

from __future__ import annotations

from functools import cache

import hexapod as hx
from legs.robot import hexapod_scene


@cache
def builtin_model(name: str) -> hx.Model:
    """The built-in scene ``name`` (``hexapod scenes``) assembled."""
    return hx.assemble(hx.load_scene(name))


def walking_robot(gait: str = "tripod", references: tuple = (), **ground) -> hx.Model:
    """The walking robot with a free trunk, its ``gait`` and ground settings (keywords of
    :class:`hexapod.scene.GroundForces`; ``references``: pairs of joint name and reference
    effort). A setting given its default value is the same robot: ``walking_robot()`` and
    ``walking_robot(policy="min-wrench")`` are the built-in ``hexapod``."""
    defaults = hx.scene.GroundForces()
    changed = tuple(sorted((k, v) for k, v in ground.items() if v != getattr(defaults, k)))
    if gait == "tripod" and not references and not changed:
        return builtin_model("hexapod")
    return _walking_robot(gait, references, changed)


@cache
def _walking_robot(gait: str, references: tuple, ground: tuple) -> hx.Model:
    settings = hx.scene.GroundForces(**dict(ground), reference_efforts=dict(references))
    return hx.assemble(hexapod_scene(gait, trunk="free", ground=settings))
