"""Pose hypotheses: where candidate poses come from.

- :mod:`~psorr.hypotheses.pairs`: PSORR's pairs of scene primitives looked up in the model hash table,
  clustered by vote (:mod:`~psorr.hypotheses.pose_clusters`) after the primitives' kinds and sizes
  (:mod:`~psorr.hypotheses.primitive_match`) ruled out most matches, then screened by box verification;
- :mod:`~psorr.hypotheses.single_plane`, :mod:`~psorr.hypotheses.single_cylinder`: poses from one face
  or one long cylinder, for parts that show no pair;
- :mod:`~psorr.hypotheses.orr`: the ORR baseline's random oriented point pairs.
"""
