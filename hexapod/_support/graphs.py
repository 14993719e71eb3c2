"""Graph algorithms with no mechanics in them (used by assembly and topology).

Edges are oriented ``(tail, head)``. The incidence matrix has +1 where a vertex is an edge's initial
vertex (its tail) and -1 where it is its final vertex (head), as in Richard, Anderson and Andrews
(1989/90).
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Sequence

import numpy as np


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


def components(vertices: Sequence[Hashable], edges: Sequence[tuple[Hashable, Hashable]]) -> int:
    """Number of connected components."""
    tree, _ = spanning_forest(vertices, edges)
    return len(vertices) - len(tree)


def incidence_matrix(vertices: Sequence[Hashable],
                     edges: Sequence[tuple[Hashable, Hashable]]) -> np.ndarray:
    """``K`` (v x e): +1 at an edge's tail, -1 at its head."""
    row = {v: i for i, v in enumerate(vertices)}
    K = np.zeros((len(vertices), len(edges)), dtype=int)
    for j, (tail, head) in enumerate(edges):
        K[row[tail], j] += 1
        K[row[head], j] -= 1
    return K


def cutset_matrix(incidence: np.ndarray, tree: Sequence[int], root: int = 0) -> np.ndarray:
    """The fundamental cutset matrix by row reduction of the incidence matrix.

    The root's row is dropped (the reduced incidence matrix has rank v - 1 for a connected
    graph); Gauss-Jordan elimination on the tree columns, with pivots of +-1 since a tree's
    incidence matrix is unimodular, gives one row per tree branch with +1 in that branch's
    column and 0 in the other branches' columns. Row ``i`` is the cutset of ``tree[i]``;
    columns are the graph's edges in their own order.
    """
    rows = [r for r in range(incidence.shape[0]) if r != root]
    D = incidence[rows].astype(int)
    pivot_of = {}
    free_rows = set(range(D.shape[0]))
    for branch in tree:
        candidates = [r for r in sorted(free_rows) if D[r, branch] != 0]
        if not candidates:
            raise ValueError(f"edge {branch} is not a tree branch: its column is dependent")
        r = candidates[0]
        D[r] *= D[r, branch]  # entries are +-1: make the pivot +1
        for other in range(D.shape[0]):
            if other != r and D[other, branch] != 0:
                D[other] -= D[other, branch] * D[r]
        free_rows.discard(r)
        pivot_of[branch] = r
    return np.array([D[pivot_of[b]] for b in tree], dtype=int)


def circuit_matrix(vertices: Sequence[Hashable], edges: Sequence[tuple[Hashable, Hashable]],
                   tree: Sequence[int], chords: Sequence[int]) -> np.ndarray:
    """The fundamental circuit matrix, built from tree paths (independently of the cutsets).

    The circuit of chord ``c = (a, b)`` runs along ``c`` from ``a`` to ``b`` and back to ``a``
    through the tree; an edge gets +1 when the circuit runs from its tail to its head, -1 the
    other way. Row ``i`` is the circuit of ``chords[i]``; columns are the edges.
    """
    neighbours: dict = {v: [] for v in vertices}
    for j in tree:
        tail, head = edges[j]
        neighbours[tail].append((head, j, +1))  # walking tail -> head
        neighbours[head].append((tail, j, -1))
    C = np.zeros((len(chords), len(edges)), dtype=int)
    for i, c in enumerate(chords):
        tail, head = edges[c]
        C[i, c] = 1
        for j, sign in _tree_path(neighbours, head, tail):
            C[i, j] += sign
    return C


def _tree_path(neighbours: dict, start, goal) -> list[tuple[int, int]]:
    """Edges (index, +1 along its orientation / -1 against) of the tree path start -> goal."""
    previous = {start: None}
    frontier = [start]
    while frontier and goal not in previous:
        nxt = []
        for v in frontier:
            for w, j, sign in neighbours[v]:
                if w not in previous:
                    previous[w] = (v, j, sign)
                    nxt.append(w)
        frontier = nxt
    if goal not in previous:
        raise ValueError("the chord's ends are not connected by the tree")
    path = []
    v = goal
    while previous[v] is not None:
        v, j, sign = previous[v]
        path.append((j, sign))
    return path[::-1]
