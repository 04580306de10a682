"""Pictures: decompositions coloured by primitive with their shape graph, and detections drawn over a
cloud (:mod:`~psorr.viz.render`)."""
