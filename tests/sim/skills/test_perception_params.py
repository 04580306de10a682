"""The looks' recognizer and noise level (sim/skills/perception_params.py), as a sweep sets them. Headless."""

import mujoco
import numpy as np
import pytest

from psorr.sensing.kinect_noise import KINECT_V1
from sim.errors import SimInputError
from sim.skills import Perception, PerceptionParams
from sim.world import WorldConfig, build_world


def test_the_default_is_the_kinect_and_a_scale_multiplies_its_axial_noise():
    assert PerceptionParams().noise is KINECT_V1
    z = np.array([0.6, 1.0, 1.4])
    assert np.allclose(PerceptionParams(noise_scale=2).noise.axial_sigma(z), 2 * KINECT_V1.axial_sigma(z))
    assert np.allclose(PerceptionParams(noise_scale=0).noise.axial_sigma(z), 0)


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"method": "ppf"}, "choose one of .*psorr.*orr"),
    ({"noise_scale": -1}, "noise_scale must be a number in \\[0, 10\\]"),
    ({"noise_scale": True}, "noise_scale must be a number"),
])
def test_a_bad_setting_is_refused_naming_the_choices(kwargs, words):
    with pytest.raises(SimInputError, match=words):
        PerceptionParams(**kwargs)


def _depth_spread(noise_scale: float) -> float:
    """Spread (m) of the depth between neighbouring pixels on one surface (a jump under 3 cm), over the view."""
    world = build_world(WorldConfig(workpieces=("flanged_hub",)), np.random.default_rng(3))
    data = world.reset(mujoco.MjData(world.model))
    mujoco.mj_forward(world.model, data)
    params = PerceptionParams(noise_scale=noise_scale)
    with Perception(world, np.random.default_rng(0), recognize=False, params=params) as perception:
        depth = perception.look(data).frame.depth
    steps = np.diff(depth, axis=1)
    same_surface = (depth[:, 1:] > 0) & (depth[:, :-1] > 0) & (np.abs(steps) < 0.03)
    return float(np.std(steps[same_surface]))


def test_the_look_is_as_noisy_as_the_scale_says():
    quiet, kinect, loud = (_depth_spread(s) for s in (0.0, 1.0, 3.0))
    assert quiet < kinect < loud
    assert loud > 1.5 * kinect  # the lateral jitter and disparity steps stay the Kinect's
