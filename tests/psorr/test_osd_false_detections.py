"""Real Kinect clouds that hold none of our parts (the OSD learn set): what the acceptance rules remove.
Skips when ../shared/osd is absent; benchmarks/osd_false_positives.py measures all 45 clouds."""


import numpy as np
import pytest
from paths import SHARED

from psorr import AcceptParams, SupportCropParams
from psorr.acceptance import accept
from psorr.io.clouds import read_cloud
from psorr.recognize import RecognizeParams, Recognizer

LEARN = SHARED / "osd/learn"


@pytest.mark.parametrize(("scene", "method", "model"), [("learn39", "psorr", "circuit_board"),
                                                        ("learn40", "psorr", "circuit_board")])
def test_a_pose_only_the_table_supports_is_not_a_detection(library, scene, method, model, monkeypatch):
    # Posed flat on the table, a board's 1.6 mm is within the depth tolerance of the table, and where the
    # tolerance is as tall as its components (22 mm at 1.6 m), all of it is supported by the table alone.
    # These are the two of the 45 clouds where PSORR, with the rule off, poses one so; ORR poses none.
    # In learn40 the board also sinks into the table, which a later rule refuses; it is left out here, so
    # that the rule under test is the one that refuses the pose. The support crop's bar, which now rises with
    # the noise, leaves that far table out of the decomposition, and the board is not posed there at all: the
    # fixed 8 mm bar keeps it in, so that the rule is what stands between the pose and a detection.
    path = LEARN / f"{scene}.pcd"
    if not path.is_file():
        pytest.skip(f"{path} is absent (the OSD data set is not installed)")
    cloud = read_cloud(path)
    monkeypatch.setattr(accept, "sinks_into_table", lambda *args: False)
    ruled_off = Recognizer(library, method, RecognizeParams(acceptance=AcceptParams(min_support_above_table=0),
                                                            support_crop=SupportCropParams(sensor_noise=False)))
    found = [d.model for d in ruled_off.recognize(cloud, np.random.default_rng(0)).detections]
    assert found and set(found) == {model}, found
    fixed_bar = RecognizeParams(support_crop=SupportCropParams(sensor_noise=False))
    assert Recognizer(library, method, fixed_bar).recognize(cloud, np.random.default_rng(0)).detections == ()
    monkeypatch.undo()
    assert Recognizer(library, method).recognize(cloud, np.random.default_rng(0)).detections == ()


@pytest.mark.parametrize("scene", ["learn39", "learn40"])
def test_a_far_tables_noise_is_not_decomposed(library, scene, monkeypatch):
    # The same clouds with the rule off and the support crop's bar rising with the noise: the far table is left
    # out, and nothing is posed on it to begin with.
    path = LEARN / f"{scene}.pcd"
    if not path.is_file():
        pytest.skip(f"{path} is absent (the OSD data set is not installed)")
    monkeypatch.setattr(accept, "sinks_into_table", lambda *args: False)
    ruled_off = Recognizer(library, "psorr", RecognizeParams(acceptance=AcceptParams(min_support_above_table=0)))
    assert ruled_off.recognize(read_cloud(path), np.random.default_rng(0)).detections == ()
