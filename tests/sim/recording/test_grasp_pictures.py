"""Pictures of a part's grasps (sim/recording/grasp_pictures.py): a panel per rest, and a bad folder. Headless."""

import imageio.v3 as iio
import numpy as np
import pytest
import trimesh

from psorr.synthetic.resting import stable_rests
from sim.errors import RecordingError, SimInputError
from sim.parts.grasp import Grasp
from sim.parts.grasp_synthesis import GraspSynthesisParams
from sim.recording.grasp_pictures import DPI, MAX_PANELS, PANEL_INCHES, grasps_by_rest, save_grasp_picture

SIZE = (0.06, 0.04, 0.03)  # m, a box the gripper (80 mm open) takes across any two faces


@pytest.fixture(scope="module")
def box():
    mesh = trimesh.creation.box(SIZE)
    mesh.apply_translation((0.0, 0.0, SIZE[2] / 2))  # the model frame: the resting face's centre at the origin
    return mesh


def rest_grasp(mesh, k: int, name: str | None = None) -> Grasp:
    """A grasp from above of ``mesh`` lying in its k-th stable rest, across the table's x, in the model frame."""
    T = stable_rests(mesh)[k].T_table_model
    posed = mesh.copy()
    posed.apply_transform(T)
    tool = np.array([0.0, 0.0, GraspSynthesisParams().lowest, 1.0])
    R = T[:3, :3].T
    return Grasp(name or f"rest{k}_synth_0", (np.linalg.inv(T) @ tool)[:3], R @ (0, 0, -1), R @ (1, 0, 0),
                 float(np.ptp(posed.vertices[:, 0])))


def test_a_panel_for_each_rest_with_grasps(box, tmp_path):
    grasps = [rest_grasp(box, 0), rest_grasp(box, 1)]
    picture = save_grasp_picture(tmp_path / "new" / "box.png", "box", box, grasps, color=(0.8, 0.2, 0.2))
    assert picture.path.is_file() and 5_000 < picture.path.stat().st_size < 150_000
    rests = stable_rests(box)
    assert [p.rest for p in picture.panels] == [0, 1]
    assert [p.probability for p in picture.panels] == [rests[0].probability, rests[1].probability]
    assert [p.grasps for p in picture.panels] == [(grasps[0],), (grasps[1],)]
    image = iio.imread(picture.path)
    assert image.shape[:2] == (round(PANEL_INCHES[1] * DPI), round(2 * PANEL_INCHES[0] * DPI))  # a row of two
    assert image.reshape(-1, image.shape[-1])[:, :3].std(axis=0).max() > 10  # not one colour
    assert picture.summary == "2 grasps in 2 rests"


def test_grasps_named_without_a_rest_are_the_upright_parts(box, tmp_path):
    upright = rest_grasp(box, 0, name="across_x")
    picture = save_grasp_picture(tmp_path / "box.png", "box", box, [upright])
    (panel,) = picture.panels
    assert panel.rest is None and panel.probability is None and np.array_equal(panel.T_table_model, np.eye(4))
    assert "hand-written" in panel.title and picture.summary == "1 grasp of the upright part"
    assert iio.imread(picture.path).shape[1] == round(1.5 * PANEL_INCHES[0] * DPI)  # one panel, drawn larger


def test_only_the_most_probable_rests_are_drawn(box):
    count = len(stable_rests(box))
    assert count > MAX_PANELS, "the box should rest in more ways than are drawn"
    grasps = [rest_grasp(box, k) for k in reversed(range(count))]  # grouped by rest whatever their order
    rests = grasps_by_rest(box, grasps)
    assert [r.rest for r in rests] == list(range(count))
    for rest in rests:  # each rest turns its grasp's approach straight down
        assert np.allclose(rest.T_table_model[:3, :3] @ rest.grasps[0].approach, (0, 0, -1))


def test_a_bad_folder_or_input_is_a_clear_error(box, tmp_path):
    (tmp_path / "file").write_text("")
    with pytest.raises(RecordingError, match=r"file.*is a file; give a folder"):
        save_grasp_picture(tmp_path / "file" / "box.png", "box", box, [rest_grasp(box, 0)])
    with pytest.raises(SimInputError, match="Grasp objects, got dict"):
        save_grasp_picture(tmp_path / "box.png", "box", box, [{"name": "rest0_synth_0"}])
    with pytest.raises(SimInputError, match="trimesh.Trimesh"):
        save_grasp_picture(tmp_path / "box.png", "box", "box.stl", [])
