"""QPBO (psorr.hypotheses.qpbo) against brute force on small hand-made problems."""

import itertools

import numpy as np
import pytest

from psorr.errors import InvalidInputError
from psorr.hypotheses.qpbo import solve_qpbo


def _brute_force(unary, edges, pairwise):
    best = None
    for x in itertools.product((0, 1), repeat=len(unary)):
        x = np.array(x)
        e = unary[np.arange(len(x)), x].sum() + sum(pw[2 * x[i] + x[j]] for (i, j), pw in zip(edges, pairwise))
        best = e if best is None else min(best, e)
    return best


def test_a_submodular_chain_is_solved_exactly_and_fully_labelled():
    unary = np.array([[0.0, 2.0], [1.0, 0.0], [0.0, 0.5], [3.0, 0.0]])
    edges = np.array([[0, 1], [1, 2], [2, 3]])
    pairwise = np.tile([0.0, 1.0, 1.0, 0.0], (3, 1))  # Potts: agreeing costs nothing
    result = solve_qpbo(unary, edges, pairwise)
    assert (result.labels >= 0).all()
    assert result.energy == pytest.approx(_brute_force(unary, edges, pairwise))


def test_a_non_submodular_problem_with_a_clear_optimum_is_solved():
    # Two nodes that must not both be 1 (E11 = 10 > E01 + E10 = 0: not submodular); node 0 wants 1 more.
    unary = np.array([[0.0, -3.0], [0.0, -2.0]])
    edges = np.array([[0, 1]])
    pairwise = np.array([[0.0, 0.0, 0.0, 10.0]])
    result = solve_qpbo(unary, edges, pairwise)
    assert result.labels.tolist() == [1, 0]
    assert result.energy == pytest.approx(-3.0)


def test_a_frustrated_triangle_leaves_every_node_unlabelled():
    # Each pair wants to differ, which three nodes cannot all do: roof duality decides nothing.
    edges = np.array([[0, 1], [1, 2], [0, 2]])
    result = solve_qpbo(np.zeros((3, 2)), edges, np.tile([1.0, 0.0, 0.0, 1.0], (3, 1)))
    assert result.unlabelled.tolist() == [0, 1, 2]


def test_bad_edges_are_refused():
    with pytest.raises(InvalidInputError, match="index"):
        solve_qpbo(np.zeros((2, 2)), np.array([[0, 5]]), np.zeros((1, 4)))
