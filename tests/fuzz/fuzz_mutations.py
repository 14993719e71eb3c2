"""The mutations of ``tests/fuzz/fuzz_inputs.py``: nasty values, byte-level mutations and random
input (any file), and the mutations of a parsed URDF and of a motion table.

The mutations of a scene file are in ``fuzz_toml.py``; ``tests/test_malformed_inputs.py`` draws
all of them with Hypothesis.
"""

from __future__ import annotations

import contextlib
import copy
import csv
import datetime
import io
import math
import random
import xml.etree.ElementTree as ET

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


def byte_mutations(rng: random.Random, data: bytes, tags: bool) -> tuple[list[str], bytes]:
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
        return byte_mutations(rng, data, tags=True)
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
        return byte_mutations(rng, data, tags=False)
    rows = list(csv.reader(io.StringIO(data.decode())))
    done = [mutate_rows(rng, rows) for _ in range(rng.randrange(1, 4))]
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    return done, buffer.getvalue().encode()
