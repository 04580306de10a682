"""The vote's share per model does not shrink below its floor as the library grows."""

import numpy as np
import pytest

from psorr.errors import PsorrError
from psorr.hypotheses.pairs import PairParams
from psorr.hypotheses.pose_clusters import densest


def _clusters(n_models: int, per_model: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Poses of ``per_model`` clusters a model, 10 cm apart, the k-th cluster with per_model - k votes."""
    poses, models, voters = [], [], []
    for model in range(n_models):
        for k in range(per_model):
            for _ in range(per_model - k):
                T = np.eye(4)
                T[:3, 3] = (0.1 * k, 0.1 * model, 1.0)
                poses.append(T)
                models.append(model)
                voters.append(len(voters))
    return np.array(poses), np.array(models), np.array(voters)


def test_each_model_keeps_its_floor_in_a_large_library():
    poses, models, voters = _clusters(n_models=40, per_model=5)
    centres = np.zeros((40, 3))
    shared = densest(poses, models, voters, centres, 0.02, limit=100)
    floored = densest(poses, models, voters, centres, 0.02, limit=100, least_per_model=4)
    assert np.bincount(models[shared], minlength=40).max() == 2  # 100 over 40 models
    assert (np.bincount(models[floored], minlength=40) == 4).all()
    # The floor keeps each model's best-supported clusters: its third is among them now.
    third = poses[floored][:, 0, 3]
    assert np.isclose(third, 0.2).sum() == 40


def test_a_small_library_keeps_its_equal_share():
    poses, models, voters = _clusters(n_models=4, per_model=30)
    chosen = densest(poses, models, voters, np.zeros((4, 3)), 0.02, limit=100, least_per_model=10)
    assert (np.bincount(models[chosen], minlength=4) == 25).all()


def test_the_floor_must_be_a_whole_number_of_poses():
    with pytest.raises(PsorrError, match="least_per_model"):
        PairParams(least_per_model=0)
