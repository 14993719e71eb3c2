"""Limits on the size of a job, weighed before the work: memory, steps, model size.

A job whose estimate passes a limit is refused with one :class:`~hexapod.errors.HexapodError`
saying what it would need, how to ask for less, and how to raise the limit. Each limit has a
default, an environment variable and, on the commands it concerns, a command-line option:

=============  ==============================  =======================  ==================
limit          default                         environment              option
=============  ==============================  =======================  ==================
memory         half the physical memory, at    ``HEXAPOD_MAX_MEMORY``   ``--max-memory``
               most 8 GiB (4 GiB if unknown)   (e.g. ``16G``)           (report, inverse,
                                                                        simulate)
steps          10,000,000                      ``HEXAPOD_MAX_STEPS``    ``--max-steps``
                                                                        (simulate)
bodies,        10,000 each                     ``HEXAPOD_MAX_BODIES``
joints
contacts       32                              ``HEXAPOD_MAX_CONTACTS``
instants       20,000                          ``HEXAPOD_MAX_INSTANTS`` ``--max-instants``
exported                                                                (export)
cases          100,000                         ``HEXAPOD_MAX_CASES``    ``--max-cases``
                                                                        (sweep)
=============  ==============================  =======================  ==================

Files a command reads are weighed against the memory limit before they are read
(:func:`hexapod._support.files.open_input`).

An option given wins over the environment, which wins over the default. Nothing here imports
NumPy: the command line parses sizes before loading it.
"""

from __future__ import annotations

import math
import os
import re

from hexapod.errors import HexapodError

GIB = 1024**3
#: at most this much memory by default, however large the machine: a job that needs more is
#: most likely a mistake (a misplaced exponent), and one that is meant can say so
MEMORY_CAP = 8 * GIB
#: the default when the physical memory cannot be read
MEMORY_UNKNOWN = 4 * GIB
#: steps of a simulation: at about a millisecond a step on a walking robot, some hours
DEFAULT_MAX_STEPS = 10_000_000
#: bodies (and joints) of a scene: assembling a model builds symbolic expressions per body, and
#: scenes beyond this many would take minutes before anything is computed
DEFAULT_MAX_BODIES = 10_000
#: foot contacts of a scene: the ground-force policy and the report's per-foot figures grow
#: faster than the square of their number (one body on 30 feet: a report of 12 s; 50: 32 s
#: and 1 GB; 100: over 2 minutes and 5 GB)
DEFAULT_MAX_CONTACTS = 32
#: saved instants of a result that ``hexapod export`` reads: each becomes VTK files held in
#: memory until the directory is written (about 8 KB and, for a report, a Newton solve each)
DEFAULT_MAX_INSTANTS = 20_000
#: cases of a design study: each is a run of its own and a file in the study's cases/ folder;
#: at a tenth of a second a case, a day of one core
DEFAULT_MAX_CASES = 100_000

_UNITS = {"": 1, "K": 1024, "M": 1024**2, "G": GIB, "T": 1024**4}
_SIZE = re.compile(r"\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([KMGT]?)(?:I?B)?\s*",
                   re.IGNORECASE)


def parse_size(text: str) -> int:
    """A memory size in bytes from ``"16G"``, ``"512M"``, ``"1.5GiB"`` or ``"1000000"``
    (binary units: K = 1024); a ``ValueError`` for anything else, zero or non-finite."""
    match = _SIZE.fullmatch(str(text))
    if not match:
        raise ValueError(f"not a memory size: {text!r} (write e.g. 16G, 512M)")
    value = float(match.group(1)) * _UNITS[match.group(2).upper()]
    if not (math.isfinite(value) and value >= 1):
        raise ValueError(f"not a memory size: {text!r} (write e.g. 16G, 512M)")
    return int(value)


def size_text(size: float) -> str:
    """Bytes as a person reads them: ``7.7 GiB``, ``512 MiB``."""
    if not math.isfinite(size):
        return "more than any machine has"
    for unit, factor in (("TiB", 1024**4), ("GiB", GIB), ("MiB", 1024**2), ("KiB", 1024)):
        if size >= factor:
            return f"{size / factor:.2g} {unit}" if size < 10 * factor \
                else f"{size / factor:.0f} {unit}"
    return f"{size:.0f} bytes"


def physical_memory() -> int | None:
    """The machine's physical memory in bytes, None when it cannot be read."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        pass
    try:
        with open("/proc/meminfo", "rb") as meminfo:
            for line in meminfo:
                if line.startswith(b"MemTotal:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def default_memory() -> int:
    """Half the physical memory, at most :data:`MEMORY_CAP`."""
    total = physical_memory()
    return MEMORY_UNKNOWN if not total else min(total // 2, MEMORY_CAP)


def _from_environment(name: str, parse, default):
    text = os.environ.get(name)
    if text is None or not text.strip():
        return default
    try:
        value = parse(text)
    except ValueError as error:
        raise HexapodError(f"environment variable {name}: {error}") from None
    return value


def _whole(text: str) -> int:
    """A positive whole number, written ``10000000`` or ``1e7``."""
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"not a whole number: {text!r}") from None
    if not (math.isfinite(value) and value >= 1 and value == int(value)):
        raise ValueError(f"must be a positive whole number, got {text!r}")
    return int(value)


def max_memory(given: int | None = None) -> int:
    """The memory limit in bytes: ``given``, else ``HEXAPOD_MAX_MEMORY``, else the default."""
    if given is not None:
        return int(given)
    return _from_environment("HEXAPOD_MAX_MEMORY", parse_size, None) or default_memory()


def max_steps(given: int | None = None) -> int:
    """The step limit: ``given``, else ``HEXAPOD_MAX_STEPS``, else :data:`DEFAULT_MAX_STEPS`."""
    if given is not None:
        return int(given)
    return _from_environment("HEXAPOD_MAX_STEPS", _whole, DEFAULT_MAX_STEPS)


def max_bodies() -> int:
    """The limit on bodies and on joints: ``HEXAPOD_MAX_BODIES``, else
    :data:`DEFAULT_MAX_BODIES`."""
    return _from_environment("HEXAPOD_MAX_BODIES", _whole, DEFAULT_MAX_BODIES)


def max_instants(given: int | None = None) -> int:
    """The limit on the saved instants an export reads: ``given``, else
    ``HEXAPOD_MAX_INSTANTS``, else :data:`DEFAULT_MAX_INSTANTS`."""
    if given is not None:
        return int(given)
    return _from_environment("HEXAPOD_MAX_INSTANTS", _whole, DEFAULT_MAX_INSTANTS)


def check_instants(count: int, what: str, limit: int | None = None) -> None:
    """Refuse to export more than ``limit`` (or :func:`max_instants`) saved instants."""
    bound = max_instants(limit)
    if count > bound:
        raise HexapodError(
            f"{what} holds {count:,} saved instants (limit {bound:,}): export a shorter run or "
            f"fewer samples, or raise the limit with "
            f"{_raise_with('--max-instants', _round_up(count), 'HEXAPOD_MAX_INSTANTS')}")


def _suggested_size(size: float) -> str:
    """A round size above ``size`` to suggest as a new limit: ``8G``, ``512M``."""
    for unit, factor in (("T", 1024**4), ("G", GIB), ("M", 1024**2)):
        if size >= factor or unit == "M":
            return f"{max(1, math.ceil(size / factor))}{unit}"
    return "1G"  # not reached


def _round_up(count: float) -> str:
    """A round number above ``count``, as the command line takes it: ``2e8``."""
    if not math.isfinite(count) or count > 1e18:
        return "N"
    exponent = math.floor(math.log10(max(count, 1)))
    mantissa = math.ceil(count / 10**exponent)
    return f"1e{exponent + 1}" if mantissa == 10 else f"{mantissa}e{exponent}"


def _shown(count: float) -> str:
    """A count in two digits, as ``1.2e12`` (not ``1.2e+12``)."""
    mantissa, e, exponent = f"{count:.2g}".partition("e")
    return f"{mantissa}e{int(exponent)}" if e else mantissa


def _raise_with(option: str | None, value: str, variable: str) -> str:
    """How to raise a limit: "--max-memory 8G (or HEXAPOD_MAX_MEMORY)", or without an option
    "the environment variable HEXAPOD_MAX_MEMORY=8G"."""
    if option is None:
        return f"the environment variable {variable}={value}"
    return f"{option} {value} (or {variable})"


def check_memory(estimate: float, what: str, how_to_lower: str,
                 limit: int | None = None, option: str | None = "--max-memory") -> None:
    """Refuse a job whose memory ``estimate`` (bytes) passes the limit (``limit`` or
    :func:`max_memory`): "<what> would need about 7.7 GiB (limit 4.0 GiB): <how_to_lower>, or
    raise the limit with --max-memory 8G" (``option``: the command's option that raises it,
    None where only the environment does)."""
    bound = max_memory(limit)
    if estimate > bound:
        raise HexapodError(
            f"{what} would need about {size_text(estimate)} of memory (limit "
            f"{size_text(bound)}): {how_to_lower}, or raise the limit with "
            f"{_raise_with(option, _suggested_size(estimate), 'HEXAPOD_MAX_MEMORY')}")


def check_steps(estimate: float, what: str, how_to_lower: str,
                limit: int | None = None, option: str | None = "--max-steps") -> None:
    """Refuse a job whose number of steps ``estimate`` passes the limit (``limit`` or
    :func:`max_steps`; ``option`` as for :func:`check_memory`)."""
    bound = max_steps(limit)
    if estimate > bound:
        raise HexapodError(
            f"{what} would take about {_shown(estimate)} steps (limit {bound:,}): "
            f"{how_to_lower}, or raise the limit with "
            f"{_raise_with(option, _round_up(estimate), 'HEXAPOD_MAX_STEPS')}")


def max_contacts() -> int:
    """The limit on foot contacts: ``HEXAPOD_MAX_CONTACTS``, else :data:`DEFAULT_MAX_CONTACTS`."""
    return _from_environment("HEXAPOD_MAX_CONTACTS", _whole, DEFAULT_MAX_CONTACTS)


def check_model_size(bodies: int, joints: int, what: str, contacts: int = 0) -> None:
    """Refuse to assemble a scene of more bodies or joints than :func:`max_bodies`, or more
    foot contacts than :func:`max_contacts`."""
    bound = max_contacts()
    if contacts > bound:
        raise HexapodError(
            f"{what} has {contacts} foot contacts (limit {bound}): the sharing of the ground "
            "forces grows faster than the square of their number (50 take half a minute and a "
            "gigabyte); give fewer, or raise the limit with the environment variable "
            f"HEXAPOD_MAX_CONTACTS={contacts}")
    bound = max_bodies()
    for count, kind in ((bodies, "bodies"), (joints, "joints")):
        if count > bound:
            raise HexapodError(
                f"{what} has {count} {kind} (limit {bound}): assembling it would take minutes; "
                "split the scene, or raise the limit with the environment variable "
                f"HEXAPOD_MAX_BODIES={count}")


def max_cases(given: int | None = None) -> int:
    """The limit on a study's cases: ``given``, else ``HEXAPOD_MAX_CASES``, else
    :data:`DEFAULT_MAX_CASES`."""
    if given is not None:
        return int(given)
    return _from_environment("HEXAPOD_MAX_CASES", _whole, DEFAULT_MAX_CASES)


def check_cases(count: float, what: str, limit: int | None = None) -> None:
    """Refuse a design study of more cases than the limit (``limit`` or :func:`max_cases`),
    before any case is listed."""
    bound = max_cases(limit)
    if count > bound:
        count = count if count < 1e300 else math.inf  # an int past a float's range
        shown = _shown(count) if count < math.inf else "more than 1e300"
        raise HexapodError(
            f"{what} has {shown} cases (limit {bound:,}): vary fewer values or draw "
            f"fewer samples, or raise the limit with --max-cases {_round_up(count)} (or "
            "HEXAPOD_MAX_CASES)")
