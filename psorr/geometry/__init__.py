"""Geometry the stages share, vectorised in numpy: rotations, analytic planes and cylinders and their fits
(:mod:`~psorr.geometry.shapes`), minimum-volume oriented boxes (:mod:`~psorr.geometry.boxes`) and their exact
intersections, pair by pair (:mod:`~psorr.geometry.box_overlap`) or many at once
(:mod:`~psorr.geometry.box_batch`); column-wise reductions of tall arrays; Open3D run on one thread so
that seeds repeat (:mod:`~psorr.geometry.open3d_threads`); of meshes, whether one bounds a solid
(:mod:`~psorr.geometry.solids`), its surface's centroid and second moments
(:mod:`~psorr.geometry.surface_moments`) and the diameter of a point set (:mod:`~psorr.geometry.diameter`)."""
