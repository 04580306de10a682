"""The installable package: the wheel, installed into a fresh venv outside the checkout, runs `psorr` and
`psorr-sim` from a folder that is not the repository, with the assets it ships.

How, and the trade-off:
- The wheel is built from a copy of the working tree (so no stale build/ folder leaks into it and nothing is
  written into the checkout), with the dev extra's setuptools and no build isolation: no network.
- It is installed with ``--no-deps`` into a venv made in a temporary folder. psorr's dependencies (open3d,
  mujoco, ...: several GB) are not downloaded again: a ``.pth`` file in the venv appends the test
  interpreter's site-packages to ``sys.path`` as plain path lines. A plain line does not run the ``.pth``
  files inside that folder, so the editable install's finder, which maps psorr to the checkout, stays out;
  the first test checks that psorr, psorr.assets and sim import from the venv's own copy.
- So this checks what the wheel holds (modules, package data, entry points) and that it runs on its own,
  not that pip can resolve the dependency list from the registry: ``make setup`` does that on every fresh
  machine.

About 40 s on 2 cores: the wheel and the venv ~6 s, importing from the venv ~3 s, training 8 models and
recognising ~11 s, the simulated cell's perception ~17 s. Marked ``wheel``: ``make test`` runs it,
``-m "not wheel"`` leaves it out of a quick run.
"""

from __future__ import annotations

import fnmatch
import json
import os
import shutil
import site
import subprocess
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from paths import REPO

from psorr.io.clouds import write_cloud
from psorr.synthetic.catalog import load_catalog
from psorr.synthetic.workpiece_scenes import workpiece_scene

pytestmark = pytest.mark.wheel

# Files of assets/ that stay in the checkout: the scripts that build the rest, and the catalog's preview picture.
NOT_SHIPPED = ("__init__.py", "workpieces/*.py", "workpieces/workpieces.png")
# Neither the build's leftovers nor the checkout's tools and outputs belong in the copy the wheel is built from.
NOT_COPIED = shutil.ignore_patterns(".git", ".venv", "build", "dist", "*.egg-info", "__pycache__", ".*_cache",
                                    ".hypothesis", "out", "site")
SCENE_PARTS = ["chassis", "flanged_hub", "u_channel"]


@dataclass(frozen=True)
class Installed:
    """The wheel, the venv it is installed in, and an empty working folder outside the checkout."""

    wheel: Path
    bin: Path
    site_packages: Path
    work: Path
    env: dict

    def run(self, *args: str, timeout: float = 300) -> subprocess.CompletedProcess:
        out = subprocess.run(args, cwd=self.work, env=self.env, capture_output=True, text=True, timeout=timeout)
        assert out.returncode == 0, f"{' '.join(args)} failed:\n{out.stderr[-3000:]}"
        return out


def _call(*args) -> str:
    out = subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, f"{' '.join(map(str, args))} failed:\n{out.stdout[-2000:]}\n{out.stderr[-3000:]}"
    return out.stdout


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Installed:
    tmp = tmp_path_factory.mktemp("wheel")
    source = tmp / "source"
    shutil.copytree(REPO, source, ignore=NOT_COPIED)
    _call(sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation", "-w", tmp / "dist", source)
    (wheel,) = (tmp / "dist").glob("psorr-*.whl")
    venv = tmp / "venv"
    _call(sys.executable, "-m", "venv", "--without-pip", venv)
    python = venv / "bin" / "python"
    _call(sys.executable, "-m", "pip", "--python", python, "install", "-q", "--no-deps", "--no-index", wheel)
    venv_site = Path(_call(python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])").strip())
    (venv_site / "_psorr_test_dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    work = tmp / "work"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}
    env["PSORR_CACHE"] = str(tmp / "cache")  # a fresh training cache, not the user's
    return Installed(wheel, venv / "bin", venv_site, work, env)


def test_psorr_and_sim_import_from_the_venv_not_the_checkout(installed):
    code = "import json, psorr, psorr.assets, sim; print(json.dumps([psorr.__file__, psorr.assets.__file__, " \
           "sim.__file__]))"
    for path in json.loads(installed.run(str(installed.bin / "python"), "-c", code).stdout):
        assert Path(path).is_relative_to(installed.site_packages), path


def test_the_wheel_ships_every_asset_but_the_build_scripts_and_the_preview(installed):
    with zipfile.ZipFile(installed.wheel) as wheel:
        shipped = {n.removeprefix("psorr/assets/") for n in wheel.namelist() if n.startswith("psorr/assets/")}
    in_checkout = {p.relative_to(REPO / "assets").as_posix() for p in (REPO / "assets").rglob("*")
                   if p.is_file() and "__pycache__" not in p.parts}
    expected = {n for n in in_checkout if not any(fnmatch.fnmatch(n, pattern) for pattern in NOT_SHIPPED)}
    assert shipped - {"__init__.py"} == expected, "list the new asset in pyproject.toml's package-data, or here"
    for kind in ("robot/arm.xml", "workpieces/catalog.json", "workpieces/meshes/chassis.stl",
                 "workpieces/collision/index.json", "workpieces/collision/chassis_0.stl"):
        assert kind in shipped


def test_psorr_recognize_finds_the_parts_with_the_shipped_meshes(installed):
    catalog = load_catalog()
    meshes = {name: catalog[name].load_mesh() for name in SCENE_PARTS}
    scene = workpiece_scene(np.random.default_rng(0), meshes, SCENE_PARTS)
    write_cloud(installed.work / "scene.pcd", scene.cloud, compressed=True)
    shipped_meshes = installed.site_packages / "psorr" / "assets" / "workpieces" / "meshes"
    out = installed.run(str(installed.bin / "psorr"), "recognize", str(shipped_meshes), "scene.pcd", "--json")
    detections = json.loads(out.stdout)["detections"]
    # A part's centroid is where it is under any of its symmetries: compare those, within 1 cm.
    for instance in scene.instances:
        centroid = np.append(meshes[instance.name].centroid, 1.0)
        truth = (instance.T_camera_model @ centroid)[:3]
        found = [np.linalg.norm((np.array(d["pose"]) @ centroid)[:3] - truth) for d in detections
                 if d["model"] == instance.name]
        assert found and min(found) < 0.01, f"{instance.name}: {found} m from the truth"
    assert len(detections) == len(SCENE_PARTS), [d["model"] for d in detections]


def test_psorr_sim_perceive_runs_the_cell_and_recognises_its_parts(installed):
    out = installed.run(str(installed.bin / "psorr-sim"), "perceive", "--seed", "0", "--json")
    result = json.loads(out.stdout)
    assert result["parts"] and result["detections"], result
    assert len(result["missed"]) < len(result["parts"]), f"no part recognised: {result}"
    assert {d["model"] for d in result["detections"] if d["correct"]} <= set(result["parts"])
