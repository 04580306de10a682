"""benchmarks/probe_parts.py: the generated folders the generalization page reports on build as closed solids, and
the script writes them where the benchmark's --cad reads them."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from paths import BENCHMARKS

from psorr.synthetic.mesh_scenes import load_meshes

sys.path.insert(0, str(BENCHMARKS))
import probe_parts  # noqa: E402

pytest.importorskip("manifold3d", reason="the probe sets' booleans need manifold3d")


@pytest.mark.parametrize("name", sorted(probe_parts.SETS))
def test_every_part_of_a_probe_set_is_a_closed_solid_of_its_sets_size(name):
    parts = probe_parts.SETS[name]()
    assert len(parts) >= 6
    for part, mesh in parts.items():
        assert mesh.is_watertight and mesh.volume > 0, part
        # The sets are millimetres, one centimetres: parts of 12 to 160 mm either way.
        longest = float(np.max(mesh.extents)) * (10 if name == "centimetres" else 1)
        assert 12 <= longest <= 160, (part, longest)


def test_the_script_writes_a_set_the_benchmark_reads_in_its_units(tmp_path):
    assert probe_parts.main([str(tmp_path), "--set", "centimetres", "--set", "flat_plates"]) == 0
    plates = load_meshes(tmp_path / "flat_plates", "mm")
    assert len(plates) == 10 and max(np.max(m.extents) for m in plates.values()) < 0.1
    parts = load_meshes(tmp_path / "centimetres", "cm")
    assert {p.suffix for p in (tmp_path / "centimetres").iterdir()} == {".obj", ".ply", ".stl"}
    assert 0.05 < max(np.max(m.extents) for m in parts.values()) < 0.1


def test_small_fittings_need_the_floor_lowered_and_are_sized_under_25_mm(tmp_path):
    import generalization_parts as parts

    probe_parts.write_set("small_fittings", tmp_path)
    meshes = load_meshes(tmp_path, "mm")
    with pytest.raises(parts.SplitError, match="--min-length"):
        parts.checked_split(meshes, tmp_path)
    kept, short = parts.checked_split(meshes, tmp_path, min_length=0.01)
    assert len(kept) == 6 and short == []
    assert {parts.size_bin(m) for m in kept.values()} == {"under 25 mm"}
