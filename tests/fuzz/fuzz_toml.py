"""The scene files of ``tests/fuzz/fuzz_inputs.py``: a TOML writer, the mutations of a parsed scene
and the values the TOML parser itself chokes on."""

from __future__ import annotations

import copy
import datetime
import math
import numbers
import random
import tomllib

from fuzz_mutations import (
    JOINT_KINDS,
    TOML_MODES,
    UNITS,
    byte_mutations,
    nasty_value,
    pick,
    random_input,
)

# ------------------------------------------------------------------ TOML

def _toml_key(key: str) -> str:
    if key and all(c.isascii() and (c.isalnum() or c in "_-") for c in key):
        return key
    return _toml_string(key)


def _toml_string(text: str) -> str:
    out = []
    for c in text:
        if c in '"\\':
            out.append("\\" + c)
        elif " " <= c <= "~":
            out.append(c)
        elif ord(c) < 0x10000:
            out.append(f"\\u{ord(c):04x}")
        else:
            out.append(f"\\U{ord(c):08x}")
    return '"' + "".join(out) + '"'


def toml_value(value) -> str:
    """A value as inline TOML."""
    if isinstance(value, bool) or type(value).__name__ == "bool_":  # NumPy's too
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(float(value))  # NumPy 2 writes np.float64(...) otherwise
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (datetime.date, datetime.time)):
        return value.isoformat()
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {toml_value(v)}" for k, v in value.items()) \
            + "}"
    raise TypeError(f"no TOML for {value!r}")


def toml_text(document: dict) -> str:
    """A document as TOML: plain values, then tables, then arrays of tables."""
    plain, tables, arrays = [], [], []
    for key, value in document.items():
        if isinstance(value, dict):
            tables.append(f"\n[{_toml_key(key)}]")
            tables += [f"{_toml_key(k)} = {toml_value(v)}" for k, v in value.items()]
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for entry in value:
                arrays.append(f"\n[[{_toml_key(key)}]]")
                arrays += [f"{_toml_key(k)} = {toml_value(v)}" for k, v in entry.items()]
        else:
            plain.append(f"{_toml_key(key)} = {toml_value(value)}")
    return "\n".join(plain + tables + arrays) + "\n"


def _slots(value, path=()):
    """Every (container, key) pair of a nested document, with its path."""
    if isinstance(value, dict):
        items = list(value.items())
    elif isinstance(value, list):
        items = list(enumerate(value))
    else:
        return
    for key, item in items:
        yield path + (key,), value, key
        yield from _slots(item, path + (key,))


def _entries(document: dict, section: str) -> list[dict]:
    entries = document.get(section)
    return [e for e in entries if isinstance(e, dict)] if isinstance(entries, list) else []


def _names(document: dict) -> list[str]:
    return [e["name"] for s in ("body", "joint", "driver", "force") for e in _entries(document, s)
            if isinstance(e.get("name"), str)]


#: the mutations of a parsed scene ("replace" twice: drawn twice as often)
DOCUMENT_MUTATIONS = ("replace", "replace", "delete", "rename", "duplicate", "drop", "scale",
                      "perturb", "unit", "type", "inertia", "self-joint", "unknown-key",
                      "dimension", "law")
#: those that change an entry of a section (``[[body]]``, ``[[joint]]``, ...)
ENTRY_MUTATIONS = ("duplicate", "drop", "type", "inertia", "self-joint", "law")
#: those that set a key of the ``[scene]`` table
SCENE_MUTATIONS = ("unit", "dimension")


def mutate_document(rng: random.Random, document: dict) -> str:
    """One mutation of a parsed scene, in place; returns what it did."""
    slots = list(_slots(document))
    kind = rng.choice(DOCUMENT_MUTATIONS)
    if kind in SCENE_MUTATIONS:
        done = _mutate_scene_table(rng, kind, document)
    elif kind in ENTRY_MUTATIONS:
        done = _mutate_entry(rng, kind, document)
    else:
        done = _mutate_value(rng, kind, document, slots)
    return done or "no change"


def _mutate_value(rng: random.Random, kind: str, document: dict, slots: list) -> str | None:
    """Replace, delete, rename, scale or perturb one value of the document, or add an unknown
    key to one of its tables; None when the document has nothing to mutate so."""
    if kind == "replace" and slots:
        path, container, key = rng.choice(slots)
        container[key] = nasty_value(rng)
        return f"replace {'.'.join(map(str, path))} by {container[key]!r}"
    if kind == "delete" and slots:
        path, container, key = rng.choice(slots)
        del container[key]
        return f"delete {'.'.join(map(str, path))}"
    if kind == "rename":
        strings = [s for s in slots if isinstance(s[1][s[2]], str)]
        if strings:
            path, container, key = rng.choice(strings)
            container[key] = rng.choice(_names(document) + ["no_such_name", "ground", ""])
            return f"rename {'.'.join(map(str, path))} to {container[key]!r}"
    numbers = [s for s in slots if isinstance(s[1][s[2]], float | int)
               and not isinstance(s[1][s[2]], bool)]
    if kind == "scale" and numbers:
        path, container, key = rng.choice(numbers)
        factor = rng.choice((-1.0, 0.0, 1e-12, 1e6, 1e300, 1e308))
        container[key] = container[key] * factor
        return f"scale {'.'.join(map(str, path))} by {factor:g}"
    if kind == "perturb" and numbers:  # a joint frame off by a little: a loop may not close
        path, container, key = rng.choice(numbers)
        container[key] = float(container[key]) + rng.uniform(-1.0, 1.0)
        return f"perturb {'.'.join(map(str, path))} to {container[key]!r}"
    if kind == "unknown-key" and slots:
        tables = [c[k] for _, c, k in slots if isinstance(c[k], dict)] or [document]
        rng.choice(tables)["colour"] = "red"
        return "add an unknown key"
    return None


def _mutate_entry(rng: random.Random, kind: str, document: dict) -> str | None:
    """Duplicate or drop an entry of a section, or give one a wrong type, a bad inertia (a
    body), its parent as child (a joint) or a nasty law (a driver); None when there is none."""
    sections = [s for s in ("body", "joint", "driver", "force") if _entries(document, s)]
    if kind in ("duplicate", "drop") and sections:
        section = rng.choice(sections)
        entries = document[section]
        i = rng.randrange(len(entries))
        if kind == "duplicate":
            entries.insert(i, copy.deepcopy(entries[i]))
            return f"duplicate {section}[{i}]"
        del entries[i]
        return f"drop {section}[{i}]"
    if kind == "type":
        typed = [e for s in sections for e in _entries(document, s)]
        if typed:
            entry = rng.choice(typed)
            entry["type"] = rng.choice(JOINT_KINDS + ("spatial", "planar", "particle", "joint",
                                                      "coordinate", "spring", "effort", "nope"))
            return f"type of {entry.get('name')!r} = {entry['type']!r}"
    if kind == "inertia":
        bodies = _entries(document, "body")
        if bodies:
            body = rng.choice(bodies)
            a, b = rng.choice(((1.0, 1.0, 3.0), (-1.0, 1.0, 1.0), (0.0, 0.0, 0.0),
                               (1.0, 1.0, 1.0, 5.0, 0.0, 0.0), (1e-320, 1e-320, 1e-320),
                               (1e308, 1e308, 1e308))), rng.choice((-1.0, 0.0, 1e-300, 1e300))
            body["inertia"], body["mass"] = list(a), b
            return f"body {body.get('name')!r}: inertia {a}, mass {b}"
    if kind == "self-joint":
        joints = _entries(document, "joint")
        if joints:
            joint = rng.choice(joints)
            joint["child"] = joint.get("parent", "ground")
            return f"joint {joint.get('name')!r} joins {joint['child']!r} to itself"
    if kind == "law":
        drivers = _entries(document, "driver")
        if drivers:
            driver = rng.choice(drivers)
            driver["law"] = nasty_value(rng)
            return f"law of {driver.get('name')!r} = {driver['law']!r}"
    return None


def _mutate_scene_table(rng: random.Random, kind: str, document: dict) -> str | None:
    """A length unit or a dimension in ``[scene]`` (made if missing); None when ``scene`` is
    not a table."""
    scene = document.setdefault("scene", {})
    if not isinstance(scene, dict):
        return None
    if kind == "unit":
        scene["length_unit"] = rng.choice(UNITS)
        return f"length_unit = {scene['length_unit']!r}"
    scene["dimension"] = rng.choice((2, 3, 1, 0, 4, -3))
    return f"dimension = {scene['dimension']}"


def parser_limits(rng: random.Random) -> tuple[str, bytes]:
    """A value the TOML parser itself chokes on: nested thousands deep, or an integer of
    thousands of digits."""
    if rng.random() < 0.3:
        digits = rng.choice((400, 5000))
        return f"integer of {digits} digits", f"\nx = {'9' * digits}\n".encode()
    depth = rng.choice((200, 2000, 50000))
    open_, close = rng.choice((("[", "]"), ("{a = ", "}")))
    return f"value nested {depth} deep", f"\nx = {open_ * depth}1{close * depth}\n".encode()


def mutate_toml(rng: random.Random, data: bytes, mode: str | None = None
                ) -> tuple[list[str], bytes]:
    """One to three mutations of a scene file, by ``mode`` (drawn when not given): on its
    parsed ``document`` (mostly), its ``bytes``, the parser's ``limits``, or ``random`` input."""
    mode = mode or pick(rng, TOML_MODES)
    if mode == "random":
        what, out = random_input(rng)
        return [what], out
    if mode == "limits":
        what, tail = parser_limits(rng)
        return [what], tail + data if rng.random() < 0.5 else data + tail
    if mode == "bytes":
        return byte_mutations(rng, data, tags=False)
    document = tomllib.loads(data.decode())
    done = [mutate_document(rng, document) for _ in range(rng.randrange(1, 4))]
    return done, toml_text(document).encode()
