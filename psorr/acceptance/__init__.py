"""Acceptance: from screened candidates to detections.

- :mod:`~psorr.acceptance.icp`: point-to-plane ICP of a candidate onto the scene;
- :mod:`~psorr.acceptance.claims`: which detection explains which pixels, settled by score;
- :mod:`~psorr.acceptance.continuation`: the measured surface going on past a pose's outline;
- :mod:`~psorr.acceptance.ambiguity`: choosing between a model's near-symmetric poses;
- :mod:`~psorr.acceptance.unexplained`: what no detection explains, for a second, finer look.
- :mod:`~psorr.acceptance.known`: an earlier look's detections, followed as the first candidates.
"""
