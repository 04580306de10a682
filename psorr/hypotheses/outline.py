"""Pose hypotheses from a part's outline on the table, for parts that show too few primitives to pair.

A clip, a hinge or a plate lying on the table shows one face or none that the decomposition can
find, and no pair. What it does show is an outline: the pixels standing higher above the supporting
plane than the sensor's noise. Each connected patch of them is matched to the silhouettes of every
model in its most probable stable resting poses (:func:`psorr.synthetic.resting.stable_rests`) seen
from above: a silhouette of about the patch's area, from a rest about as high as the patch, is
turned about the plane's normal to the angles where it overlaps the patch best, and each gives a
pose. The best of them go through the same ICP and acceptance as every other hypothesis.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import trimesh
from scipy import ndimage

from psorr.checks import params as check
from psorr.geometry.boxes import orthonormal_frame
from psorr.hypotheses.candidates import Candidate, CandidateSet
from psorr.sensing.kinect_noise import KINECT_V1
from psorr.types import PointCloud


@dataclass(frozen=True)
class OutlineParams:
    """Outline hypotheses; distances in metres, areas in m^2.

    A point stands on the table when it is higher than ``sigmas`` x the sensor's depth sigma at its
    depth, and at least ``min_height``. Patches are drawn on a grid of ``cell``; those of at least
    ``min_area`` are matched to each model's ``rests`` most probable resting poses no higher than
    ``max_rest_height``, whose silhouette area is within ``area_ratio`` of the patch's and whose
    height is within ``height_slack`` of the patch's (its 95th percentile). Silhouettes are turned in
    steps of ``angle_step_deg``; the ``angles`` best-overlapping turns give poses, and the
    ``max_candidates`` best of a scene, by overlap, go on to acceptance. Off by default.
    """

    enabled: bool = False
    cell: float = 0.002
    sigmas: float = 2.0
    min_height: float = 0.0027
    min_area: float = 2e-4
    rests: int = 3
    max_rest_height: float = 0.03
    area_ratio: tuple[float, float] = (0.6, 1.4)
    height_slack: float = 0.006
    angle_step_deg: float = 6.0
    angles: int = 2
    max_candidates: int = 24

    def __post_init__(self):
        check.flag(self, "enabled")
        check.positive(self, "cell", "min_height", "min_area", "max_rest_height", "height_slack", unit=" metres")
        check.positive(self, "sigmas", "angle_step_deg")
        check.whole(self, "rests", "angles", "max_candidates")


@dataclass(frozen=True, eq=False)
class Silhouette:
    """A model resting one way, seen from above: its surface samples (N, 2) in the table plane, centred,
    the area they cover, the rest's height, and T_table_model (4, 4) with the samples' centroid at x = y = 0."""

    model: int
    xy: np.ndarray
    area: float
    height: float
    T_table_model: np.ndarray


def _masks(xy: np.ndarray, low: np.ndarray, shape: tuple[int, int], cell: float) -> np.ndarray:
    """(A, *shape) bool images from corner ``low``: the grid cells that each of A point sets (A, N, 2) falls
    in, each closed on its own."""
    index = np.floor((xy - low) / cell).astype(np.int64)
    inside = (index >= 0).all(axis=2) & (index[..., 0] < shape[0]) & (index[..., 1] < shape[1])
    masks = np.zeros((len(xy),) + tuple(shape), dtype=bool)
    which = np.broadcast_to(np.arange(len(xy))[:, None], inside.shape)
    masks[which[inside], index[..., 0][inside], index[..., 1][inside]] = True
    flat = np.zeros((3, 3, 3), dtype=bool)  # the 2-D closing's cross, spanning no two images
    flat[1] = ndimage.generate_binary_structure(2, 1)
    return ndimage.binary_closing(masks, structure=flat, iterations=2)


def _mask(xy: np.ndarray, low: np.ndarray, shape: tuple[int, int], cell: float) -> np.ndarray:
    """The grid cells (a bool image of ``shape`` from corner ``low``) that the points (N, 2) fall in, closed."""
    return _masks(xy[None], low, shape, cell)[0]


def _grid(xy: np.ndarray, cell: float, margin: float) -> tuple[np.ndarray, tuple[int, int]]:
    low = xy.min(axis=0) - margin
    return low, tuple(int(n) for n in np.ceil((xy.max(axis=0) + margin - low) / cell).astype(np.int64) + 1)


def table_frame(plane: np.ndarray) -> np.ndarray:
    """T_cloud_table (4, 4) of a supporting plane (a, b, c, d; unit normal towards the sensor): z along the
    normal, the origin the plane's point nearest the sensor."""
    normal = np.asarray(plane[:3], dtype=float)
    T = np.eye(4)
    T[:3, 0], T[:3, 1] = orthonormal_frame(normal)
    T[:3, 2], T[:3, 3] = normal, -plane[3] * normal
    return T


class OutlineMatcher:
    """The library's silhouettes in their resting poses, matched to the patches standing on a scene's table."""

    def __init__(self, models, params: OutlineParams):
        from psorr.synthetic.resting import stable_rests

        self.params, self.silhouettes = params, []
        p = params
        self.turn_angles = np.radians(np.arange(0.0, 360.0, p.angle_step_deg))
        for index, model in enumerate(models):
            mesh = trimesh.Trimesh(model.vertices, model.faces, process=False)
            for rest in stable_rests(mesh)[:p.rests]:
                if rest.height > p.max_rest_height:
                    continue
                T = rest.T_table_model.copy()
                xy = (model.points @ T[:3, :3].T + T[:3, 3])[:, :2]
                T[:2, 3] -= xy.mean(axis=0)
                xy = xy - xy.mean(axis=0)
                low, shape = _grid(xy, p.cell, 0.01)
                area = float(_mask(xy, low, shape, p.cell).sum()) * p.cell**2
                self.silhouettes.append(Silhouette(index, xy, area, rest.height, T))

    def candidates(self, cloud: PointCloud, view) -> CandidateSet:
        """Poses of the silhouettes over the patches standing on ``view``'s supporting plane in ``cloud``."""
        start = time.perf_counter()
        plane = view.support_plane
        if plane is None or not self.silhouettes:
            return CandidateSet()
        T_cloud_table = table_frame(plane)
        on_table = self._standing(cloud, plane, np.linalg.inv(T_cloud_table))
        scored = []
        for xy, heights in self._patches(on_table):
            scored += self._matches(xy, heights, T_cloud_table)
        scored.sort(key=lambda s: -s[0])
        chosen = scored[:self.params.max_candidates]
        return CandidateSet(tuple(Candidate(m, T) for _, m, T in chosen), len(scored),
                            (time.perf_counter() - start) * 1e3)

    def _standing(self, cloud: PointCloud, plane: np.ndarray, T_table_cloud: np.ndarray) -> np.ndarray:
        """(K, 3) the cloud's points standing on the table, in the table frame."""
        p = self.params
        points = cloud.points[cloud.valid_mask]
        height = points @ plane[:3] + plane[3]
        floor = np.maximum(p.min_height, p.sigmas * KINECT_V1.depth_sigma(points[:, 2]))
        up = points[height > floor]
        return up @ T_table_cloud[:3, :3].T + T_table_cloud[:3, 3]

    def _patches(self, on_table: np.ndarray):
        """(points (N, 2), heights (N,)) of each connected patch of at least min_area standing on the table."""
        p = self.params
        if len(on_table) == 0:
            return
        low, shape = _grid(on_table[:, :2], p.cell, 0.01)
        labels, count = ndimage.label(ndimage.binary_opening(_mask(on_table[:, :2], low, shape, p.cell)))
        index = np.floor((on_table[:, :2] - low) / p.cell).astype(np.int64)
        owner = labels[index[:, 0], index[:, 1]]
        for k in range(1, count + 1):
            cells = np.argwhere(labels == k)
            if len(cells) * p.cell**2 >= p.min_area:
                yield cells * p.cell + low, on_table[owner == k, 2]

    def _overlaps(self, xy: np.ndarray, centre: np.ndarray, target: np.ndarray, low) -> np.ndarray:
        """(A,) intersection over union of the silhouette samples ``xy`` turned by each of the turn angles onto
        ``centre`` with the patch's mask ``target`` (grid corner ``low``); all turns drawn and closed at once."""
        c, n = np.cos(self.turn_angles)[:, None], np.sin(self.turn_angles)[:, None]
        turned = np.stack([xy[:, 0] * c - xy[:, 1] * n, xy[:, 0] * n + xy[:, 1] * c], axis=-1) + centre  # (A, N, 2)
        masks = _masks(turned, low, target.shape, self.params.cell)
        both = (masks & target).sum(axis=(1, 2))
        return both / np.maximum((masks | target).sum(axis=(1, 2)), 1)

    def _matches(self, patch: np.ndarray, heights: np.ndarray, T_cloud_table: np.ndarray) -> list:
        """(overlap, model, T_cloud_model) of the silhouettes turned onto one patch (its cells' corners (N, 2))."""
        p = self.params
        centre, area = patch.mean(axis=0), len(patch) * p.cell**2
        top = np.percentile(heights, 95) if len(heights) else 0.0
        low, shape = _grid(patch, p.cell, 0.03)
        target = _mask(patch, low, shape, p.cell)
        out = []
        for s in self.silhouettes:
            if not p.area_ratio[0] * s.area < area < p.area_ratio[1] * s.area or abs(top - s.height) > p.height_slack:
                continue
            overlap = self._overlaps(s.xy, centre, target, low)
            # The best turns that are peaks of the overlap, not a peak's shoulders: a half-turned twin
            # (a plate's hole at the other end) is a second peak.
            peaks = np.flatnonzero((overlap >= np.roll(overlap, 1)) & (overlap >= np.roll(overlap, -1)))
            turns = sorted(((overlap[k], self.turn_angles[k]) for k in peaks), key=lambda t: -t[0])
            for share, angle in turns[:p.angles]:
                Rz = np.eye(4)
                Rz[:2, :2] = [[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]
                Rz[:2, 3] = centre
                out.append((float(share), s.model, T_cloud_table @ Rz @ s.T_table_model))
        return out
