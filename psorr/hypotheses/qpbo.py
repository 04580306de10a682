"""Quadratic pseudo-boolean optimisation (QPBO; Kolmogorov and Rother 2007) by thinqpbo: the minimum of
an energy over binary labels, with pairwise terms that need not be submodular, where the nodes that
the roof duality cannot decide stay unlabelled (their persistency is unknown)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.errors import InvalidInputError

try:  # a dependency of psorr, imported here alone so that the rest of the library loads without it
    import thinqpbo
except ImportError:  # pragma: no cover - reported when used
    thinqpbo = None


@dataclass(frozen=True, eq=False)
class QpboResult:
    """labels (N,) int8: 0 or 1 where QPBO decides (persistent: some minimum has it), -1 where it cannot;
    energy: of the labelling with the undecided nodes at 0."""

    labels: np.ndarray
    energy: float

    @property
    def unlabelled(self) -> np.ndarray:
        return np.flatnonzero(self.labels < 0)


def solve_qpbo(unary: np.ndarray, edges: np.ndarray, pairwise: np.ndarray) -> QpboResult:
    """Minimise sum_i unary[i, x_i] + sum_e pairwise[e, 2 x_i + x_j] over x in {0, 1}^N.

    Args:
        unary: (N, 2) costs of label 0 and 1.
        edges: (E, 2) node pairs (i, j).
        pairwise: (E, 4) costs of (x_i, x_j) = (0, 0), (0, 1), (1, 0), (1, 1).
    """
    if thinqpbo is None:
        raise InvalidInputError("QPBO needs the thinqpbo package: pip install thinqpbo")
    unary = np.asarray(unary, dtype=np.float64).reshape(-1, 2)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    pairwise = np.asarray(pairwise, dtype=np.float64).reshape(-1, 4)
    if len(edges) != len(pairwise) or (len(edges) and not 0 <= edges.min() <= edges.max() < len(unary)):
        raise InvalidInputError(f"edges ({edges.shape}) must index the {len(unary)} nodes, one row of pairwise "
                                f"({pairwise.shape}) each")
    graph = thinqpbo.QPBODouble()
    graph.add_node(len(unary))
    for i, (e0, e1) in enumerate(unary):
        graph.add_unary_term(i, float(e0), float(e1))
    for (i, j), (e00, e01, e10, e11) in zip(edges, pairwise):
        graph.add_pairwise_term(int(i), int(j), float(e00), float(e01), float(e10), float(e11))
    graph.solve()
    graph.compute_weak_persistencies()
    labels = np.array([graph.get_label(i) for i in range(len(unary))], dtype=np.int8)
    labels[labels < 0] = -1
    x = np.maximum(labels, 0)
    energy = unary[np.arange(len(x)), x].sum() + (pairwise[np.arange(len(edges)), 2 * x[edges[:, 0]] + x[edges[:, 1]]]
                                                  .sum() if len(edges) else 0.0)
    return QpboResult(labels, float(energy))
