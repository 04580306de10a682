"""ORR hypotheses (Papazov and Burschka 2010): random oriented scene point
pairs looked up in the same hash table, each pose screened point by point
(psorr.verification.point_check, many poses at once)."""

from __future__ import annotations

import time

import numpy as np

from psorr.verification.point_check import check_poses

# Hypotheses checked at once (Table 1's scenes: 32, 64 and 128 cost the same per hypothesis; one at a
# time cost 2.7x as much).
_BATCH = 64


def orr_hypotheses(recognizer, cloud, view, rng):
    """(candidates [(model index, T)], hypotheses checked, total check ms)."""
    p, library = recognizer.params, recognizer.library
    # Oriented scene points: the view's ICP copy already carries normals facing the sensor.
    # Papazov samples the scene with the supporting plane segmented away.
    pts = view.object_points
    nrm = np.asarray(view.objects.normals)
    tree = view.object_tree
    if len(nrm) < 2:  # fewer than 3 points off the table get no normals: nothing to pair
        return [], 0, 0.0
    diameters = np.array([m.diameter for m in library.models])
    drawn_poses, drawn_models = [], []
    attempts = 0
    while len(drawn_poses) < p.orr_hypotheses and attempts < 20 * p.orr_hypotheses:
        attempts += 1
        a = int(rng.integers(len(pts)))
        # Papazov draws the second point at a fixed distance from the first: a
        # share of the model size, so both points often lie on one object.
        radius = float(rng.uniform(0.3, 0.8) * np.median(diameters))
        _, idx, _ = tree.search_radius_vector_3d(pts[a], radius)
        idx = np.asarray(idx)
        if len(idx) < 2:
            continue
        far = idx[np.linalg.norm(pts[idx] - pts[a], axis=1) > 0.6 * radius]
        if len(far) == 0:
            continue
        b = int(rng.choice(far))
        # Papazov looks a pair up in its own cell only. Raw points are as dense as the model's
        # samples, so the cell holds the match; the neighbouring cells' extra matches would only
        # dilute the few poses drawn from them.
        s, rows = library.table.lookup(pts[[a]], nrm[[a]], pts[[b]], nrm[[b]], neighbours=False)
        if len(rows) == 0:
            continue
        pick = rng.choice(len(rows), size=min(len(rows), 4), replace=False)
        poses, models = library.table.poses(s[pick], rows[pick], pts[[a]], nrm[[a]], pts[[b]])
        drawn_poses.extend(poses)
        drawn_models.extend(int(m) for m in models)
    # No draw depends on a check, so the hypotheses are checked in batches, as PSORR's boxes are:
    # one at a time, numpy's per-call overhead cost as much as the check itself.
    scored, elapsed = [], 0.0
    for start in range(0, len(drawn_poses), _BATCH):
        poses, models = np.array(drawn_poses[start:start + _BATCH]), drawn_models[start:start + _BATCH]
        t0 = time.perf_counter()
        checks = check_poses(view, [library.models[m].points for m in models],
                             [library.models[m].normals for m in models], poses, p.check)
        elapsed += (time.perf_counter() - t0) * 1e3
        scored += [(c.score, m, T) for c, m, T in zip(checks, models, poses) if c.n_support >= p.min_support // 2]
    scored.sort(key=lambda s: -s[0])
    return [(m, T) for _, m, T in scored[: p.refine_top]], len(drawn_poses), elapsed
