"""psorr's package data: the workpiece catalog, meshes and collision meshes, and the robot's MJCF.

Layout, below this folder:
    workpieces/catalog.json       the catalog (psorr.synthetic.catalog reads it)
    workpieces/meshes/*.stl       one CAD mesh per part, metres
    workpieces/collision/         CoACD convex parts of each mesh and their index.json (the sim's contacts)
    robot/arm.xml                 the arm and gripper (MJCF, primitives only)

In a checkout this is the repository's top-level ``assets/`` folder, where the build scripts in
``assets/workpieces/`` write these files; setuptools installs the folder as the package
``psorr.assets`` (``package-dir`` in pyproject.toml, the package list in setup.py), so an
installed psorr carries them and needs no checkout. The build scripts and the preview picture
stay in the checkout. Code reaches every file through :func:`asset_path`, never through a path
of its own relative to ``__file__``.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from psorr.errors import AssetError

__all__ = ["asset_path"]


def asset_path(*parts: str) -> Path:
    """The file or folder ``parts`` below psorr's assets, e.g. ``asset_path("robot", "arm.xml")``.

    Raises:
        AssetError: it does not exist (the message names it and the fix), or psorr is installed
            zipped, where MuJoCo and trimesh, which open files by name, could not read it.
    """
    root = files(__name__)
    if not isinstance(root, Path):
        raise AssetError(root, "psorr's assets are not files on disk (a zipped install)",
                         "install psorr with pip, which unpacks it")
    path = root.joinpath(*parts)
    if not path.exists():
        raise AssetError(path, "no such psorr asset", _fix(root))
    return path


def _fix(root: Path) -> str:
    if (root / "workpieces" / "build_workpieces.py").is_file():  # a checkout: the build scripts are beside them
        return (f"rebuild it with the scripts in {root / 'workpieces'} (build_workpieces.py, build_collision.py), "
                "or restore it with git checkout")
    return "this psorr was installed without its package data: reinstall it with pip install --force-reinstall"
