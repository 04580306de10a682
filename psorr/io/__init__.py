"""Reading and writing files: point clouds (PCD, PLY, XYZ/TXT, NPY) and triangle meshes (STL, OBJ, PLY, STEP).

Every failure caused by a file raises :class:`psorr.errors.CloudFileError` naming the file and the fix.

- :mod:`psorr.io.clouds`: ``read_cloud`` and ``write_cloud``, by suffix;
- :mod:`psorr.io.pcd`, :mod:`psorr.io.ply`: the two codecs, over the typed records of :mod:`psorr.io.records`;
- :mod:`psorr.io.meshes`: ``read_mesh``, with the checks a CAD export needs;
- :mod:`psorr.io.step`: STEP files, tessellated by OpenCASCADE (the ``step`` extra), and the unit they declare.
"""

from psorr.io.clouds import CLOUD_SUFFIXES, read_cloud, write_cloud
from psorr.io.meshes import MESH_SUFFIXES, read_mesh
from psorr.io.step import declared_units

__all__ = ["CLOUD_SUFFIXES", "MESH_SUFFIXES", "declared_units", "read_cloud", "read_mesh", "write_cloud"]
