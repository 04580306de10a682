"""Recordings of a recognition for the Rerun viewer (``rerun-sdk``, the ``psorr[viz]`` extra): every stage
from the cloud to the accepted poses, and the candidates turned down with the reason, to see why a part was
missed. ``psorr recognize ... --rerun OUT.rrd`` and ``psorr decompose ... --rerun OUT.rrd`` write one.

Entity paths, under ``prefix`` (default ``recognition``):

=============================================  =====================================================
``cloud``                                      the cloud (its colours where it has them)
``table``                                      the supporting plane: a flat box over the points on it
``decomposition/<pass>/points``                each primitive's inliers, in its colour in the PNGs
``decomposition/<pass>/boxes``                 one oriented box per primitive, labelled kind and id
``decomposition/<pass>/edges``                 the primitive shape graph: a line per edge
``candidates/round_<k>``                       one search round's candidates: their model's box, with
                                               its screening score (box fitness for pairs and cliques)
``rejected``                                   each candidate acceptance turned down, with the reason
``detections/<k>_<model>/mesh``                the model's mesh at the detected pose, with its score
``detections/<k>_<model>/support``             the cloud points on the posed model
``detections/<k>_<model>/alternatives``        the near-symmetric twin poses it left open, as boxes
``time_ms/<stage>``                            each stage's time, a scalar
=============================================  =====================================================

Everything is logged on the ``stage`` timeline (one step per report), so scrubbing replays the search.
"""

from __future__ import annotations

import numpy as np

from psorr.viz.observer import RecognitionObserver
from psorr.viz.rerun_import import RerunStream

TABLE_BAND = 0.01  # m from the supporting plane: the points the table's box spans (display only)
REJECTED_RGB, CANDIDATE_RGB, ALTERNATIVE_RGB = (200, 40, 40), (150, 150, 150), (240, 200, 0)


class RerunLogger(RecognitionObserver, RerunStream):
    """Records what a recognition does for the Rerun viewer; pass it as ``Recognizer.recognize(...,
    observer=logger)``.

    Args:
        path: the ``.rrd`` file to write, or None to stream to a viewer spawned here (``rerun`` installed).
        recording: log into this ``rerun.RecordingStream`` instead (path and spawning are then its own).
        prefix: the entity path everything goes under; each recognition first clears what the last one
            logged there, so that a recording of several shows only the current one's.
        log_cloud: log the input cloud (a recorder that logs the cloud itself, such as the simulator's, passes
            False).
    """

    def __init__(self, path=None, recording=None, prefix: str = "recognition", log_cloud: bool = True):
        RerunStream.__init__(self, "psorr", path, recording)
        self.prefix, self.log_cloud = prefix.strip("/"), log_cloud
        self._cloud = None
        self._step = self._round = 0

    def _log(self, path: str, *archetypes) -> None:
        self.recording.set_time("stage", sequence=self._step)
        self._step += 1
        self.recording.log(f"{self.prefix}/{path}".rstrip("/"), *archetypes)

    # ---------------------------------------------------------------------------- what the stages report

    def cloud(self, cloud) -> None:
        self._cloud = cloud
        if self._step:
            self._log("", self.rr.Clear(recursive=True))
        if not self.log_cloud:
            return
        valid = cloud.valid_mask
        colours = None if cloud.colors is None else np.asarray(cloud.colors)[valid]
        self._log("cloud", self.rr.Points3D(cloud.points[valid], colors=colours, radii=0.001))

    def table(self, plane) -> None:
        if plane is None or self._cloud is None:
            return
        points = self._cloud.points[self._cloud.valid_mask]
        on = points[np.abs(points @ plane[:3] + plane[3]) <= TABLE_BAND]
        if len(on) < 3:
            return
        # The plane as a flat box over the points on it, in axes of the plane: the points are the cloud's.
        normal = np.asarray(plane[:3], dtype=np.float64)
        u = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        axes = np.column_stack([u, np.cross(normal, u), normal])
        local = on @ axes
        low, high = local.min(axis=0), local.max(axis=0)
        self._log("table", self.rr.Boxes3D(centers=[axes @ ((low + high) / 2)], half_sizes=[(high - low) / 2],
                                           quaternions=_quaternions([axes]), colors=(120, 120, 120),
                                           labels=["table"]),
                  self.rr.AnyValues(plane=[float(v) for v in plane]))

    def decomposition(self, name: str, cloud, scene) -> None:
        if scene is None:
            return
        from psorr.viz.render import primitive_colors  # here: it loads matplotlib

        prims = scene.graph.primitives
        kind_rgb = np.round(primitive_colors(scene.graph) * 255).astype(np.uint8)  # as `psorr decompose --png`
        labels = np.asarray(scene.labels)
        on = labels >= 0
        self._log(f"decomposition/{name}/points",
                  self.rr.Points3D(cloud.points[on], colors=kind_rgb[labels[on]], class_ids=labels[on], radii=0.0015))
        self._log(f"decomposition/{name}/boxes", self.rr.Boxes3D(
            centers=[p.box.center for p in prims], half_sizes=[p.box.extent / 2 for p in prims],
            quaternions=_quaternions([p.box.rotation for p in prims]), colors=kind_rgb,
            labels=[f"{p.kind.value} {i}" for i, p in enumerate(prims)]))
        edges = [[prims[i].centroid, prims[j].centroid] for i, j in scene.graph.edges]
        self._log(f"decomposition/{name}/edges", self.rr.LineStrips3D(edges, colors=(20, 20, 20)))

    def candidates(self, candidates, library) -> None:
        if not candidates:
            return
        models = [library.models[c.model] for c in candidates]
        labels = [f"{m.name} {'' if c.score is None else f'{c.score:.2f}'}".strip()
                  for m, c in zip(models, candidates)]
        self._log(f"candidates/round_{self._round:02d}",
                  _posed_boxes(self.rr, models, [c.T_cloud_model for c in candidates], labels, CANDIDATE_RGB))
        self._round += 1

    def rejected(self, model: str, T_cloud_model, reason: str) -> None:
        self._log("rejected", self.rr.Points3D([T_cloud_model[:3, 3]], colors=REJECTED_RGB, radii=0.004,
                                               labels=[f"{model}: {reason}"]),
                  self.rr.TextLog(f"{model} rejected: {reason}", level="DEBUG"))

    def detections(self, detections, library) -> None:
        from psorr.segment.support_colour import supporting_points

        for k, d in enumerate(detections):
            model = library.model(d.model)
            path = f"detections/{k}_{d.model}"
            T = d.T_cloud_model
            self._log(f"{path}/mesh", self.rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]),
                      self.rr.Mesh3D(vertex_positions=model.vertices, triangle_indices=model.faces),
                      self.rr.AnyValues(score=float(d.score), seen=float(d.visible_fraction)))
            if self._cloud is not None:
                support = self._cloud.points[supporting_points(self._cloud, d, model)]
                self._log(f"{path}/support", self.rr.Points3D(support, colors=(40, 180, 60), radii=0.0015))
            if d.alternatives:
                self._log(f"{path}/alternatives", _posed_boxes(
                    self.rr, [model] * len(d.alternatives), list(d.alternatives),
                    [f"{d.model} twin {j}" for j in range(len(d.alternatives))], ALTERNATIVE_RGB))

    def stage_ms(self, name: str, ms: float) -> None:
        self._log(f"time_ms/{name}", self.rr.Scalars(float(ms)))


def _posed_boxes(rr, models, poses, labels, colour):
    """Each model's bounding box (of its samples, in its frame) at its pose (4, 4) in the cloud."""
    lows = np.array([m.points.min(axis=0) for m in models])
    highs = np.array([m.points.max(axis=0) for m in models])
    poses = np.asarray(poses)
    centres = np.einsum("kij,kj->ki", poses[:, :3, :3], (lows + highs) / 2) + poses[:, :3, 3]
    return rr.Boxes3D(centers=centres, half_sizes=(highs - lows) / 2, quaternions=_quaternions(poses[:, :3, :3]),
                      colors=colour, labels=labels)


def _quaternions(rotations) -> np.ndarray:
    """(K, 4) x, y, z, w of box axes (K, 3, 3); an axis frame that is not right-handed has its last axis
    flipped first, which leaves a box the same box."""
    from scipy.spatial.transform import Rotation

    R = np.array(rotations, dtype=np.float64).reshape(-1, 3, 3)
    R[np.linalg.det(R) < 0, :, 2] *= -1
    return Rotation.from_matrix(R).as_quat()
