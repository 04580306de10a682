"""Real Kinect clouds that hold none of our parts (the OSD learn set): what the acceptance rules remove.
Skips when ../shared/osd is absent; benchmarks/osd_false_positives.py measures all 45 clouds."""


import numpy as np
import pytest
from paths import SHARED

from psorr import AcceptParams
from psorr.io.clouds import read_cloud
from psorr.recognize import RecognizeParams, Recognizer

LEARN = SHARED / "osd/learn"


@pytest.mark.parametrize(("scene", "method", "model"), [("learn38", "orr", "circuit_board"),
                                                        ("learn44", "psorr", "u_channel")])
def test_a_pose_only_the_table_supports_is_not_a_detection(library, scene, method, model):
    # At the far edge of the table, 1.6 m off, the depth tolerance (22 mm) is as tall as a board's components:
    # posed flat there, a board or a channel's web is supported by the table alone.
    path = LEARN / f"{scene}.pcd"
    if not path.is_file():
        pytest.skip(f"{path} is absent (the OSD data set is not installed)")
    cloud = read_cloud(path)
    ruled_off = Recognizer(library, method, RecognizeParams(acceptance=AcceptParams(min_support_above_table=0)))
    found = [d.model for d in ruled_off.recognize(cloud, np.random.default_rng(0)).detections]
    assert found and set(found) == {model}, found
    assert Recognizer(library, method).recognize(cloud, np.random.default_rng(0)).detections == ()
