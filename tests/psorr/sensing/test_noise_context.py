"""The depth-noise model of a recognition (psorr.sensing.noise_context): RecognizeParams.sensor, read by the stages."""

import numpy as np
import pytest
import trimesh

from psorr.decomposition.pipeline import DecomposeParams, inlier_threshold
from psorr.geometry.support_plane import band
from psorr.library.models import ModelLibrary
from psorr.recognize import Recognizer
from psorr.recognize_params import RecognizeParams
from psorr.sensing.kinect_noise import KINECT_V1, KinectNoise
from psorr.sensing.noise_context import depth_noise, noise_model
from psorr.synthetic.mesh_scenes import mesh_scene
from psorr.verification.point_check import CheckParams, depth_tolerance
from psorr.viz.observer import RecognitionObserver

NOISIER = KinectNoise(sigma_base=2 * KINECT_V1.sigma_base, sigma_quad=2 * KINECT_V1.sigma_quad)


def test_the_model_holds_inside_its_block_and_the_kinects_outside():
    assert depth_noise() is KINECT_V1
    with noise_model(NOISIER):
        assert depth_noise() is NOISIER
    assert depth_noise() is KINECT_V1
    with pytest.raises(RuntimeError), noise_model(NOISIER):
        raise RuntimeError("a stage failed")
    assert depth_noise() is KINECT_V1


def test_noise_scaled_thresholds_follow_the_model():
    z = np.array([0.6, 1.0, 1.4])
    points = np.column_stack([np.zeros((3, 2)), z])
    with noise_model(NOISIER):
        tolerance, inliers = depth_tolerance(z, CheckParams()), inlier_threshold(points, DecomposeParams())
        table_band = band()
    assert (tolerance[1:] > depth_tolerance(z, CheckParams())[1:]).all()
    assert (inliers[1:] > inlier_threshold(points, DecomposeParams())[1:]).all()
    assert band() == 0.008 and table_band > 1.5 * band()  # the supporting plane's RANSAC band


class _Seen(RecognitionObserver):
    def __init__(self):
        self.models = []

    def cloud(self, cloud):
        self.models.append(depth_noise())

    def table(self, plane):
        self.models.append(depth_noise())


def test_a_recognizers_stages_read_its_sensor_and_only_during_the_call(tmp_path):
    block = trimesh.creation.box(extents=(0.08, 0.05, 0.03))
    block.export(tmp_path / "block.stl")
    library = ModelLibrary.from_meshes([tmp_path / "block.stl"], use_cache=False)
    scene = mesh_scene(np.random.default_rng(0), {"block": block}, "single", names=["block"])
    seen = _Seen()
    Recognizer(library, "psorr", RecognizeParams(sensor=NOISIER)).recognize(scene.cloud, observer=seen)
    assert seen.models and all(m is NOISIER for m in seen.models)
    assert depth_noise() is KINECT_V1
    seen = _Seen()
    Recognizer(library, "psorr").recognize(scene.cloud, observer=seen)
    assert seen.models and all(m is KINECT_V1 for m in seen.models)
