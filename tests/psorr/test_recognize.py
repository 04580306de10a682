"""Recognition on seeded ray-cast Kinect scenes of the catalog workpieces,
scored by the symmetry-aware ADD (correct under 0.1 x the model diameter).

The recall tests assert the issue's correctness bar: single parts are
recognised, and clutter recall is at least 0.8 with at most one false
positive per scene. The benchmark's harder set, with an occluder, is in
benchmarks/peers.py.
"""

import json
import subprocess
import sys

import numpy as np
import pytest

from psorr import AcceptParams, DetailParams, OutlineParams, PairParams
from psorr.errors import InvalidInputError
from psorr.io.clouds import write_cloud
from psorr.recognize import RecognizeParams, Recognizer
from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.workpiece_scenes import workpiece_scene
from psorr.types import PointCloud
from psorr.verification.scene_view import SceneView


@pytest.fixture(scope="module")
def catalog():
    return load_catalog()


def _accepting(**settings) -> RecognizeParams:
    """The default settings but these of acceptance's."""
    return RecognizeParams(acceptance=AcceptParams(**settings))


def _matches(det, instance, library, catalog) -> bool:
    """Is ``det`` the scene's ``instance``: the same model, within a symmetric ADD of 0.1 x its diameter?"""
    if det.model != instance.name:
        return False
    model = library.model(det.model)
    return symmetric_add(model.points[::10], det.T_cloud_model, instance.T_camera_model,
                         catalog[instance.name]) < 0.1 * model.diameter


def _occluded_clutter(catalog, seed):
    """The peers benchmark's cluttered scene of ``seed``: four parts the seed draws, and the occluder."""
    names = list(np.random.default_rng(seed).choice(sorted(catalog), size=4, replace=False))
    return workpiece_scene(np.random.default_rng(1000 + seed), {n: catalog[n].load_mesh() for n in names}, names,
                           occluder=True)


def _score(scene, detections, library, catalog):
    """(instances found, false positives)."""
    found, false = set(), 0
    for det in detections:
        hits = [k for k, inst in enumerate(scene.instances) if _matches(det, inst, library, catalog)]
        if hits:
            found.add(hits[0])
        else:
            false += 1
    return len(found), false


def test_single_parts_are_recognised(library, catalog):
    # Three seeded scenes per catalog part, the flat circuit board and the small bushing included. A small
    # part's few faces make its decomposition, and so its recognition, hinge on the random draws: over these
    # 24 scenes x 5 recognizer seeds, 118 of 120 succeed (0.98; 110 without the finer second look). 24
    # scenes, not 16, so one unlucky draw does not decide the test.
    found = false = total = 0
    for k, name in enumerate(sorted(catalog)):
        for s in range(3):
            scene = workpiece_scene(np.random.default_rng(2000 + 10 * k + s), {name: catalog[name].load_mesh()}, [name])
            result = Recognizer(library).recognize(scene.cloud)
            f, fp = _score(scene, result.detections, library, catalog)
            found, false, total = found + f, false + fp, total + 1
            for det in result.detections:
                assert 0 < det.score <= 1 and 0 < det.visible_fraction <= 1
            # Per search (the first, and the finer second look), pair clusters each round plus poses from
            # single faces and cylinders left unexplained.
            params = RecognizeParams()
            per_search = (params.pairs.pair_rounds * params.pairs.max_hypotheses + params.single_plane.max_poses
                          + params.single_cylinder.max_poses)
            assert result.stats.hypotheses <= 2 * per_search
    assert found >= 0.95 * total, f"single-part recall {found}/{total}"
    assert false <= 2, f"{false} false positives in {total} single-part scenes"


def test_clutter_recall_and_false_positives(library, catalog):
    # Seeded 4-part scenes without an occluder.
    names_all = sorted(catalog)
    found = total = 0
    for seed in range(6):
        names = list(np.random.default_rng(seed).choice(names_all, size=4, replace=False))
        scene = workpiece_scene(np.random.default_rng(1000 + seed), {n: catalog[n].load_mesh() for n in names}, names)
        f, fp = _score(scene, Recognizer(library).recognize(scene.cloud).detections, library, catalog)
        found, total = found + f, total + len(names)
        assert fp <= 1, f"{fp} false positives in the scene of seed {seed}"
    assert found / total >= 0.8, f"clutter recall {found}/{total}"


def test_a_second_pairing_round_finds_a_part_the_first_crowded_out(library, catalog):
    # Seed 1003 with the occluder (the peers benchmark's 4th cluttered scene): the bushing's few pair
    # votes lose to pairs across the other parts until those parts are explained and leave the pairing.
    # Without the finer second look and the resting-pose search, which find it after one round too (the
    # search since the arm's points no longer join the bushing's patch).
    scene = _occluded_clutter(catalog, 3)
    bushing = next(inst for inst in scene.instances if inst.name == "bushing")

    def bushing_found(rounds):
        params = RecognizeParams(pairs=PairParams(pair_rounds=rounds), detail=DetailParams(fine_voxel=None),
                                 outline=OutlineParams(enabled=False))
        result = Recognizer(library, params=params).recognize(scene.cloud)
        return result, any(_matches(d, bushing, library, catalog) for d in result.detections)

    one, found_in_one = bushing_found(1)
    two, found_in_two = bushing_found(2)
    assert not found_in_one and found_in_two
    assert {d.model for d in one.detections} <= {d.model for d in two.detections}
    assert two.stats.hypotheses > one.stats.hypotheses


def test_a_part_mostly_hidden_behind_others_is_judged_by_what_could_be_seen(library, catalog):
    # Seed 1006 with the occluder (the peers benchmark's 7th cluttered scene): the chassis shows less than
    # 0.35 of its sensor-facing surface, as the capsule and a part in front hide much of the rest. Of what
    # they leave in view, most is measured, and that is what accepts it.
    scene = _occluded_clutter(catalog, 6)
    chassis = next(inst for inst in scene.instances if inst.name == "chassis")

    def chassis_found(params):
        return [d for d in Recognizer(library, params=params).recognize(scene.cloud).detections
                if _matches(d, chassis, library, catalog)]

    assert not chassis_found(RecognizeParams(acceptance=AcceptParams(min_unblocked_fraction=1.0)))
    found = chassis_found(RecognizeParams())
    assert len(found) == 1 and found[0].visible_fraction < AcceptParams().min_visible_fraction


def test_partly_hidden_parts_of_the_occluded_benchmark_scenes_are_found(library, catalog):
    # Three of the peers benchmark's misses, each for its own reason:
    # - the chassis of seed 2 shows 0.18 of its sensor-facing surface, and most of the rest lies in the arm's
    #   projector shadow: unmeasured, it counted against the part until shadows counted as hidden;
    # - the U-channel of seed 3, two thirds hidden, got pair poses 4 cm off along its length, where neither
    #   ICP nor the resolver's slide reaches: candidates of a sliding part are now also fitted slid onto the data;
    # - the pipe tee of seed 4 shows its run but not its branch, and Open3D's ICP rolled it away.
    for seed, name in ((2, "chassis"), (3, "u_channel"), (4, "pipe_tee")):
        scene = _occluded_clutter(catalog, seed)
        part = next(inst for inst in scene.instances if inst.name == name)
        detections = Recognizer(library).recognize(scene.cloud).detections
        assert any(_matches(d, part, library, catalog) for d in detections), (seed, name)
        assert _score(scene, detections, library, catalog)[1] == 0, (seed, "false positive")


def test_a_channel_is_fitted_from_its_pair_pose_as_well_as_from_where_the_slide_puts_it(library, catalog):
    # Seed 13 of the wider clutter set: the U-channel's pair poses started 1-13 mm off, some tilted. Judged
    # from a tilted start, the slide went 2-5 cm along the channel, the wrong way, and no fit from there
    # passed; the plain fits from the same starts came within 0.6 mm. The slide is now a second start,
    # and the coarse point check keeps the better fit.
    scene = _occluded_clutter(catalog, 13)
    channel = next(inst for inst in scene.instances if inst.name == "u_channel")
    detections = Recognizer(library).recognize(scene.cloud).detections
    assert any(_matches(d, channel, library, catalog) for d in detections)
    assert _score(scene, detections, library, catalog)[1] == 0


def test_what_stands_unexplained_gets_a_finer_second_look(library, catalog):
    # The peers benchmark's bushing scene of seed 0: at 8 mm voxels the 54 mm bushing's faces come out
    # as a cylinder of the wrong radius and planes merged with the table, and no pair of them matches.
    # Its points stand on the table unexplained; decomposed again at 5 mm, they give the bushing. (The
    # resting-pose search finds it too, so it is off here, where the second look is what is tested.)
    names = sorted(catalog)
    scene = workpiece_scene(np.random.default_rng(2000 + 10 * names.index("bushing")),
                            {"bushing": catalog["bushing"].load_mesh()}, ["bushing"])

    def found(params):
        result = Recognizer(library, params=params).recognize(scene.cloud)
        return result, [d for d in result.detections if _matches(d, scene.instances[0], library, catalog)]

    no_rests = OutlineParams(enabled=False)
    coarse_only, missed = found(RecognizeParams(detail=DetailParams(fine_voxel=None), outline=no_rests))
    both, hit = found(RecognizeParams(outline=no_rests))
    assert not missed and len(hit) == 1 and len(both.detections) == 1
    assert both.stats.hypotheses > coarse_only.stats.hypotheses


def test_a_part_floating_on_the_arm_is_not_taken(library, catalog):
    # Seed 1004 with the occluder (the peers benchmark's 5th cluttered scene): an L bracket's plates fit
    # the arm-sized capsule within the depth tolerance, 13 cm above the table. Parts rest on the table.
    scene = _occluded_clutter(catalog, 4)
    plane = SceneView(scene.cloud).support_plane

    def lowest(d):
        T = d.T_cloud_model
        return float(((library.model(d.model).points @ T[:3, :3].T + T[:3, 3]) @ plane[:3] + plane[3]).min())

    # The continuation check drops this bracket too (the capsule goes on past its plates); it is off here
    # so that the float limit is tested alone, and on alone below.
    anywhere = Recognizer(library, params=RecognizeParams().for_stacked_parts()).recognize(scene.cloud)
    resting = Recognizer(library, params=_accepting(max_continued=None)).recognize(scene.cloud)
    assert any(lowest(d) > 0.1 for d in anywhere.detections)
    assert resting.detections and all(lowest(d) <= AcceptParams().max_float for d in resting.detections)
    f_any, fp_any = _score(scene, anywhere.detections, library, catalog)
    f_rest, fp_rest = _score(scene, resting.detections, library, catalog)
    assert f_rest >= f_any and fp_rest < fp_any
    continued = Recognizer(library, params=_accepting(max_float=None)).recognize(scene.cloud).detections
    assert not any(lowest(d) > 0.1 for d in continued)


@pytest.mark.parametrize("method", ["psorr", "orr"])
def test_empty_table_gives_no_detection(library, catalog, method):
    # Seed 0's table decomposes into the table alone: no primitive is left to pair (it used to crash).
    for seed in (0, 9):
        scene = workpiece_scene(np.random.default_rng(seed), {}, [])
        result = Recognizer(library, method).recognize(scene.cloud, np.random.default_rng(0))
        assert result.detections == ()
        # Screening no hypothesis costs nothing per hypothesis (its empty batch once came out as 0.06 ms each).
        assert result.stats.hypotheses > 0 or result.stats.verify_ms_per_hypothesis == 0.0


@pytest.mark.parametrize("method", ["psorr", "orr"])
def test_a_handful_of_points_gives_no_detection(library, method):
    # PSORR cropped all but 4 of these as table and then refused to decompose "a cloud of 4 points".
    points = np.random.default_rng(0).uniform(-0.1, 0.1, (10, 3)) + [0, 0, 1]
    assert Recognizer(library, method).recognize(PointCloud(points), np.random.default_rng(0)).detections == ()
    # Many points in five clumps fill five voxels: PSORR refused them with "use a smaller voxel_size", an
    # option recognize() does not have.
    rng = np.random.default_rng(1)
    clumps = np.repeat(rng.uniform(-0.1, 0.1, (5, 3)) + [0, 0, 1], 100, axis=0) + rng.normal(0, 1e-4, (500, 3))
    assert Recognizer(library, method).recognize(PointCloud(clumps), np.random.default_rng(0)).detections == ()


@pytest.mark.parametrize("method", ["psorr", "orr"])
def test_a_frame_with_no_measurement_gives_no_detection(library, method):
    # The person's arm over the lens: every pixel NaN. It failed inside numpy building the depth buffer.
    blind = PointCloud(np.full((480 * 640, 3), np.nan), width=640, height=480)
    result = Recognizer(library, method).recognize(blind, np.random.default_rng(0))
    assert result.detections == () and result.stats.hypotheses == 0


def test_a_cloud_in_millimetres_is_refused(library):
    scene = workpiece_scene(np.random.default_rng(0), {}, [])
    with pytest.raises(InvalidInputError, match=r"recognize\(\): the cloud: .* in metres"):
        Recognizer(library).recognize(PointCloud(scene.cloud.points * 1000.0))


def test_unknown_method_names_the_choices(library):
    with pytest.raises(InvalidInputError, match="psorr"):
        Recognizer(library, method="ransac")


def test_cli_prints_the_json_contract(tmp_path, library, catalog):
    names = ["transformer"]
    scene = workpiece_scene(np.random.default_rng(2), {n: catalog[n].load_mesh() for n in names}, names)
    cloud = tmp_path / "scene.pcd"
    write_cloud(cloud, scene.cloud, compressed=True)
    lib_file = library.save(tmp_path / "library.npz")
    out = subprocess.run([sys.executable, "-m", "psorr.cli", "recognize", str(lib_file), str(cloud), "--json",
                          "--png", str(tmp_path / "overlay.png")], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    assert len(lines) == 1
    record = json.loads(lines[0])
    assert set(record) == {"detections", "stats"}
    assert set(record["stats"]) == {"method", "hypotheses", "verify_ms_per_hypothesis", "total_ms", "train_ms"}
    assert record["stats"]["method"] == "psorr"
    det = record["detections"][0]
    assert set(det) == {"model", "pose", "score"} and det["model"] == "transformer"
    pose = np.array(det["pose"])
    assert pose.shape == (4, 4)
    assert symmetric_add(library.model("transformer").points[::10], pose, scene.instances[0].T_camera_model,
                         catalog["transformer"]) < 0.1 * library.model("transformer").diameter
    assert (tmp_path / "overlay.png").exists()


def test_recognize_wants_a_generator_not_a_seed(library):
    scene = workpiece_scene(np.random.default_rng(9), {}, [])
    with pytest.raises(InvalidInputError, match=r"recognize\(\) takes rng=np.random.default_rng"):
        Recognizer(library).recognize(scene.cloud, 0)


def test_the_same_cloud_gives_the_same_poses_to_the_last_bit(library, catalog):
    """A seed must reproduce an episode bit for bit, and everything after a pose depends on its last bits."""
    meshes = {n: catalog[n].load_mesh() for n in ("chassis", "transformer")}
    scene = workpiece_scene(np.random.default_rng(5), meshes, ["chassis", "transformer"])
    runs = [Recognizer(library).recognize(scene.cloud, np.random.default_rng(0)).detections for _ in range(3)]
    assert runs[0]
    for other in runs[1:]:
        assert [d.model for d in other] == [d.model for d in runs[0]]
        for a, b in zip(runs[0], other):
            assert np.array_equal(a.T_cloud_model, b.T_cloud_model)


def _counting_decompositions(monkeypatch) -> list:
    """Each call of the scene decomposition recognize() makes, recorded (as its cropped cloud's size)."""
    import psorr.recognize as recognize

    calls, decompose = [], recognize.decompose_with_leftovers

    def counted(cloud, *args, **kwargs):
        calls.append(int(cloud.valid_mask.sum()))
        return decompose(cloud, *args, **kwargs)

    monkeypatch.setattr(recognize, "decompose_with_leftovers", counted)
    return calls


def test_a_lone_part_at_rest_is_found_without_decomposing_the_scene(library, catalog, monkeypatch):
    # Its resting pose explains every point standing on the table, with no twin pose left open: the pairs
    # would have nothing left to look at.
    names = sorted(catalog)
    calls = _counting_decompositions(monkeypatch)
    for name in ("bushing", "pipe_tee", "transformer"):
        scene = workpiece_scene(np.random.default_rng(2000 + 10 * names.index(name)), {name: catalog[name].load_mesh()},
                                [name])
        detections = Recognizer(library).recognize(scene.cloud).detections
        assert _score(scene, detections, library, catalog) == (1, 0)
    assert calls == []


def test_what_no_part_at_rest_explains_is_decomposed_and_paired(library, catalog, monkeypatch):
    # The occluded clutter scene of seed 1003: the resting poses do not explain every standing point, so the
    # scene is decomposed and paired as a whole, and all four parts are found.
    calls = _counting_decompositions(monkeypatch)
    scene = _occluded_clutter(catalog, 3)
    detections = Recognizer(library).recognize(scene.cloud).detections
    assert calls
    found, false = _score(scene, detections, library, catalog)
    assert found == len(scene.instances) and false == 0
