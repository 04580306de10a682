"""Seeded synthetic scenes with ground truth, and the measures they are graded with.

- :mod:`~psorr.synthetic.catalog`: the workpiece catalog (meshes, symmetries) and the symmetry-aware
  pose error;
- :mod:`~psorr.synthetic.workpiece_scenes`: table-top scenes of catalog workpieces, ray cast from a
  Kinect v1;
- :mod:`~psorr.synthetic.primitive_scenes`: scenes of analytic planes and cylinders with known surfaces;
- :mod:`~psorr.synthetic.metrics`: a decomposition scored against ground-truth labels.
"""

from psorr.synthetic.catalog import load_catalog, symmetric_add
from psorr.synthetic.workpiece_scenes import WorkpieceScene, workpiece_scene

__all__ = ["WorkpieceScene", "load_catalog", "symmetric_add", "workpiece_scene"]
