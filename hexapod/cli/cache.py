"""``hexapod cache``: what the cache on disk holds, and cleaning it (:mod:`hexapod._support.cache`).

Neither action loads NumPy or CasADi: the cache's entries are folders of files.
"""

from __future__ import annotations

import json
import os
import time

HELP = "what the cache of compiled code holds; clean it"
DESCRIPTION = (
    "The cache on disk keeps compiled code under the content hash of each model, so that the "
    "second compiled run of the same model compiles nothing. Folder: HEXAPOD_CACHE_DIR, else "
    "$XDG_CACHE_HOME/hexapod, else ~/.cache/hexapod; "
    "HEXAPOD_CACHE=0 turns it off; at most HEXAPOD_CACHE_SIZE (default 1G), the entries used "
    "least recently removed beyond. 'info' (the default) lists it, 'clean' empties it.")


def add_arguments(parser) -> None:
    from hexapod.cli.common import memory_size, positive

    actions = parser.add_subparsers(dest="action", metavar="ACTION")
    info = actions.add_parser("info", help="the folder, its entries, their size and the limit",
                              description="The cache folder, each entry (size, last use, what "
                              "it holds), their total size and the limit.")
    info.add_argument("--json", action="store_true", help="print the same as JSON")
    clean = actions.add_parser(
        "clean", help="remove entries: all, or the old ones, or down to a size",
        description="Remove the cache's entries: every one by default; with --older-than, those "
        "not used for that many days; with --max-size, the least recently used until the rest "
        "hold at most SIZE. Nothing else in the folder is touched; whatever is removed is "
        "built again when next needed.")
    clean.add_argument("--older-than", type=positive(float), metavar="DAYS",
                       help="remove the entries not used for DAYS days (e.g. 30, or 0.5)")
    clean.add_argument("--max-size", type=memory_size, metavar="SIZE",
                       help="remove the least recently used entries until the rest hold at "
                       "most SIZE (e.g. 200M)")


def run(args) -> int:
    from hexapod._support import cache

    if getattr(args, "action", None) == "clean":
        return _clean(cache, args)
    report = cache.summary()
    report["where"] = _where(cache)
    report["items"] = [{"key": e.key, "size": e.size, "used": e.used, "what": e.what}
                       for e in cache.entries(describe=True)] if report["folder"] else []
    if getattr(args, "json", False):
        print(json.dumps(report, indent=2))
        return 0
    print(_text(report))
    return 0


def _where(cache) -> str:
    """Which setting chose the folder."""
    if cache.folder() is None:
        return f"turned off by {cache.SWITCH_VARIABLE}={os.environ.get(cache.SWITCH_VARIABLE)}"
    if os.environ.get(cache.FOLDER_VARIABLE, "").strip():
        return cache.FOLDER_VARIABLE
    if os.environ.get("XDG_CACHE_HOME", "").strip():
        return "XDG_CACHE_HOME"
    return "the default"


def _text(report: dict) -> str:
    from hexapod._support.limits import size_text

    if report["folder"] is None:
        return f"the cache is off ({report['where']}): nothing is kept between runs"
    lines = [f"cache folder: {_printable(str(report['folder']))} ({report['where']})",
             f"entries: {report['entries']}, {size_text(report['size'])} of at most "
             f"{report['limit_text']}"]
    for item in reversed(report["items"]):  # most recently used first
        used = time.strftime("%Y-%m-%d %H:%M", time.localtime(item["used"]))
        lines.append(f"  {size_text(item['size']):>10}  used {used}  {_printable(item['what'])}")
    return "\n".join(lines)


def _printable(text) -> str:
    """``text`` with its control characters escaped (``\\x1b``): what an entry says is shown,
    never sent to the terminal as a command."""
    text = str(text)
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii")
                   for c in text)


def _not_removed(left: list, args) -> list:
    """The entries still there that the cleaning should have removed (it could not)."""
    if args.older_than is None and args.max_size is None:
        return left
    stale = [e for e in left if args.older_than is not None
             and time.time() - e.used > args.older_than * 86400.0]
    if args.max_size is not None and sum(e.size for e in left) > args.max_size:
        return stale or left
    return stale


def _clean(cache, args) -> int:
    from hexapod._support.limits import size_text

    root = cache.folder()
    if root is None:
        print(f"the cache is off ({_where(cache)}): nothing to clean")
        return 0
    unused = None if args.older_than is None else args.older_than * 86400.0
    removed, freed = cache.clean(root, unused_for=unused, keep_size=args.max_size)
    left = cache.entries(root)
    said = (f"removed {removed} entr{'y' if removed == 1 else 'ies'} ({size_text(freed)}) from "
            f"{root}; {len(left)} left ({size_text(sum(e.size for e in left))})")
    failed = _not_removed(left, args)
    if failed:
        from hexapod.errors import HexapodError

        writable = os.access(root, os.W_OK) and all(
            os.access(e.path.parent, os.W_OK) for e in failed)
        raise HexapodError(f"{said}: could not remove {len(failed)} entr"
                           f"{'y' if len(failed) == 1 else 'ies'}"
                           + ("" if writable else " (the folder is not writable)"))
    print(said)
    return 0
