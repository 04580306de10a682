"""Multi-label assignment by alpha-expansion (Boykov, Veksler and Zabih 2001)
with a Potts smoothness term, each expansion move solved as an s-t min cut on
PyMaxflow.

Energy: E(f) = sum_p D[p, f_p] + sum_(p,q) w_pq [f_p != f_q]. An infinite data
cost forbids a label at a point, so the move for label alpha only involves
the points alpha may take and the edges that touch them. Every cut stays
small except the one for the label allowed everywhere ("no primitive").
"""

from __future__ import annotations

import maxflow
import numpy as np


def labelling_energy(costs, labels, edge_i, edge_j, weights) -> float:
    """E(labels) for (N, L) costs."""
    data = costs[np.arange(len(labels)), labels].sum()
    return float(data + weights[labels[edge_i] != labels[edge_j]].sum())


class _Incidence:
    """For each node, the ids of the edges that touch it (CSR)."""

    def __init__(self, n_nodes, edge_i, edge_j):
        ends = np.concatenate([edge_i, edge_j])
        self.edge_ids = np.argsort(ends, kind="stable") % len(edge_i)
        self.indptr = np.r_[0, np.cumsum(np.bincount(ends, minlength=n_nodes))]

    def edges_of(self, nodes):
        starts, stops = self.indptr[nodes], self.indptr[nodes + 1]
        lengths = stops - starts
        offsets = np.repeat(starts - np.r_[0, np.cumsum(lengths)[:-1]], lengths)
        return self.edge_ids[np.arange(lengths.sum()) + offsets]


def _expansion_move(alpha, labels, costs_t, allowed, incidence, edge_i, edge_j, weights):
    """Labels after the best alpha-expansion of `labels`, or None if it changes nothing."""
    candidates = allowed[alpha]
    active_nodes = candidates[labels[candidates] != alpha]
    n_active = len(active_nodes)
    if n_active == 0:
        return None
    node = np.full(len(labels), -1, dtype=np.int64)
    node[active_nodes] = np.arange(n_active)
    keep_cost = costs_t[labels[active_nodes], active_nodes]   # x = 0
    switch_cost = costs_t[alpha, active_nodes].copy()          # x = 1

    eid = incidence.edges_of(active_nodes)
    ei, ej, w = edge_i[eid], edge_j[eid], weights[eid]
    ni, nj = node[ei], node[ej]
    # An edge with both ends free is listed twice; keep the copy from its first end.
    both = (ni >= 0) & (nj >= 0)
    first_copy = np.zeros(len(eid), dtype=bool)
    first_copy[np.flatnonzero(both)[np.unique(eid[both], return_index=True)[1]]] = True
    pair = both & first_copy
    # Both ends free. E00 = w[f_p != f_q], E01 = E10 = w, E11 = 0, written as
    # E00 + (w - E00) x_p - w x_q + (2w - E00)(1 - x_p) x_q.
    p, q, wp = ni[pair], nj[pair], w[pair]
    e00 = wp * (labels[ei[pair]] != labels[ej[pair]])
    switch_cost += np.bincount(p, wp - e00, n_active)
    keep_cost = keep_cost + np.bincount(q, wp, n_active)
    # One end free, the other held at its label g: keeping costs w[f_p != g],
    # switching costs w[alpha != g].
    one = ~both
    free_end = np.where(ni[one] >= 0, ei[one], ej[one])
    held_end = np.where(ni[one] >= 0, ej[one], ei[one])
    f_node, g, w1 = node[free_end], labels[held_end], w[one]
    keep_cost += np.bincount(f_node, w1 * (labels[free_end] != g), n_active)
    switch_cost += np.bincount(f_node, w1 * (g != alpha), n_active)

    graph = maxflow.GraphFloat(n_active, len(p))
    nodes = graph.add_nodes(n_active)
    if len(p):
        graph.add_edges(p, q, 2.0 * wp - e00, np.zeros(len(p)))
    # A node on the sink side (x = 1) cuts its source edge, so that edge carries the switch cost.
    graph.add_grid_tedges(nodes, switch_cost, keep_cost)
    graph.maxflow()
    switched = graph.get_grid_segments(nodes)
    if not switched.any():
        return None
    result = labels.copy()
    result[active_nodes[switched]] = alpha
    return result


def alpha_expansion(costs, edge_i, edge_j, weights, initial, rng, max_passes: int = 3,
                    tolerance: float = 1e-3):
    """Minimise the Potts energy over labels 0..L-1.

    Args:
        costs: (N, L) data costs; np.inf forbids a label at a point. `initial`
            must have finite cost everywhere.
        edge_i: (E,) first point of each undirected neighbour pair.
        edge_j: (E,) second point of each pair.
        weights: (E,) the pairs' Potts weights.
        initial: (N,) starting labels.
        rng: visits labels in a random order each pass.
        tolerance: stop once a pass lowers the energy by less than this fraction.
    Returns (labels (N,), energy).
    """
    labels = np.asarray(initial, dtype=np.int64).copy()
    costs_t = np.ascontiguousarray(np.asarray(costs, dtype=np.float64).T)
    allowed = [np.flatnonzero(np.isfinite(row)) for row in costs_t]
    incidence = _Incidence(len(labels), edge_i, edge_j)
    # A move only reads the labels of alpha's candidate nodes and of their
    # neighbours. A change stamps the changed nodes and their neighbours, so a
    # label none of whose candidates is stamped since its last try is skipped.
    changed_at = np.zeros(len(labels), dtype=np.int64)
    tried_at = np.full(costs_t.shape[0], -1, dtype=np.int64)
    step = 0
    energy = labelling_energy(costs, labels, edge_i, edge_j, weights)
    for _ in range(max_passes):
        start = energy
        for alpha in rng.permutation(costs_t.shape[0]):
            step += 1
            if len(allowed[alpha]) == 0 or changed_at[allowed[alpha]].max() < tried_at[alpha]:
                continue
            tried_at[alpha] = step
            candidate = _expansion_move(alpha, labels, costs_t, allowed, incidence, edge_i, edge_j, weights)
            if candidate is not None:
                changed = np.flatnonzero(candidate != labels)
                eid = incidence.edges_of(changed)
                changed_at[changed] = step
                changed_at[edge_i[eid]] = step
                changed_at[edge_j[eid]] = step
                labels = candidate
        energy = labelling_energy(costs, labels, edge_i, edge_j, weights)
        if start - energy <= tolerance * abs(start):
            break
    return labels, energy
