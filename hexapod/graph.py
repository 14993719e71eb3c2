"""Graph algorithms with no mechanics in them (used by assembly and topology)."""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Sequence


def spanning_forest(vertices: Iterable[Hashable],
                    edges: Sequence[tuple[Hashable, Hashable]]) -> tuple[list[int], list[int]]:
    """Split ``edges`` into tree edges and chords (loop-closing edges), in the given order.

    An edge joining two vertices already connected by earlier tree edges is a chord, so the
    order of ``edges`` decides which edge of a loop closes it. Returns the indices of the tree
    edges and of the chords.
    """
    parent = {v: v for v in vertices}

    def root(v):
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        return v

    tree, chords = [], []
    for index, (a, b) in enumerate(edges):
        ra, rb = root(a), root(b)
        if ra == rb:
            chords.append(index)
        else:
            parent[ra] = rb
            tree.append(index)
    return tree, chords
