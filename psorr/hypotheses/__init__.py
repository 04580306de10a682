"""Pose hypotheses: where candidate poses come from.

- :mod:`~psorr.hypotheses.pairs`: PSORR's pairs of scene primitives looked up in the model hash table,
  clustered by vote (:mod:`~psorr.hypotheses.pose_clusters`) after the primitives' kinds and sizes
  (:mod:`~psorr.hypotheses.primitive_match`) ruled out most matches, then screened by box verification;
- :mod:`~psorr.hypotheses.single_plane`, :mod:`~psorr.hypotheses.single_cylinder`: poses from one face
  or one long cylinder, for parts that show no pair;
- :mod:`~psorr.hypotheses.outline`: parts in their stable resting poses over the patches they raise on the
  table (again where something hides them: :mod:`~psorr.hypotheses.hidden_rests`), one pose of each set
  that puts the same surface in the same place (:mod:`~psorr.hypotheses.same_surface`);
- :mod:`~psorr.hypotheses.psg`: the primitive shape graph's cliques, with QPBO;
- :mod:`~psorr.hypotheses.orr`: the ORR baseline's random oriented point pairs.
"""
