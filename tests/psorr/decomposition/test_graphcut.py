"""Alpha-expansion against exhaustive search on small random Potts problems."""

import itertools

import numpy as np
import pytest

from psorr.decomposition.graphcut import alpha_expansion, labelling_energy


def _random_problem(rng, n=6, n_labels=3):
    costs = rng.random((n, n_labels)) * 3
    costs[rng.random((n, n_labels)) < 0.2] = np.inf
    costs[:, -1] = 1.5  # the "no primitive" label is allowed everywhere
    edge_i, edge_j = np.triu_indices(n, 1)
    keep = rng.random(len(edge_i)) < 0.5
    return costs, edge_i[keep], edge_j[keep], rng.random(keep.sum())


@pytest.mark.parametrize("seed", range(40))
def test_result_is_optimal_over_every_expansion_move(seed):
    rng = np.random.default_rng(seed)
    costs, ei, ej, w = _random_problem(rng)
    n, n_labels = costs.shape
    labels, energy = alpha_expansion(costs, ei, ej, w, np.full(n, n_labels - 1), rng)
    assert energy == pytest.approx(labelling_energy(costs, labels, ei, ej, w))
    for alpha in range(n_labels):
        for mask in itertools.product([False, True], repeat=n):
            moved = labels.copy()
            moved[np.array(mask)] = alpha
            assert labelling_energy(costs, moved, ei, ej, w) >= energy - 1e-9


@pytest.mark.parametrize("seed", range(10))
def test_within_twice_the_global_optimum(seed):
    # Boykov et al.: expansion moves reach 2x the optimum for Potts energies.
    rng = np.random.default_rng(100 + seed)
    costs, ei, ej, w = _random_problem(rng)
    n, n_labels = costs.shape
    _, energy = alpha_expansion(costs, ei, ej, w, np.full(n, n_labels - 1), rng)
    best = min(labelling_energy(costs, np.array(c), ei, ej, w)
               for c in itertools.product(range(n_labels), repeat=n))
    assert best - 1e-9 <= energy <= 2 * best + 1e-9


def test_smoothness_cleans_an_isolated_label():
    # A chain whose middle node slightly prefers label 1; strong smoothness overrules it.
    costs = np.array([[0.0, 1.0], [0.6, 0.5], [0.0, 1.0]])
    ei, ej = np.array([0, 1]), np.array([1, 2])
    labels, _ = alpha_expansion(costs, ei, ej, np.array([1.0, 1.0]), np.array([0, 1, 0]),
                                np.random.default_rng(0))
    assert labels.tolist() == [0, 0, 0]
    labels, _ = alpha_expansion(costs, ei, ej, np.array([0.01, 0.01]), np.array([0, 0, 0]),
                                np.random.default_rng(0))
    assert labels.tolist() == [0, 1, 0]
