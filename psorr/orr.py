"""ORR hypotheses (Papazov and Burschka 2010): random oriented scene point
pairs looked up in the same hash table, each pose screened point by point."""

from __future__ import annotations

import time

import numpy as np

from psorr.verify import check_pose


def orr_hypotheses(recognizer, cloud, view, rng):
    """(candidates [(model index, T)], hypotheses checked, total check ms)."""
    p, library = recognizer.params, recognizer.library
    # Oriented scene points: the view's ICP copy already carries normals facing the sensor.
    # Papazov samples the scene with the supporting plane segmented away.
    pts = view.object_points
    nrm = np.asarray(view.objects.normals)
    tree = view.object_tree
    if len(pts) < 2:
        return [], 0, 0.0
    diameters = np.array([m.diameter for m in library.models])
    checked, elapsed, scored = 0, 0.0, []
    attempts = 0
    while checked < p.orr_hypotheses and attempts < 20 * p.orr_hypotheses:
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
        for T, m in zip(poses, models):
            model = library.models[m]
            start = time.perf_counter()
            check = check_pose(view, model.points, model.normals, T, p.check)
            elapsed += (time.perf_counter() - start) * 1e3
            checked += 1
            if check.n_support >= p.min_support // 2:
                scored.append((check.score, int(m), T))
    scored.sort(key=lambda s: -s[0])
    return [(m, T) for _, m, T in scored[: p.refine_top]], checked, elapsed
