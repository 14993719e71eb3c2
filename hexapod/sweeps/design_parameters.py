"""Design parameters named by scene keys (``body.femur.mass``), ``*`` matching any element name.

The keys are those of a study (:func:`hexapod.sweeps.cases.set_scene_key`): a dotted path into
the scene's TOML form. Sensitivities cover the bodies' inertia and the joints' positions:

* ``body.NAME.mass`` (kg);
* ``body.NAME.inertia``: every component as the scene gives it (3 principal moments or the 6
  entries ``xx yy zz xy xz yz`` of a spatial body, in its ``inertia_rotation`` axes; a planar
  body's one moment), each a parameter ``body.NAME.inertia.K``; ``body.NAME.inertia.K`` names
  one. Values and derivatives are in SI (kg m^2) whatever the scene's length unit, as every
  output (``InertiaChange.scene_scale`` converts to the scene's kg L^2);
* ``joint.NAME.origin`` (``.K``: one component): a joint's origin, world axes at the initial
  pose, moved on both its bodies; ``joint.NAME.parent_frame.position`` (``child_frame``): its
  frame's origin on one body, in that body's axes, as a segment's length (m,
  :class:`~hexapod.algorithms.sensitivity.FrameChange`);
* ``ground.mu``: the friction coefficient, which bounds the friction policy's forces;
* ``gait.period`` (s; ``period``, the built-in walking scenes' builder argument, alike): the
  gait's period, the motion kept at the same fractions of the stride
  (:class:`~hexapod.algorithms.sensitivity.PeriodChange`: a scene whose laws all follow the
  gait's phase, as the gait builders make them);
* ``geometric_scale`` (1: the scene as given): every length times ``s``, masses times
  ``s^3``, inertias times ``s^5``, the motion's times kept
  (:class:`~hexapod.algorithms.sensitivity.ScaleChange`); with the period's half, the Froude
  scaling whose forces go as ``s^3`` and torques as ``s^4``;
* ``gait.duty`` (1): the gait's duty factor, its stride and period kept, the footholds centred
  on their stances (:mod:`legs.duty`): the feet's paths, the coupled joints, the contacts'
  footholds and load-sharing weights all follow; the scene's characteristic length held;
* ``gait.stride`` (m): the gait's stride, its period and duty factor kept (so its speed
  changes), the footholds centred on their stances: the feet's paths along the walk, the
  contacts' footholds and the trunk's speed follow;
* ``payload`` (kg): the load the body with a ``payload`` key carries at its centre of mass
  (the walking robot's builders put it on the trunk), part of its mass;
* ``gait.step_height`` (m; ``step_height``, alike): the feet's lift in swing, held by the
  feet's paths (the laws whose :meth:`~hexapod.scene.Law.design_parameter` answers to it;
  :class:`~hexapod.algorithms.sensitivity.LawChange`): the joints follow the paths, and the
  motion's and forces' derivatives are the phase path's
  (:mod:`hexapod.algorithms.law_tangents`).

A glob that matches bodies without the key (a particle has no inertia) skips them; a name that
matches nothing, or a key sensitivities do not cover, is refused.
"""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from fnmatch import fnmatchcase
from typing import TYPE_CHECKING

import numpy as np

from hexapod.algorithms.sensitivity import (
    FrameChange,
    FrictionChange,
    InertiaChange,
    LawChange,
    PeriodChange,
    ScaleChange,
)
from hexapod.scene.bodies import Particle, PlanarBody, inertia_tensor
from hexapod.scene.element import GROUND
from hexapod.sweeps.cases import StudyError

if TYPE_CHECKING:
    from hexapod.model.model import Model
    from hexapod.scene.scene import Scene

_COVERED = ("masses and inertias, body.NAME.mass and body.NAME.inertia[.K], and joints' "
            "positions, joint.NAME.origin[.K] or joint.NAME.parent_frame.position[.K] "
            "(child_frame) ('*' matches any NAME), the friction coefficient, ground.mu, the "
            "gait's period, step height, duty factor and stride, gait.period, "
            "gait.step_height, gait.duty and gait.stride (or period and step_height), the "
            "geometric scale, geometric_scale, and the payload, payload")


def inertia_parameters(scene: Scene, patterns: Sequence[str],
                       source: str = "--parameters"
                       ) -> tuple[InertiaChange | FrameChange | FrictionChange, ...]:
    """The parameters ``patterns`` name in ``scene``, in the order named, each once.

    Parameters
    ----------
    scene : Scene
    patterns : sequence of str
        Scene keys, ``*`` matching any body name.
    source : str
        What gave them, for the messages.

    Returns
    -------
    tuple of InertiaChange, FrameChange or FrictionChange

    Raises
    ------
    StudyError
        A key sensitivities do not cover, a body name that matches nothing, a component that
        does not exist; one message naming ``source`` and the key.
    """
    from hexapod.scene.writer import scene_text

    document = tomllib.loads(scene_text(scene))
    bodies = {b["name"]: b for b in document.get("body", [])}
    joints = {j["name"]: j for j in document.get("joint", [])}
    found: dict[str, InertiaChange | FrameChange | FrictionChange] = {}
    for pattern in patterns:
        if pattern == "ground.mu":
            found.setdefault(pattern, FrictionChange(value=float(scene.ground.mu)))
            continue
        if pattern in ("gait.period", "period"):  # a scene key, or a builder's argument
            found.setdefault(pattern, _period(scene, pattern, source))
            continue
        if pattern == "duty":  # the built-in walking robot's builder argument: not gait.duty
            raise StudyError(f"{source}: 'duty', the built-in walking robot's builder argument, "
                             "keeps its stance's length, so its stride changes with it: not a "
                             "parameter sensitivities cover; gait.duty keeps the stride and "
                             "period (the footholds centred on their stances), and the "
                             "builder's duty is gait.duty - (stride / duty) gait.stride")
        if pattern in _LAW_PARAMETERS:
            found.setdefault(pattern, _law_change(scene, pattern, source))
            continue
        if pattern == "payload":  # a builder's argument: the load its body carries
            found.setdefault(pattern, _payload(scene, source))
            continue
        if pattern == "geometric_scale":  # every length, masses and inertias with them
            total = sum(float(b.mass) for b in scene.bodies.values())
            found.setdefault(pattern, ScaleChange(pattern, mass=3.0 * total))
            continue
        parts = pattern.split(".")
        section = parts[0]
        if _kind(parts) is None:
            raise StudyError(f"{source}: '{pattern}' is not a parameter sensitivities cover: "
                             f"{_COVERED}")
        elements = bodies if section == "body" else joints
        names = [n for n in elements if fnmatchcase(n, parts[1])]
        if not names:
            shown = ", ".join(list(elements)[:8]) + (", ..." if len(elements) > 8 else "")
            raise StudyError(f"{source}: '{pattern}': no {section} matches '{parts[1]}' "
                             f"({section}s: {shown or 'none'})")
        glob = len(names) > 1 or names[0] != parts[1]
        for name in names:
            changes = (_changes(scene, bodies[name], parts, pattern, source, glob)
                       if section == "body" else
                       _origin_changes(scene, joints[name], parts, pattern, source))
            for change in changes:
                found.setdefault(change.name, change)
    return tuple(found.values())


def moved_model(scene: Scene, model, changes) -> Model | None:
    """``scene`` assembled again with the joints ``changes`` move outside the tree path (a
    model whose loops close, feet stand or joints follow guides: ``model``, assembled from
    it) shifted by symbols, for :func:`hexapod.inverse_sensitivities` (``moved``); None when
    none does."""
    from hexapod.algorithms.sensitivity import tree_solved
    from hexapod.model.assemble import assemble
    from hexapod.scene.laws.base import DesignShift

    frames = [c for c in changes if isinstance(c, FrameChange)] if not tree_solved(model) \
        else []
    scaled = next((DesignShift(c.name) for c in changes if isinstance(c, ScaleChange)), None)
    if not frames and scaled is None:
        return None
    moved = tuple((c.joint, c.parent, c.child, DesignShift(c.name)) for c in frames)
    return assemble(scene, rank_tolerance=model.rank_tolerance, moved_frames=moved,
                    scaled=scaled)


def _period(scene: Scene, name: str, source: str) -> PeriodChange:
    """The gait's period (parameter ``name``): the one its periodic laws share."""
    from hexapod.model.assemble import assemble

    period = assemble(scene).cycle_time()
    if period is None:
        raise StudyError(f"{source}: '{name}': scene '{scene.name}' has no gait (no law of it "
                         "repeats)")
    for driver in scene.drivers.values():  # a law planned for its period does not follow it
        law = getattr(driver, "law", None)
        try:
            if law is not None:
                law.design_parameter("gait.period")
        except ValueError as error:
            raise StudyError(f"{source}: '{name}': driver '{driver.name}' of scene "
                             f"'{scene.name}': {error}") from None
    return PeriodChange(name=name, value=float(period))


#: The parameters that change the scene's laws: name -> (the scene key the laws answer to
#: (:meth:`hexapod.scene.Law.design_parameter`), its SI unit, whether a length). A builder's
#: argument (``step_height``) names its scene key's parameter.
_LAW_PARAMETERS = {"gait.step_height": ("gait.step_height", "m", True),
                   "step_height": ("gait.step_height", "m", True),
                   "gait.duty": ("gait.duty", "1", False),
                   "gait.stride": ("gait.stride", "m", True)}


def _law_change(scene: Scene, name: str, source: str) -> LawChange:
    """The parameter ``name`` that the scene's laws hold (:data:`_LAW_PARAMETERS`): each law
    that depends on it and its derivative, per SI unit; its value, which they must share."""
    key, unit, length = _LAW_PARAMETERS[name]
    per_si = 1.0 / scene.unit if length else 1.0  # the laws are in the scene's units
    laws, values = {}, set()
    for driver in scene.drivers.values():
        law = getattr(driver, "law", None)
        try:
            held = law.design_parameter(key) if law is not None else None
        except ValueError as error:
            raise StudyError(f"{source}: '{name}': driver '{driver.name}' of scene "
                             f"'{scene.name}': {error}") from None
        if held is not None:
            values.add(float(held[0]))
            laws[law] = held[1].scaled(per_si)
    if key in ("gait.duty", "gait.stride"):  # the contacts' schedules hold them too
        values.update(_contact_values(scene, key, name, source))
    if not laws:
        raise StudyError(f"{source}: '{name}': no law of scene '{scene.name}' depends on "
                         f"{key} (a walking robot's feet's paths do)")
    ordered = sorted(values)  # alike to round-off (a trunk's speed times its period)
    if ordered[-1] - ordered[0] > 1e-12 * max(abs(ordered[0]), abs(ordered[-1])):
        shown = ", ".join(f"{v:g}" for v in ordered)
        raise StudyError(f"{source}: '{name}': the laws of scene '{scene.name}' hold {key} "
                         f"at different values ({shown}): one parameter cannot move them all")
    value = ordered[0] * (scene.unit if length else 1.0)
    return LawChange(name, laws, unit, value, scene.unit if length else 1.0, key=key)


def _contact_values(scene: Scene, key: str, name: str, source: str) -> set[float]:
    """The duty factors (``gait.duty``) or strides (``gait.stride``: their advance along
    ``x``, scene units) of the scene's contacts, whose footholds (and load-sharing weights)
    follow them: refused where the footholds turn or the ground is not flat."""
    from hexapod.scene.joints import Contact

    contacts = [j for j in scene.joints.values() if isinstance(j, Contact) and j.duty < 1.0]
    if contacts and (not scene.ground.terrain.flat or any(c.turn for c in contacts)):
        raise StudyError(f"{source}: '{name}': the contacts of scene '{scene.name}' turn or "
                         "stand on a ground that is not flat: their footholds' dependence on "
                         f"{key} is not derived (a straight walk on flat ground is)")
    if key == "gait.duty":
        return {float(c.duty) for c in contacts}
    return {float(c.advance[0]) for c in contacts}


def _payload(scene: Scene, source: str) -> InertiaChange:
    """The load a body carries at its centre of mass (``payload``, kg, a robot builder's
    argument: :attr:`~hexapod.scene.SpatialBody.payload`): its body's mass, the rest kept."""
    carriers = [b for b in scene.bodies.values() if b.payload is not None]
    if len(carriers) != 1:
        named = ", ".join(b.name for b in carriers)
        raise StudyError(f"{source}: 'payload': scene '{scene.name}' has "
                         f"{'no body' if not carriers else 'bodies ' + named} with a payload "
                         "(a body's 'payload' key; the walking robot's builders put theirs on "
                         "the trunk): one body must carry it")
    body = carriers[0]
    size = 1 if isinstance(body, (PlanarBody, Particle)) else 3
    return InertiaChange("payload", body.name, 1.0, np.zeros((size, size)), "kg",
                         float(body.payload))


def _kind(parts: list[str]) -> str | None:
    """What a key names: ``mass``, ``inertia``, ``origin``, ``parent_frame`` or
    ``child_frame`` (None: nothing sensitivities cover)."""
    if parts[0] == "body" and len(parts) in (3, 4) and parts[2] in ("mass", "inertia") \
            and (len(parts) == 3 or parts[2] == "inertia"):
        return parts[2]
    if parts[0] == "joint" and len(parts) in (3, 4) and parts[2] == "origin":
        return "origin"
    if parts[0] == "joint" and len(parts) in (4, 5) and parts[2] in ("parent_frame",
                                                                     "child_frame") \
            and parts[3] == "position":
        return parts[2]
    return None


def _origin_changes(scene, entry: dict, parts: list[str], pattern: str, source: str):
    """A joint's position: ``joint.NAME.origin[.K]``, its origin in world axes at the initial
    pose, moved on both its bodies (the parent's segment grows by what the child's shrinks);
    ``joint.NAME.parent_frame.position[.K]`` (``child_frame``), its frame's origin on one
    body, in that body's axes (a segment's length)."""
    name, kind = entry["name"], _kind(parts)
    given = entry.get(kind, {})
    values = given if kind == "origin" else (given.get("position")
                                              if isinstance(given, dict) else None)
    if scene.dimension != 3 or not isinstance(values, list) or len(values) != 3:
        written = "origin" if kind == "origin" else f"{kind}.position"
        raise StudyError(f"{source}: '{pattern}': joint '{name}' of a spatial scene gives no "
                         f"{written} (a joint is placed by its origin, or by its frames)")
    last = 3 if kind == "origin" else 4
    components = range(3)
    if len(parts) == last + 1:
        if not parts[last].isdigit() or int(parts[last]) > 2:
            raise StudyError(f"{source}: '{pattern}': a position has components 0 to 2")
        components = [int(parts[last])]
    joint = scene.joints[name]

    def axes(body: str) -> np.ndarray:  # the body's centre-of-mass axes at the initial pose
        return np.eye(3) if body == GROUND else scene.bodies[body].com_pose.rotation

    zero = np.zeros((3, 3))
    if kind == "origin":  # d (frame origin in each body's axes) / d (world origin)
        parent, child = axes(joint.parent).T, axes(joint.child).T
    else:  # a frame given in its body's axes, which are its centre-of-mass frame's axes
        parent, child = (np.eye(3), zero) if kind == "parent_frame" else (zero, np.eye(3))
    key = "origin" if kind == "origin" else f"{kind}.position"
    return [FrameChange(f"joint.{name}.{key}.{k}", name, parent[:, k].copy(),
                        child[:, k].copy(), "m", float(values[k]) * scene.unit, scene.unit)
            for k in components]


def _changes(scene, entry: dict, parts: list[str], pattern: str, source: str, glob: bool):
    name, body = entry["name"], scene.bodies[entry["name"]]
    planar = isinstance(body, PlanarBody)
    size = 1 if planar else 3
    if parts[2] == "mass":
        return [InertiaChange(f"body.{name}.mass", name, 1.0, np.zeros((size, size)), "kg",
                              float(entry["mass"]))]
    if isinstance(body, Particle):
        if glob:
            return []
        raise StudyError(f"{source}: '{pattern}': body '{name}' is a particle: it has no inertia")
    unit, to_si = "kg m^2", scene.unit ** 2  # derivatives per SI unit, as every output
    if planar:
        if len(parts) == 4:
            raise StudyError(f"{source}: '{pattern}': the planar body '{name}' has one moment of "
                             f"inertia, body.{name}.inertia")
        return [InertiaChange(f"body.{name}.inertia", name, 0.0, np.ones((1, 1)), unit,
                              float(entry["inertia"]) * to_si, to_si)]
    given = np.asarray(entry["inertia"], dtype=float)
    if given.ndim != 1:
        raise StudyError(f"{source}: '{pattern}': body '{name}' gives its inertia as a 3 x 3 "
                         "matrix; give it as 3 principal moments or 6 entries (xx yy zz xy xz "
                         "yz) to vary its components")
    components = range(given.size)
    if len(parts) == 4:
        if not parts[3].isdigit() or int(parts[3]) >= given.size:
            raise StudyError(f"{source}: '{pattern}': body '{name}' has inertia components 0 "
                             f"to {given.size - 1}")
        components = [int(parts[3])]
    R = body.inertia_rotation
    changes = []
    for k in components:
        unit_entry = np.zeros(given.size)
        unit_entry[k] = 1.0
        changes.append(InertiaChange(f"body.{name}.inertia.{k}", name, 0.0,
                                     R @ inertia_tensor(unit_entry) @ R.T, unit,
                                     float(given[k]) * to_si, to_si))
    return changes
