"""Settings objects refuse bad fields with an InvalidInputError that names the field, at construction:
never a numpy traceback later, never a value quietly cut or coerced."""

import dataclasses
import re

import numpy as np
import pytest
import trimesh

from psorr.acceptance.continuation import ContinuationParams
from psorr.acceptance.params import AcceptParams
from psorr.decomposition import DecomposeParams, decompose
from psorr.decomposition.detail import DetailParams
from psorr.decomposition.support_crop import SupportCropParams
from psorr.errors import InvalidInputError
from psorr.hypotheses.orr import OrrParams
from psorr.hypotheses.pairs import PairParams
from psorr.hypotheses.single_cylinder import SingleCylinderParams
from psorr.hypotheses.single_plane import SinglePlaneParams
from psorr.library.models import ModelLibrary, TrainParams
from psorr.recognize import RecognizeParams, Recognizer
from psorr.synthetic import primitive_scenes as synthetic
from psorr.types import Method
from psorr.verification.point_check import CheckParams

NAN = float("nan")
CLASSES = [DecomposeParams, RecognizeParams, TrainParams, ContinuationParams, CheckParams, SinglePlaneParams,
           SingleCylinderParams, SupportCropParams, AcceptParams, PairParams, OrrParams, DetailParams]

REPORTED = [
    (PairParams, "max_hypotheses", NAN),
    (AcceptParams, "min_support_above_table", NAN),
    (AcceptParams, "icp_distance", "0.01"),
    (RecognizeParams, "decompose", "x"),
    (RecognizeParams, "acceptance", {"icp_distance": 0.01}),
    (DecomposeParams, "k_neighbours", NAN),
    (DecomposeParams, "voxel_size", "0.01"),
    (DecomposeParams, "cylinder_radius_range", (0.1,)),
    (DecomposeParams, "ransac_sample", 1.5),
    (DecomposeParams, "k_neighbours", "8"),
    (DecomposeParams, "k_neighbours", 2.5),
    (DecomposeParams, "min_points", 2.5),
    (DecomposeParams, "smoothness", NAN),
    (DecomposeParams, "mdl_k", NAN),
    (DecomposeParams, "sensor_noise", "no"),
    (TrainParams, "seed", -1),
    (TrainParams, "pair_points", NAN),
]


@pytest.mark.parametrize("cls, name, value", REPORTED, ids=lambda v: repr(v) if not isinstance(v, type) else None)
def test_reported_bad_fields_name_the_field(cls, name, value):
    with pytest.raises(InvalidInputError, match=re.escape(f"{cls.__name__}.{name} must")):
        cls(**{name: value})


def _default(f: dataclasses.Field):
    return f.default_factory() if f.default is dataclasses.MISSING else f.default


def _bad_values(f: dataclasses.Field) -> list:
    """Values the field must refuse, by the kind its default and annotation give it."""
    default = _default(f)
    if isinstance(default, bool):
        return ["no", 1, None]
    if isinstance(default, int):
        return [NAN, 2.5, float(default), "8", True, None]
    if isinstance(default, float) or default is None:
        bad = [NAN, float("inf"), -float("inf"), "0.01", True, [0.01]]
        return bad if "None" in f.type else [*bad, None]
    if isinstance(default, tuple):
        return [(0.1,), (0.1, 0.2, 0.3), ("0.1", 0.2), (NAN, 0.2), 0.1, None]
    return [{}, "x", None]  # a nested settings object


CASES = [pytest.param(cls, f.name, bad, id=f"{cls.__name__}.{f.name}={bad!r}")
         for cls in CLASSES for f in dataclasses.fields(cls) for bad in _bad_values(f)]


@pytest.mark.parametrize("cls, name, bad", CASES)
def test_every_field_refuses_the_wrong_kind_of_value(cls, name, bad):
    with pytest.raises(InvalidInputError, match=re.escape(f"{cls.__name__}.{name} must")):
        cls(**{name: bad})


@pytest.mark.parametrize("cls", CLASSES)
def test_defaults_pass_and_numpy_numbers_are_kept_as_given(cls):
    cls()
    for f in dataclasses.fields(cls):
        default = _default(f)
        if isinstance(default, bool) or not isinstance(default, int | float):
            continue
        given = np.int64(default) if isinstance(default, int) else np.float32(default)
        assert getattr(cls(**{f.name: given}), f.name) is given


def test_optional_fields_take_none_and_turned_off_checks_take_zero():
    assert DetailParams(leftover_voxel=None, fine_voxel=None).fine_voxel is None
    p = AcceptParams(max_float=None, max_continued=None, min_support_above_table=0)
    assert p.max_float is None and p.min_support_above_table == 0
    stacked = RecognizeParams().for_stacked_parts().acceptance
    assert stacked.max_float is None and stacked.max_continued is None and stacked.max_shared_pixels == 0.3
    assert DecomposeParams(cylinder_radius_range=[0.01, 0.1]).cylinder_radius_range == [0.01, 0.1]


def test_range_errors_keep_their_wording():
    with pytest.raises(InvalidInputError, match=r"AcceptParams.icp_distance must be > 0 metres, got 0"):
        AcceptParams(icp_distance=0)
    with pytest.raises(InvalidInputError, match=r"min_support_above_table must be >= 0 \(0 turns it off\)"):
        AcceptParams(min_support_above_table=NAN)
    with pytest.raises(InvalidInputError, match=r"k_neighbours must be >= 1 and a whole number \(an int\), got 2.5"):
        DecomposeParams(k_neighbours=2.5)
    with pytest.raises(InvalidInputError, match=r"cylinder_radius_range must be \(min, max\) with 0 < min < max"):
        DecomposeParams(cylinder_radius_range=(0.2, 0.1))
    with pytest.raises(InvalidInputError, match=r"min_side_ratio must be <= max_side_ratio"):
        SinglePlaneParams(min_side_ratio=1.2, max_side_ratio=1.1)


@pytest.mark.parametrize("bad", ["fast", {"voxel_size": 0.01}, {}, ""])
def test_decompose_takes_only_decompose_params(bad):
    cloud = synthetic.box_on_table(np.random.default_rng(0)).cloud
    with pytest.raises(InvalidInputError, match=r"decompose\(\)'s params must be a DecomposeParams \(pass "):
        decompose(cloud, bad)


@pytest.mark.parametrize("bad", ["lib.npz", ["a.stl"], None])
def test_a_recognizer_needs_a_model_library_and_says_how_to_get_one(bad):
    expected = r"library must be a ModelLibrary.*ModelLibrary.load\(path\).*from_meshes"
    with pytest.raises(InvalidInputError, match=expected):
        Recognizer(bad)


@pytest.fixture(scope="module")
def block_library(tmp_path_factory):
    folder = tmp_path_factory.mktemp("block")
    trimesh.creation.box(extents=(0.1, 0.06, 0.04)).export(folder / "block.stl")
    return ModelLibrary.from_meshes([folder / "block.stl"], use_cache=False)


@pytest.mark.parametrize("bad", [{"pairs": {"refine_top": 4}}, {}, "fast", DecomposeParams(), PairParams()])
def test_a_recognizer_takes_only_recognize_params(block_library, bad):
    with pytest.raises(InvalidInputError, match=r"params must be a RecognizeParams.*RecognizeParams\(acceptance="):
        Recognizer(block_library, params=bad)
    params = RecognizeParams(pairs=PairParams(refine_top=4))
    assert Recognizer(block_library, params=params).pairs.params.refine_top == 4


@pytest.mark.parametrize("method", ["psorr", "psg", "orr", "auto", Method.PSORR, Method.PSG, Method.ORR, Method.AUTO])
def test_a_recognizer_takes_a_method_by_name_or_enum(block_library, method):
    assert Recognizer(block_library, method=method).method is Method(method)


@pytest.mark.parametrize("bad", ["PSORR ", "ppf", None, 1])
def test_an_unknown_method_names_the_valid_ones(block_library, bad):
    with pytest.raises(InvalidInputError, match=r"unknown method .*choose one of \['psorr', 'psg', 'orr', 'auto'\]"):
        Recognizer(block_library, method=bad)


@pytest.mark.parametrize("kwargs, field", [({"angle_step_deg": "12"}, "angle_step_deg"),
                                           ({"angle_step_deg": 0}, "angle_step_deg"),
                                           ({"angle_step_deg": 91}, "angle_step_deg"),
                                           ({"distance_tolerance": float("nan")}, "distance_tolerance"),
                                           ({"nearest_neighbour_bins": 1}, "nearest_neighbour_bins")])
def test_hash_settings_name_the_field(kwargs, field):
    from psorr.library.ppf import HashParams

    with pytest.raises(InvalidInputError, match=f"HashParams.{field}"):
        HashParams(**kwargs)
    assert HashParams(angle_step_deg=90).n_bins == 2


def test_settings_holding_numpy_numbers_save_and_load(tmp_path, monkeypatch):
    monkeypatch.setenv("PSORR_CACHE", str(tmp_path / "cache"))
    trimesh.creation.box(extents=(0.1, 0.06, 0.04)).export(tmp_path / "block.stl")
    lib = ModelLibrary.from_meshes([tmp_path / "block.stl"], params=TrainParams(pair_points=np.int64(4)))
    assert ModelLibrary.load(lib.save(tmp_path / "lib.npz")).params.pair_points == 4
