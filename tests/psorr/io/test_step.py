"""Tests for STEP files (psorr.io.step): the unit a file declares, the tessellated mesh in that unit, the unit a
user gives checked against it, and a part trained from STEP found in a scene.

The fixtures in data/ are one bracket (a 60 x 40 x 5 mm base, a 30 mm wall, two 6 mm holes and a 10 mm bore)
written by build123d 0.13 (``export_step``), as is edge_mm.step (a 10 mm line); bracket_in.step is the same
bracket in inches, its length unit entity rewritten as a conversion-based INCH unit."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from psorr.errors import CloudFileError, MissingExtraError
from psorr.io.step import declared_units

DATA = Path(__file__).parent / "data"
BRACKET_MM, BRACKET_IN = DATA / "bracket_mm.step", DATA / "bracket_in.step"
BRACKET_VOLUME_MM3 = 20324.56  # build123d's exact volume of the solid


def _cascadio():
    pytest.importorskip("cascadio", reason="the step extra (pip install 'psorr[step]') is not installed")


def _context(refs: str) -> str:
    return (f"#1 = ( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNIT_ASSIGNED_CONTEXT\n(({refs})) "
            "REPRESENTATION_CONTEXT('Context #1','3D Context') );\n")


def _step_text(units_entity: str, contexts: str = _context("#10")) -> str:
    """A STEP file's text reduced to what declares its length unit."""
    return f"ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n{contexts}{units_entity}\nENDSEC;\nEND-ISO-10303-21;\n"


@pytest.mark.parametrize(("entity", "units"), [
    ("#10 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );", "mm"),
    ("#10 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.CENTI.,.METRE.) );", "cm"),
    ("#10 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT($,.METRE.) );", "m"),
    ("#10 = ( CONVERSION_BASED_UNIT('INCH',#11) LENGTH_UNIT() NAMED_UNIT(#12) );\n"
     "#11 = LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#13);", "in"),
])
def test_declared_units(tmp_path, entity, units):
    path = tmp_path / "part.stp"
    path.write_text(_step_text(entity))
    assert declared_units(path) == units


def test_the_fixtures_declare_their_units(tmp_path):
    assert declared_units(BRACKET_MM) == "mm"
    assert declared_units(BRACKET_IN) == "in"
    (tmp_path / "part.stl").write_bytes(b"solid part\nendsolid part\n")
    assert declared_units(tmp_path / "part.stl") is None  # another format's unit only its user knows


@pytest.mark.parametrize(("entity", "fragment"), [
    ("#10 = ( CONVERSION_BASED_UNIT('FOOT',#11) LENGTH_UNIT() NAMED_UNIT(#12) );", "'foot'"),
    ("#10 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MICRO.,.METRE.) );", "does not read"),
    ("#10 = ( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) );", "no length unit"),
])
def test_units_psorr_cannot_read_are_refused(tmp_path, entity, fragment):
    path = tmp_path / "part.step"
    path.write_text(_step_text(entity))
    with pytest.raises(CloudFileError, match=fragment) as caught:
        declared_units(path)
    assert "part.step" in str(caught.value) and "re-export" in str(caught.value)


def test_two_units_in_one_file_are_refused(tmp_path):
    path = tmp_path / "assembly.step"
    path.write_text(_step_text("#10 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );\n"
                               "#20 = ( CONVERSION_BASED_UNIT('INCH',#11) LENGTH_UNIT() NAMED_UNIT(#12) );",
                               _context("#10") + _context("#20").replace("#1 =", "#2 =")))
    with pytest.raises(CloudFileError, match=r"several units \(in, mm\)"):
        declared_units(path)


def test_a_step_mesh_is_closed_and_in_its_declared_unit():
    _cascadio()
    from psorr.io.meshes import read_mesh

    in_mm, in_inches = read_mesh(BRACKET_MM), read_mesh(BRACKET_IN)
    np.testing.assert_allclose(in_mm.extents, [60.0, 40.0, 35.0], atol=1e-4)
    np.testing.assert_allclose(in_inches.extents * 25.4, [60.0, 40.0, 35.0], atol=1e-4)
    for mesh, mm3 in ((in_mm, 1.0), (in_inches, 25.4**3)):
        assert mesh.is_watertight  # each B-rep face's vertices merged with its neighbours'
        assert mesh.volume * mm3 == pytest.approx(BRACKET_VOLUME_MM3, rel=1e-3)  # tessellated to 0.01 mm


def test_units_given_must_agree_with_the_file():
    _cascadio()
    from psorr.library.models import load_mesh_in_metres

    np.testing.assert_allclose(load_mesh_in_metres(BRACKET_MM).extents, [0.06, 0.04, 0.035], atol=1e-7)
    np.testing.assert_allclose(load_mesh_in_metres(BRACKET_IN, "in").extents, [0.06, 0.04, 0.035], atol=1e-7)
    with pytest.raises(CloudFileError, match="declares its lengths in mm, but units 'in' were given") as caught:
        load_mesh_in_metres(BRACKET_MM, "in")
    assert "bracket_mm.step" in str(caught.value)


def test_without_cascadio_the_error_names_the_extra(monkeypatch):
    from psorr.io.meshes import read_mesh

    monkeypatch.setitem(sys.modules, "cascadio", None)  # import cascadio now raises ImportError
    with pytest.raises(MissingExtraError, match=r"pip install 'psorr\[step\]'") as caught:
        read_mesh(BRACKET_MM)
    assert "bracket_mm.step" in str(caught.value)


def test_a_part_trained_from_step_is_found():
    _cascadio()
    from psorr.library.models import ModelLibrary, load_mesh_in_metres
    from psorr.recognize import Recognizer
    from psorr.synthetic.mesh_scenes import SceneKind, mesh_scene

    library = ModelLibrary.from_meshes([BRACKET_IN], use_cache=False)
    assert library.models[0].name == "bracket_in"
    meshes = {"bracket_in": load_mesh_in_metres(BRACKET_MM)}  # the same bracket, from the millimetre file
    for seed in (0, 1):
        scene = mesh_scene(np.random.default_rng(seed), meshes, SceneKind.SINGLE)
        found = Recognizer(library).recognize(scene.cloud, np.random.default_rng(0)).detections
        truth = scene.instances[0].T_camera_model
        assert [d.model for d in found] == ["bracket_in"]
        assert np.linalg.norm(found[0].T_cloud_model[:3, 3] - truth[:3, 3]) < 0.004


def test_a_step_file_of_an_edge_only_is_refused_with_the_fix():
    _cascadio()
    from psorr.io.meshes import read_mesh

    with pytest.raises(CloudFileError, match="edge_mm.step: holds no faces.*export the part's solid"):
        read_mesh(DATA / "edge_mm.step")  # a 10 mm line, written by build123d


def test_a_step_file_of_no_shape_is_refused_with_the_fix(tmp_path):
    _cascadio()
    from psorr.io.meshes import read_mesh

    # The bracket's file cut down to its units: OpenCASCADE finds nothing to tessellate and writes no file.
    header, data = BRACKET_MM.read_text().split("DATA;", 1)
    units = [e for e in data.split(";") if "GLOBAL_UNIT_ASSIGNED_CONTEXT" in e or "LENGTH_UNIT" in e]
    path = tmp_path / "units_only.step"
    path.write_text(header + "DATA;" + ";".join(units) + ";\nENDSEC;\nEND-ISO-10303-21;\n")
    with pytest.raises(CloudFileError, match="units_only.step: OpenCASCADE found no shape.*re-export") as caught:
        read_mesh(path)
    assert "converted.glb" not in str(caught.value)  # no temporary file of trimesh's named
