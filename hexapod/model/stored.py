"""Assembled models kept in the cache on disk, so that the second assembly of a scene builds no
graph.

:func:`hexapod.assemble` builds a scene's constraint and force expressions in Python, term by
term: about 10 ms for a leg, 30 ms for an 18-joint robot, 70 ms for the walking hexapod. What it
builds depends on the scene's content hash alone (``Model.digest``) but for the time laws, which
are the model's inputs. So the model's description (bodies, joints, drivers, rows, force
elements, contacts, mass matrix, initial state) and its expressions (one CasADi Function of
``q, v, w, wd, wdd``) are kept under that hash, with where each of its laws is found in a scene
(:func:`find_law`); a scene of the same hash then gets its model, with its own laws, without
building anything (1.5, 3.4 and 8 ms to read it back). The model's other Functions (Jacobians,
``gamma``, ...) are derived from those expressions by CasADi as before: reading them back
serialized would be slower (``gamma`` of the walking hexapod: 37 ms to derive, 67 ms to read).

An entry that cannot be read back (damaged, foreign) is removed and the scene assembled; a
restored model is the assembled one to the last bit (``tests/test_cache_models.py``).
"""

from __future__ import annotations

import dataclasses
import pickle

import casadi as ca

from hexapod._support import cache
from hexapod.model.model import Model, Symbolic
from hexapod.scene.contacts import Foothold, StanceGate
from hexapod.scene.laws import Law
from hexapod.scene.scene import Scene

#: The files of an entry: the description (pickled) and the expressions (serialized).
DESCRIPTION, EXPRESSIONS = "model.pickle", "expressions.casadi"
#: The Model's fields kept as they are (the others: its laws, expressions, name and ground come
#: from the scene at hand, and so do its joints' types: a type of a user's own need not pickle).
_KEPT = ("dimension", "bodies", "rows", "gravity", "characteristic_length", "q0", "v0",
         "mass", "forces", "rank_tolerance", "working_elements", "report_forces")


def _key(digest: str) -> str:
    return cache.key("model", digest, f"casadi {ca.__version__}")


def find_law(scene: Scene, where: tuple) -> Law:
    """The law of ``scene`` that ``where`` names: ``("driver", name)``, ``("force", name,
    attribute, index)`` (``index`` None for a single law, else the component's), ``("gate",
    contact)`` or ``("foothold", contact, axis)``."""
    kind, name = where[0], where[1]
    if kind == "driver":
        return scene.drivers[name].law
    if kind == "gate":
        return StanceGate(scene.joints[name])
    if kind == "foothold":
        return Foothold(scene.joints[name], where[2])
    if kind == "force":
        law = getattr(scene.forces[name], where[2])
        return law if where[3] is None else law[where[3]]
    raise ValueError(f"no law where {where!r}")


def store(model: Model, where: list[tuple]) -> None:
    """Keep ``model`` (assembled from a scene whose laws are found at ``where``) in the cache
    under its content hash; nothing without a cache or a content hash."""
    if not model.digest or cache.folder() is None:
        return
    s = model._sym
    outputs = [s.phi, s.qdot, s.Q] + [x for x in (s.Q_across, s.potential) if x is not None]
    try:
        expressions = ca.Function("expressions", [s.q, s.v, s.w, s.wd, s.wdd], outputs)
    except RuntimeError:  # expressions of something else than the model's inputs: not kept
        return
    description = {name: getattr(model, name) for name in _KEPT}
    description.update(
        joints=tuple(dataclasses.replace(j, type=None) for j in model.joints),
        drivers=tuple(dataclasses.replace(d, spec=None) for d in model.drivers),
        contacts=tuple(dataclasses.replace(c, schedule=None) for c in model.contacts),
        where=list(where), across=s.Q_across is not None, potential=s.potential is not None)
    cache.keep(_key(model.digest), f"the model '{model.name}'",
               {DESCRIPTION: pickle.dumps(description), EXPRESSIONS: expressions.serialize()},
               stacklevel=3)


def restore(scene: Scene, digest: str) -> Model | None:
    """The model of ``scene`` (in SI units, of content hash ``digest``) from the cache, with the
    scene's laws, name and ground-force settings; None when the cache holds none."""
    found = cache.load(_key(digest))
    if found is None:
        return None
    try:
        return _model(scene, digest, *found)
    except Exception:  # noqa: BLE001 (a damaged or foreign entry, whatever fails: built again)
        cache.discard(_key(digest))
        return None


def _model(scene: Scene, digest: str, folder, files: dict[str, bytes]) -> Model:
    description = pickle.loads(files[DESCRIPTION])  # noqa: S301 (checked, the user's own)
    expressions = ca.Function.deserialize(files[EXPRESSIONS].decode("ascii"))
    laws = tuple(find_law(scene, where) for where in description.pop("where"))
    n_q, n_v, n_w = description["q0"].size, description["v0"].size, len(laws)
    q, v = ca.SX.sym("q", n_q), ca.SX.sym("v", n_v)
    w, wd, wdd = (ca.SX.sym(name, n_w) for name in ("w", "wd", "wdd"))
    outputs = list(expressions(q, v, w, wd, wdd))
    phi, qdot, Q = outputs[:3]
    across = outputs.pop(3) if description.pop("across") else None
    potential = outputs[3] if description.pop("potential") else None
    scene_joints = scene.joints  # built on each call
    joints = tuple(dataclasses.replace(j, type=scene_joints[j.name])
                   for j in description.pop("joints"))
    drivers = tuple(dataclasses.replace(d, spec=scene.drivers[d.name].law)
                    for d in description.pop("drivers"))
    contacts = tuple(dataclasses.replace(c, schedule=scene.joints[c.name])
                     for c in description.pop("contacts"))
    symbolic = Symbolic(q=q, v=v, w=w, wd=wd, wdd=wdd, qdot=qdot, phi=phi, Q=Q,
                        Q_across=across, potential=potential)
    return Model(name=scene.name, laws=laws, joints=joints, drivers=drivers, contacts=contacts,
                 symbolic=symbolic, ground=scene.ground, digest=digest, **description)
