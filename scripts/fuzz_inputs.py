"""Fuzz the input readers and the command line with malformed files: no traceback, ever.

    python scripts/fuzz_inputs.py                          # 5000 inputs, seed 0 (a few minutes)
    python scripts/fuzz_inputs.py --count 200 --seed 7     # a quick look
    python scripts/fuzz_inputs.py --replay fuzz-failures/0042-scene-cli  # one saved failure

Protocol
--------
Each input is made from a valid file of the repository -- a scene (``data/scenes/*.toml``), a
URDF or a motion CSV (``tests/data/pinocchio/*/``) -- by one to three random mutations: on the
parsed document (delete a key or an element, replace a value by NaN, infinity, -1, 0, 1e308, a
string, a list or a table, rename a reference to an unknown name, make a joint join a body to
itself, duplicate an element, change a type, a unit or an inertia), or on the bytes (truncate,
flip, insert or delete bytes, break tags, nest arrays deeply, add a BOM); a few inputs are random
text or random bytes. The mutations are those of ``tests/test_malformed_inputs.py``, where
Hypothesis draws them; here ``random.Random(seed)`` does, so a run is reproducible.

Every input goes through its reader and, when it reads, through ``hexapod.assemble`` and
``hexapod.consistent_state`` (a motion drives the URDF it was made for). Every fourth input also
goes through the command line, in process (``hexapod.cli.main``, stdout and stderr captured):
``validate`` or ``info`` for a scene, ``info`` for a URDF, ``inverse --out`` for a motion (and
for a URDF with its motion), each writing into an empty directory of its own.

Each run is counted as

* **accepted**: read (and assembled) without error, or the command succeeded;
* **rejected**: a :class:`hexapod.HexapodError` whose message names the file; on the command
  line, a non-zero exit with a message starting ``hexapod: error:``;
* **traceback**: any other exception (``KeyError``, ``ValueError``, ``RecursionError``, ...), a
  ``HexapodError`` that does not name the file, or a command that ended in ``hexapod: internal
  error`` or printed a traceback;
* **partial file**: after the command, the output directory holds a file it should not (an
  output after a failure, or a temporary file after anything).

The column **unnamed** counts the command-line rejections whose message does not name the input:
errors of the computation after the files were read and assembled (the forward dynamics of
``info``, a diverging ``simulate``), which name what failed but not the file. They are not
failures (the readers' own errors always name the file: the library path checks it).

Progress goes to stderr, a summary table to stdout; the exit status is 1 when any traceback or
partial file was seen, else 0. Every failing input is saved in ``--failures DIR`` (default
``fuzz-failures``) as ``NNNN-KIND/`` with the input, the file it needs (the URDF of a motion) and
``failure.txt`` (the mutations, the command, the traceback); ``--replay`` runs one again.
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import csv
import datetime
import io
import json
import math
import numbers
import os
import random
import shutil
import sys
import tempfile
import time
import tomllib
import traceback
import warnings
import xml.etree.ElementTree as ET
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "data" / "scenes").glob("*.toml"))
FIXTURES = sorted(p for p in (ROOT / "tests" / "data" / "pinocchio").iterdir() if p.is_dir())
URDFS = [p / "model.urdf" for p in FIXTURES]
MOTIONS = [p / "motion.csv" for p in FIXTURES]

# ------------------------------------------------------------------ nasty values

NASTY_NUMBERS = (math.nan, math.inf, -math.inf, -1.0, 0.0, -0.0, 1e308, -1e308, 1e-320,
                 5e-324, 1e16, -(10**19), 10**30, 2**63 - 1, 0.5, 3)
NASTY_STRINGS = ("", " ", "x", "ground", "nan", "1.0", "no_such_name", "a b", "a/b", "é",
                 "m", "mm", "furlong", "revolute", "spline", "\t", "a" * 200)
NASTY_ATTRIBUTES = ("nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "1e-320", "1e999",
                    "abc", "", " ", "1 2", "1 2 3 4", "nan nan nan", "1e308 1e308 1e308",
                    "0 0 0", "-1 -1 -1", "1,2,3", "0x10", "1_0", "NaN 0 0", "١ ٢ ٣")
NASTY_CELLS = ("nan", "inf", "-inf", "", " ", "abc", "1e308", "-1e308", "1e-320", "1e999",
               "0x10", "1,5", " 1 ", "١", '"', "1e", "--1", "0")
UNITS = ("m", "dm", "cm", "mm", "um", "in", "ft", "km", "furlong", "", "M", "metre")
JOINT_KINDS = ("revolute", "prismatic", "spherical", "fixed", "distance", "universal",
               "cylindrical", "planar", "point-on-plane", "hinge", "", "floating",
               "continuous", "REVOLUTE")
BYTES = (b"\xff", b"\x00", b"\xc3", b"[", b"]", b"[[", b"{", b"}", b"\"", b"'", b"=", b"\n",
         b",", b"<", b">", b"/", b"&", b"#", b"\\", b"\r\n", b" ", "é".encode(), b"\xef\xbb\xbf",
         b"nan", b"1e308", b"-")


def nasty_value(rng: random.Random):
    """A value of a wrong kind, or of the right kind with a bad number in it."""
    kind = rng.randrange(8)
    if kind == 0:
        return rng.choice(NASTY_NUMBERS)
    if kind == 1:
        return rng.choice(NASTY_STRINGS)
    if kind == 2:
        return rng.choice((True, False))
    if kind == 3:
        return [rng.choice(NASTY_NUMBERS) for _ in range(rng.randrange(8))]
    if kind == 4:
        deep: list = [1.0]
        for _ in range(300):
            deep = [deep]
        return rng.choice(([[1.0, 0.0, 0.0]] * 3, [[1.0, 2.0], [3.0]], [[]], [["a"]],
                           [{"type": "constant", "value": 1.0}], ["a", "b", "c"], deep,
                           [0.5] * 5000, [10**300, 0, 0]))
    if kind == 5:
        return rng.choice(({}, {"x": 1.0}, {"type": "spline"}, {"type": "nope"},
                           {"rpy": [math.nan, 0.0, 0.0]}, {"position": "m"},
                           {"type": "gait", "period": -1.0}, {"matrix": [[0.0] * 3] * 3},
                           {"type": "harmonic", "frequency": 1e308, "sin": [1.0]},
                           {"type": "polynomial", "coefficients": [1e308, 1e308, 1e308]}))
    if kind == 6:
        return rng.choice((datetime.datetime(1979, 5, 27, 7, 32), datetime.date(2024, 2, 29),
                           datetime.time(12, 0)))
    if rng.random() < 0.5:
        return rng.uniform(-3.0, 3.0)  # plausible, but not what the geometry needs
    return rng.uniform(-1e3, 1e3) * 10.0 ** rng.randrange(-300, 300)


# ------------------------------------------------------------------ bytes

def mutate_bytes(rng: random.Random, data: bytes) -> tuple[str, bytes]:
    """One byte-level mutation (any file)."""
    n = len(data)
    kind = rng.choice(("truncate", "flip", "insert", "delete", "line-delete", "line-duplicate",
                       "line-swap", "bom", "crlf"))
    if kind == "truncate":
        cut = rng.randrange(n + 1)
        return f"truncate at byte {cut}", data[:cut]
    if kind == "flip" and n:
        out = bytearray(data)
        for _ in range(rng.randrange(1, 4)):
            i = rng.randrange(n)
            out[i] ^= 1 << rng.randrange(8)
        return "flip bits", bytes(out)
    if kind == "insert":
        i = rng.randrange(n + 1)
        piece = rng.choice(BYTES)
        return f"insert {piece!r} at byte {i}", data[:i] + piece + data[i:]
    if kind == "delete" and n:
        i = rng.randrange(n)
        j = min(n, i + rng.randrange(1, 40))
        return f"delete bytes {i}:{j}", data[:i] + data[j:]
    lines = data.split(b"\n")
    if kind == "line-delete" and lines:
        i = rng.randrange(len(lines))
        return f"delete line {i + 1}", b"\n".join(lines[:i] + lines[i + 1:])
    if kind == "line-duplicate" and lines:
        i = rng.randrange(len(lines))
        return f"duplicate line {i + 1}", b"\n".join(lines[:i + 1] + lines[i:])
    if kind == "line-swap" and len(lines) > 1:
        i, j = rng.sample(range(len(lines)), 2)
        lines[i], lines[j] = lines[j], lines[i]
        return f"swap lines {i + 1} and {j + 1}", b"\n".join(lines)
    if kind == "bom":
        return "UTF-8 byte-order mark", b"\xef\xbb\xbf" + data
    return "CRLF line ends", data.replace(b"\n", b"\r\n")


def random_input(rng: random.Random) -> tuple[str, bytes]:
    """Not a mutation: random bytes, random printable text, or nothing."""
    kind = rng.randrange(4)
    if kind == 0:
        return "empty file", b""
    if kind == 1:
        return "random bytes", rng.randbytes(rng.randrange(1, 400))
    alphabet = "abcxyz0123456789 =[]{}<>/\",.:#\n\t-_'+eE"
    text = "".join(rng.choice(alphabet) for _ in range(rng.randrange(1, 400)))
    return "random text", text.encode()


def _byte_mutations(rng: random.Random, data: bytes, tags: bool) -> tuple[list[str], bytes]:
    """One or two byte-level mutations; with ``tags``, half of them drop a markup character
    (``<``, ``>``, ``/``, ``"``, ``=``) to break an XML tag."""
    done, out = [], data
    for _ in range(rng.randrange(1, 3)):
        marks = [i for i, b in enumerate(out) if b in b'<>/"='] if tags else []
        if marks and rng.random() < 0.5:
            i = rng.choice(marks)
            done.append(f"drop {out[i:i + 1]!r} at byte {i}")
            out = out[:i] + out[i + 1:]
        else:
            what, out = mutate_bytes(rng, out)
            done.append(what)
    return done, out


def pick(rng: random.Random, weights: dict[str, float]) -> str:
    """A key of ``weights`` with its probability."""
    return rng.choices(list(weights), weights=list(weights.values()))[0]


#: how often each kind of mutation is drawn (the tests draw the mode themselves)
TOML_MODES = {"document": 0.7, "bytes": 0.23, "limits": 0.02, "random": 0.05}
URDF_MODES = {"tree": 0.7, "bytes": 0.22, "entity": 0.03, "random": 0.05}
MOTION_MODES = {"table": 0.75, "bytes": 0.2, "random": 0.05}


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


def mutate_document(rng: random.Random, document: dict) -> str:
    """One mutation of a parsed scene, in place; returns what it did."""
    slots = list(_slots(document))
    kind = rng.choice(("replace", "replace", "delete", "rename", "duplicate", "drop", "scale",
                       "perturb", "unit", "type", "inertia", "self-joint", "unknown-key",
                       "dimension", "law"))
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
    if kind == "unit":
        scene = document.setdefault("scene", {})
        if isinstance(scene, dict):
            scene["length_unit"] = rng.choice(UNITS)
            return f"length_unit = {scene['length_unit']!r}"
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
    if kind == "unknown-key" and slots:
        tables = [c[k] for _, c, k in slots if isinstance(c[k], dict)] or [document]
        rng.choice(tables)["colour"] = "red"
        return "add an unknown key"
    if kind == "dimension":
        scene = document.setdefault("scene", {})
        if isinstance(scene, dict):
            scene["dimension"] = rng.choice((2, 3, 1, 0, 4, -3))
            return f"dimension = {scene['dimension']}"
    if kind == "law":
        drivers = _entries(document, "driver")
        if drivers:
            driver = rng.choice(drivers)
            driver["law"] = nasty_value(rng)
            return f"law of {driver.get('name')!r} = {driver['law']!r}"
    return "no change"


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
        return _byte_mutations(rng, data, tags=False)
    document = tomllib.loads(data.decode())
    done = [mutate_document(rng, document) for _ in range(rng.randrange(1, 4))]
    return done, toml_text(document).encode()


# ------------------------------------------------------------------ URDF

def _parents(root: ET.Element) -> dict:
    return {child: parent for parent in root.iter() for child in parent}


def mutate_tree(rng: random.Random, root: ET.Element) -> str:
    """One mutation of a parsed URDF, in place; returns what it did."""
    parents = _parents(root)
    elements = list(parents)
    links = [e.get("name") for e in root.findall("link") if e.get("name")]
    kind = rng.choice(("delete-element", "delete-attribute", "attribute", "attribute",
                       "perturb", "rename-link", "duplicate", "joint-type", "inertia",
                       "root-tag", "loop", "self-joint"))
    if kind == "delete-element" and elements:
        element = rng.choice(elements)
        parents[element].remove(element)
        return f"delete <{element.tag} {element.get('name', '')}>"
    with_attributes = [e for e in elements if e.attrib]
    if kind in ("delete-attribute", "attribute") and with_attributes:
        element = rng.choice(with_attributes)
        name = rng.choice(sorted(element.attrib))
        if kind == "delete-attribute":
            del element.attrib[name]
            return f"delete <{element.tag}> {name}"
        element.set(name, rng.choice(NASTY_ATTRIBUTES))
        return f"<{element.tag}> {name}=\"{element.get(name)}\""
    numeric = [(e, a) for e in with_attributes for a in e.attrib if a not in ("name", "link")]
    if kind == "perturb" and numeric:  # plausible numbers, of the right count
        element, name = rng.choice(numeric)
        count = len(element.get(name).split()) or 1
        element.set(name, " ".join(repr(rng.uniform(-2.0, 2.0)) for _ in range(count)))
        return f"<{element.tag}> {name}=\"{element.get(name)}\""
    ends = [e for e in elements if e.tag in ("parent", "child")]
    if kind == "rename-link" and ends:
        end = rng.choice(ends)
        end.set("link", rng.choice(links + ["no_such_link", ""]))
        return f"<{end.tag} link=\"{end.get('link')}\">"
    if kind == "duplicate" and elements:
        element = rng.choice([e for e in elements if e.tag in ("link", "joint")] or elements)
        parents[element].append(copy.deepcopy(element))
        return f"duplicate <{element.tag} {element.get('name', '')}>"
    joints = root.findall("joint")
    if kind == "joint-type" and joints:
        joint = rng.choice(joints)
        joint.set("type", rng.choice(JOINT_KINDS))
        return f"joint {joint.get('name')!r} type=\"{joint.get('type')}\""
    inertias = root.findall("link/inertial")
    if kind == "inertia" and inertias:
        inertial = rng.choice(inertias)
        values = rng.choice(((1, 1, 3, 0, 0, 0), (-1, 1, 1, 0, 0, 0), (0, 0, 0, 0, 0, 0),
                             (1, 1, 1, 5, 0, 0), (1e308, 1e308, 1e308, 0, 0, 0)))
        for key, value in zip(("ixx", "iyy", "izz", "ixy", "ixz", "iyz"), values, strict=True):
            for inertia in inertial.findall("inertia"):
                inertia.set(key, repr(float(value)))
        for mass in inertial.findall("mass"):
            mass.set("value", rng.choice(("-1", "0", "1e-300", "1")))
        return f"inertia {values}"
    if kind == "root-tag":
        root.tag = rng.choice(("model", "Robot", "sdf"))
        return f"root <{root.tag}>"
    if kind in ("loop", "self-joint") and joints:
        joint = rng.choice(joints)
        parent, child = joint.find("parent"), joint.find("child")
        if parent is not None and child is not None:
            if kind == "self-joint":
                child.set("link", parent.get("link", ""))
            else:
                parent.set("link", links[-1] if links else "")
                child.set("link", links[0] if links else "")
            return f"joint {joint.get('name')!r}: {parent.get('link')} -> {child.get('link')}"
    return "no change"


BROKEN_XML = (b"<!DOCTYPE r [<!ENTITY a \"aaaaaaaaaa\"><!ENTITY b \"&a;&a;&a;&a;&a;&a;&a;&a;&a;"
              b"&a;\"><!ENTITY c \"&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;\"><!ENTITY d \"&c;&c;&c;&c;"
              b"&c;&c;&c;&c;&c;&c;\"><!ENTITY e \"&d;&d;&d;&d;&d;&d;&d;&d;&d;&d;\"><!ENTITY f "
              b"\"&e;&e;&e;&e;&e;&e;&e;&e;&e;&e;\"><!ENTITY g \"&f;&f;&f;&f;&f;&f;&f;&f;&f;&f;\">"
              b"]><robot name=\"&g;\"/>",
              b"<!DOCTYPE r [<!ENTITY x SYSTEM \"file:///etc/passwd\">]><robot name=\"&x;\"/>",
              b"<robot name=\"r\"><link name=\"&undefined;\"/></robot>")


def mutate_urdf(rng: random.Random, data: bytes, mode: str | None = None
                ) -> tuple[list[str], bytes]:
    """One to three mutations of a URDF, by ``mode`` (drawn when not given): on its element
    ``tree`` (mostly), its ``bytes`` and tags, an ``entity`` trick, or ``random`` input."""
    mode = mode or pick(rng, URDF_MODES)
    if mode == "random":
        what, out = random_input(rng)
        return [what], out
    if mode == "entity":
        return ["entity trick"], rng.choice(BROKEN_XML)
    if mode == "bytes":
        return _byte_mutations(rng, data, tags=True)
    root = ET.fromstring(data)
    done = [mutate_tree(rng, root) for _ in range(rng.randrange(1, 4))]
    return done, b'<?xml version="1.0"?>\n' + ET.tostring(root)


# ------------------------------------------------------------------ motion CSV

def mutate_rows(rng: random.Random, rows: list[list[str]]) -> str:
    """One mutation of a motion table (header first), in place; returns what it did."""
    kind = rng.choice(("drop-column", "drop-row", "duplicate-row", "swap-rows", "cell", "cell",
                       "rename", "extra-cell", "missing-cell", "only-header", "scale-column",
                       "reverse"))
    width = len(rows[0]) if rows else 0
    if kind == "drop-column" and width:
        j = rng.randrange(width)
        for row in rows:
            if j < len(row):
                del row[j]
        return f"drop column {j}"
    if kind == "drop-row" and rows:
        i = rng.randrange(len(rows))
        del rows[i]
        return f"drop line {i + 1}"
    if kind == "duplicate-row" and len(rows) > 1:
        i = rng.randrange(1, len(rows))
        rows.insert(i, list(rows[i]))
        return f"duplicate line {i + 1}"
    if kind == "swap-rows" and len(rows) > 2:
        i, j = rng.sample(range(1, len(rows)), 2)
        rows[i], rows[j] = rows[j], rows[i]
        return f"swap lines {i + 1} and {j + 1}"
    if kind == "cell" and len(rows) > 1 and width:
        i, j = rng.randrange(1, len(rows)), rng.randrange(width)
        if j < len(rows[i]):
            rows[i][j] = rng.choice(NASTY_CELLS)
            return f"line {i + 1} column {j}: {rows[i][j]!r}"
    if kind == "rename" and width:
        j = rng.randrange(width)
        rows[0][j] = rng.choice(rows[0] + ["knee", "qd:", "qdd:nosuch", ":", "", "T", "t",
                                           "qd:qd:j0", " j0 "])
        return f"column {j} named {rows[0][j]!r}"
    if kind == "extra-cell" and rows:
        rng.choice(rows).append(rng.choice(NASTY_CELLS))
        return "an extra cell"
    if kind == "missing-cell" and rows:
        row = rng.choice(rows)
        if row:
            row.pop()
        return "a missing cell"
    if kind == "only-header" and rows:
        del rows[1:]
        return "header only"
    if kind == "scale-column" and len(rows) > 1 and width:
        j = rng.randrange(width)
        factor = rng.choice((-1.0, 0.0, 1e-300, 1e300, 1e308))
        for row in rows[1:]:
            with contextlib.suppress(ValueError, IndexError):
                row[j] = repr(float(row[j]) * factor)
        return f"scale column {j} by {factor:g}"
    if kind == "reverse" and len(rows) > 2:
        rows[1:] = rows[:0:-1]
        return "times decreasing"
    return "no change"


def mutate_motion(rng: random.Random, data: bytes, mode: str | None = None
                  ) -> tuple[list[str], bytes]:
    """One to three mutations of a motion file, by ``mode`` (drawn when not given): on its
    ``table`` (mostly), its ``bytes``, or ``random`` input."""
    mode = mode or pick(rng, MOTION_MODES)
    if mode == "random":
        what, out = random_input(rng)
        return [what], out
    if mode == "bytes":
        return _byte_mutations(rng, data, tags=False)
    rows = list(csv.reader(io.StringIO(data.decode())))
    done = [mutate_rows(rng, rows) for _ in range(rng.randrange(1, 4))]
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    return done, buffer.getvalue().encode()


#: the kinds of input: the valid files they start from, and their mutation
KINDS = {"scene": (SCENES, mutate_toml, ".toml"), "urdf": (URDFS, mutate_urdf, ".urdf"),
         "motion": (MOTIONS, mutate_motion, ".csv")}


# ------------------------------------------------------------------ one input


@dataclass
class Case:
    """One malformed input: its kind, what it was made from and how, its bytes."""

    kind: str
    seed_file: Path
    mutations: list[str]
    data: bytes

    @property
    def suffix(self) -> str:
        return KINDS[self.kind][2]

    @property
    def model(self) -> Path:
        """The URDF a motion drives (the fixture it came from)."""
        return self.seed_file.parent / "model.urdf"


def make_case(rng: random.Random, kind: str | None = None) -> Case:
    kind = kind or rng.choice(tuple(KINDS))
    seeds, mutate, _ = KINDS[kind]
    seed_file = rng.choice(seeds)
    mutations, data = mutate(rng, seed_file.read_bytes())
    return Case(kind, seed_file, mutations, data)


@dataclass
class Outcome:
    """How one run ended: accepted, rejected, traceback or partial; with the evidence."""

    status: str
    detail: str = ""
    leftovers: list[str] = field(default_factory=list)
    unnamed: bool = False  # rejected by a message that does not name the input
    command: list[str] | None = None  # the command line run, as a template (cli_arguments)


def _quiet():
    """Numerical warnings of extreme inputs are not failures: the result is judged."""
    stack = contextlib.ExitStack()
    stack.enter_context(warnings.catch_warnings())
    warnings.simplefilter("ignore")
    return stack


def read_and_assemble(case: Case, path: Path) -> None:
    """What a user's first call does: read, validate, assemble, find a consistent state."""
    import hexapod as hx
    from hexapod import apply_motion, read_motion, read_scene, read_urdf

    t = 0.0
    if case.kind == "scene":
        scene = read_scene(path)
    elif case.kind == "urdf":
        scene = read_urdf(path)
    else:
        motion = read_motion(path)
        scene = apply_motion(read_urdf(case.model), motion)
        t = float(motion.times[0])
    data = hx.assemble(scene).create_data()
    hx.consistent_state(hx.assemble(scene), data, t)


def check_library(case: Case, path: Path) -> Outcome:
    """Read and assemble in process: accepted, rejected naming the file, or a traceback."""
    from hexapod import HexapodError

    try:
        with _quiet():
            read_and_assemble(case, path)
    except HexapodError as error:
        if path.name not in str(error):
            return Outcome("traceback", f"{type(error).__name__} without the file name: {error}")
        return Outcome("rejected", str(error).splitlines()[0])
    except Exception as error:  # anything else is what this script is looking for
        return Outcome("traceback", "".join(traceback.format_exception(error)))
    return Outcome("accepted")


def cli_arguments(case: Case, rng: random.Random) -> list[str]:
    """A command that reads the input, with ``{input}``, ``{model}`` (the URDF a motion drives,
    or the motion of a URDF) and ``{out}`` (an empty directory) to fill in."""
    if case.kind == "scene":
        command = rng.choice(("validate", "info", "dynamics", "simulate"))
        if command == "simulate":  # ten fixed steps: a bounded cost whatever the scene
            return ["simulate", "{input}", "--method", "rk4-baumgarte", "--t-end", "0.01",
                    "--step", "0.001", "--out", "{out}/run"]
        return [command, "{input}"]
    if case.kind == "urdf":
        if rng.random() < 0.5:
            return ["info", "{input}"]
        return ["inverse", "{input}", "--motion", "{model}", "--out", "{out}/out.csv"]
    return ["inverse", "{model}", "--motion", "{input}", "--out", "{out}/out.csv"]


def companion(case: Case) -> Path | None:
    """The other file a command needs: the URDF of a motion, the motion of a URDF."""
    if case.kind == "scene":
        return None
    return case.model if case.kind == "motion" else case.seed_file.parent / "motion.csv"


def run_cli(argv: list[str]) -> tuple[int, str]:
    """``hexapod ARGV`` in process: its exit status and stderr."""
    from hexapod.cli import main

    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        try:
            status = main(argv)
        except SystemExit as exit_:
            status = exit_.code if isinstance(exit_.code, int) else 1
    return status, stderr.getvalue()


def one_message(stderr: str) -> bool:
    """One ``hexapod: error:`` line, its problems (``  - ...``) and warnings: nothing else."""
    lines = stderr.strip().splitlines()
    return (sum(line.startswith("hexapod: error:") for line in lines) == 1
            and all(line.startswith(("hexapod: error:", "hexapod: warning:", "  - "))
                    for line in lines))


def expected_outputs(argv: list[str], status: int, stderr: str) -> set[str]:
    """What the output directory may hold after the command: its output when it succeeded
    (a failed simulation keeps the states up to the failure, by design), else nothing."""
    if "--out" not in argv:
        return set()
    name = Path(argv[argv.index("--out") + 1]).name
    if status == 0 or (argv[0] == "simulate" and "the states up to it are in" in stderr):
        return {name}
    return set()


def leftovers(out: Path, expected: set[str]) -> list[str]:
    """What the output directory holds beyond the expected outputs, temporary files included
    (in the output directory and in an output that is a directory)."""
    found = sorted(p.name for p in out.iterdir() if p.name not in expected)
    for name in sorted(expected):
        if (out / name).is_dir():
            found += [f"{name}/{p.name}" for p in (out / name).iterdir()
                      if p.name.startswith(".")]
    return found


def judge_cli(argv: list[str], path: Path, out: Path) -> Outcome:
    """Run ``hexapod ARGV``; judge its exit, its message and what it left in ``out``."""
    try:
        status, stderr = run_cli(argv)
    except Exception as error:  # escaped main() itself
        return Outcome("traceback", f"hexapod {' '.join(argv)}\n"
                       + "".join(traceback.format_exception(error)))
    command = f"hexapod {' '.join(argv)} -> exit {status}\n{stderr}"
    if "Traceback" in stderr or "internal error" in stderr:
        return Outcome("traceback", command)
    if status != 0 and not one_message(stderr):
        return Outcome("traceback", command + "\n(not one 'hexapod: error:' message)")
    extra = leftovers(out, expected_outputs(argv, status, stderr))
    if extra:
        return Outcome("partial", command, extra)
    if status == 0:
        return Outcome("accepted", command)
    return Outcome("rejected", command, unnamed=path.name not in stderr)


def fill(template: list[str], path: Path, model: Path | None, out: Path) -> list[str]:
    return [a.format(input=path, model=model or "", out=out) for a in template]


def check_cli(case: Case, path: Path, out: Path, rng: random.Random) -> Outcome:
    """The command line on the input, writing (if at all) into the empty directory ``out``."""
    template = cli_arguments(case, rng)
    outcome = judge_cli(fill(template, path, companion(case), out), path, out)
    outcome.command = template
    return outcome


# ------------------------------------------------------------------ the run


@dataclass
class Tally:
    counts: Counter = field(default_factory=Counter)
    failures: int = 0

    def add(self, kind: str, path: str, outcome: Outcome) -> None:
        self.counts[(kind, path, outcome.status)] += 1
        self.counts[(kind, path, "unnamed")] += outcome.unnamed

    def table(self) -> str:
        statuses = ("accepted", "rejected", "traceback", "partial")
        rows = [("input", "path", "runs", *statuses, "unnamed")]
        for kind in KINDS:
            for path in ("library", "cli"):
                counts = [self.counts[(kind, path, s)] for s in statuses + ("unnamed",)]
                rows.append((kind, path, str(sum(counts[:-1])), *map(str, counts)))
        totals = [sum(v for (_, _, s), v in self.counts.items() if s == status)
                  for status in statuses + ("unnamed",)]
        rows.append(("all", "", str(sum(totals[:-1])), *map(str, totals)))
        widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
        lines = ["  ".join(c.ljust(w) if i < 2 else c.rjust(w)
                           for i, (c, w) in enumerate(zip(r, widths, strict=True)))
                 for r in rows]
        return "\n".join(lines[:1] + ["-" * len(lines[0])] + lines[1:-1]
                         + ["-" * len(lines[0])] + lines[-1:])


def save_failure(folder: Path, number: int, case: Case, path: Path, outcome: Outcome,
                 how: str) -> Path:
    """Keep a failing input, with what it needs and what happened, for --replay."""
    target = folder / f"{number:04d}-{case.kind}-{how}"
    target.mkdir(parents=True, exist_ok=True)
    (target / path.name).write_bytes(case.data)
    other = companion(case)
    if other is not None:
        shutil.copy(other, target / other.name)
    command = json.dumps(outcome.command) if outcome.command else ""
    (target / "failure.txt").write_text(
        f"kind: {case.kind}\ninput: {path.name}\ncompanion: {other.name if other else ''}\n"
        f"command: {command}\nmade from: {case.seed_file.relative_to(ROOT)}\nmutations:\n"
        + "".join(f"  - {m}\n" for m in case.mutations)
        + f"path: {how}\nstatus: {outcome.status}\nleftovers: {outcome.leftovers}\n\n"
        + outcome.detail + "\n", encoding="utf-8")
    return target


def run(count: int, seed: int, cli_share: float, failures: Path, progress) -> Tally:
    rng = random.Random(seed)
    tally = Tally()
    with tempfile.TemporaryDirectory(prefix="hexapod-fuzz-") as work:
        work = Path(work)
        for number in range(count):
            case = make_case(rng)
            folder = work / f"{number:05d}"
            folder.mkdir()
            path = folder / f"input{case.suffix}"
            path.write_bytes(case.data)
            runs = [("library", check_library(case, path))]
            if rng.random() < cli_share:
                out = folder / "out"
                out.mkdir()
                with _quiet():
                    runs.append(("cli", check_cli(case, path, out, rng)))
            for how, outcome in runs:
                tally.add(case.kind, how, outcome)
                if outcome.status in ("traceback", "partial"):
                    tally.failures += 1
                    saved = save_failure(failures, number, case, path, outcome, how)
                    progress(f"\n{outcome.status}: {saved}\n")
            shutil.rmtree(folder)
            if (number + 1) % 50 == 0 or number + 1 == count:
                progress(f"\r{number + 1}/{count} inputs, {tally.failures} failures")
    progress("\n")
    return tally


def replay(folder: Path) -> int:
    """Run one saved failure again (through the command line too when it failed there)."""
    info = dict(line.split(":", 1) for line in
                (folder / "failure.txt").read_text(encoding="utf-8").splitlines()[:4])
    info = {key: value.strip() for key, value in info.items()}
    path = folder / info["input"]
    model = folder / info["companion"] if info["companion"] else None
    case = Case(info["kind"], path, [], path.read_bytes())  # its model.urdf is beside it
    outcome = check_library(case, path)
    print(f"library: {outcome.status}\n{outcome.detail}")
    failed = outcome.status not in ("accepted", "rejected")
    if info["command"]:
        with tempfile.TemporaryDirectory() as out:
            argv = fill(json.loads(info["command"]), path, model, Path(out))
            outcome = judge_cli(argv, path, Path(out))
        print(f"command line: {outcome.status} {outcome.leftovers}\n{outcome.detail}")
        failed |= outcome.status not in ("accepted", "rejected")
    return 1 if failed else 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--count", type=int, default=5000, help="inputs to make (default 5000)")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--cli-share", type=float, default=0.25,
                        help="share of the inputs also run through the command line "
                        "(default 0.25)")
    parser.add_argument("--failures", type=Path, default=Path("fuzz-failures"),
                        help="where failing inputs are saved (default fuzz-failures)")
    parser.add_argument("--replay", type=Path, metavar="DIR", help="run one saved failure")
    args = parser.parse_args(argv)
    if args.replay:
        return replay(args.replay)
    started = time.perf_counter()

    def progress(text: str) -> None:
        print(text, end="", file=sys.stderr, flush=True)

    tally = run(args.count, args.seed, args.cli_share, args.failures, progress)
    elapsed = time.perf_counter() - started
    print(f"hexapod input fuzzing: {args.count} inputs, seed {args.seed}, "
          f"{elapsed:.0f} s\n")
    print(tally.table())
    partial = sum(v for (_, _, s), v in tally.counts.items() if s == "partial")
    tracebacks = sum(v for (_, _, s), v in tally.counts.items() if s == "traceback")
    print(f"\ntracebacks: {tracebacks}, partial files: {partial}"
          + (f" (inputs saved in {args.failures}/)" if tally.failures else ""))
    return 1 if tally.failures else 0


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    sys.exit(main())
