"""Seeded synthetic scenes with ground truth, and the measures they are graded with.

- :mod:`~psorr.synthetic.catalog`: the workpiece catalog (meshes, symmetries) and the symmetry-aware
  pose error;
- :mod:`~psorr.synthetic.workpiece_scenes`: table-top scenes of catalog workpieces, ray cast from a
  Kinect v1;
- :mod:`~psorr.synthetic.mesh_scenes`: table-top scenes of any folder of meshes, each part in a stable
  resting pose, single, in clutter with distractors, or occluded (:mod:`~psorr.synthetic.resting`
  finds the rests and lays them out, :mod:`~psorr.synthetic.scene_visibility` says how much of each
  part is seen);
- :mod:`~psorr.synthetic.mesh_symmetry`: a mesh's symmetries found from the mesh, for grading parts
  without a catalog entry;
- :mod:`~psorr.synthetic.part_shapes`: a part's class (thin, flanged, turned, freeform, prismatic) from
  its mesh;
- :mod:`~psorr.synthetic.primitive_scenes`: scenes of analytic planes and cylinders with known surfaces;
- :mod:`~psorr.synthetic.metrics`: a decomposition scored against ground-truth labels.
"""

from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.mesh_scenes import MeshScene, SceneKind, SceneParams, load_meshes, mesh_scene, simple_shapes
from psorr.synthetic.mesh_symmetry import MeshSymmetry, SymmetryParams, find_symmetries, mesh_symmetric_add
from psorr.synthetic.part_shapes import PartClass, PartShape, ShapeParams, part_shape
from psorr.synthetic.workpiece_scenes import WorkpieceScene, workpiece_scene

__all__ = ["MeshScene", "MeshSymmetry", "PartClass", "PartShape", "SceneKind", "SceneParams", "ShapeParams",
           "SymmetryParams", "WorkpieceScene", "find_symmetries", "load_catalog", "load_meshes", "mesh_scene",
           "mesh_symmetric_add", "part_shape", "simple_shapes", "symmetric_add", "workpiece_scene"]
