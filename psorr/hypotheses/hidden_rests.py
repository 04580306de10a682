"""Resting poses of parts that something above them hides in part: an arm reaching in, or a taller neighbour.

The resting-pose search (:mod:`psorr.hypotheses.outline`) charges a silhouette for every sample that falls
off the patch, and shifts a pose's centre only a few millimetres from the patch's. A part half under an arm
shows a patch whose centre lies far from the part's, and the true pose's silhouette covers table cells the
sensor never saw: the search misses it. Here a table cell counts as hidden when the sensor's ray to it meets
something higher than any model rests, or lies out of the sensor's sight (an arm nearer than its range:
:attr:`~psorr.verification.scene_view.SceneView.out_of_sight`); a patch that borders hidden cells may cover
them at no cost, and each resting shape wider than the patch is shifted as far as its own reach, the farthest
its silhouette's centre can lie from the centre of any piece of it. This runs after the full search, and only
over patches no part found explains: the cheap silhouettes over hidden cells would otherwise crowd the other
poses out.
Measured: docs/decisions/0071-partly-hidden-resting-parts.md and 0073-out-of-sight.md.
"""

from __future__ import annotations

import time

import numpy as np
from scipy import ndimage

from psorr.hypotheses.candidates import CandidateSet
from psorr.hypotheses.outline import OutlineMatcher, cheapest
from psorr.hypotheses.standing_patches import StandingGrid, patch_reach, standing_grid, table_frame
from psorr.types import PointCloud
from psorr.verification.point_check import depth_tolerance


def hidden_cells(grid: StandingGrid, view, plane: np.ndarray, tallest: float, check) -> np.ndarray:
    """(rows, cols) the grid's table cells that no patch holds and that ``view`` sees through something
    higher than ``tallest`` metres above ``plane``: the depth at the cell's pixel is nearer than the table's
    there, by more than the point check's tolerance, and that nearer point stands above every rest; or the
    pixel lies out of the sensor's sight (``view.out_of_sight``)."""
    rows, cols = grid.labels.shape
    centres = grid.centres(np.ones((rows, cols), dtype=bool))
    T = grid.T_cloud_table
    table = centres @ T[:3, :2].T + T[:3, 3]
    u, v, inside = view.project(table)
    depth = view.depth[v * view.width + u]
    nearer = inside & np.isfinite(depth) & (depth < table[:, 2] - depth_tolerance(table[:, 2], check))
    depth = np.where(nearer, depth, 0.0)  # a pixel with no measurement (inf) stands for no point
    seen = np.column_stack([(u - view.cx) * depth / view.focal, (v - view.cy) * depth / view.focal, depth])
    height = np.where(nearer, seen @ plane[:3] + plane[3], -np.inf)
    hidden = (height > tallest) | (inside & view.out_of_sight[v * view.width + u])
    return hidden.reshape(rows, cols) & (grid.labels == 0)


class HiddenRests:
    """The outline search's resting shapes, posed over patches that border table cells an occluder hides."""

    def __init__(self, outline: OutlineMatcher):
        self.outline = outline
        self.border = outline.params.hidden_border
        # The grid reaches as far past the standing points as the widest silhouette, in whole cells, so that
        # its cells are the ordinary search's and every cell a shifted silhouette covers is on it.
        cell = outline.params.cell
        widest = max((shape.reach for shape in outline.shapes), default=0.0)
        self.margin = float(np.ceil(widest / cell) * cell)

    def candidates(self, cloud: PointCloud, view, explained=None) -> CandidateSet:
        """Poses over the patches standing on ``view``'s supporting plane in ``cloud`` that border hidden cells;
        each patch's silhouettes may cover those cells free. ``explained(points)``, given a patch's (N, 3)
        points in the cloud's frame, says whether a part found already accounts for them: those are skipped."""
        start = time.perf_counter()
        outline, plane = self.outline, view.support_plane
        if plane is None or not outline.shapes or self.border is None or not (
                self._above_every_rest(cloud, plane) or view.out_of_sight.any()):
            return CandidateSet()
        grid = standing_grid(cloud, plane, outline.params, outline.tallest, outline.check, self.margin)
        if grid is None:
            return CandidateSet()
        hidden = hidden_cells(grid, view, plane, outline.tallest, outline.check)
        near = ndimage.binary_dilation(hidden, iterations=self.border) if hidden.any() else hidden
        per_patch = []
        T = grid.T_cloud_table
        for label in grid.patches:
            mine = grid.labels == label
            if not (near & mine).any():
                continue
            patch = grid.patch(label, mine | near, outline.truncation, outline.check)
            if explained is None or not explained(patch.points @ T[:3, :3].T + T[:3, 3]):
                per_patch.append(self._poses(patch, outline.clear_in(view, T)))
        return outline.chosen(per_patch, table_frame(plane), start)

    def _above_every_rest(self, cloud: PointCloud, plane: np.ndarray) -> bool:
        """Whether any of ``cloud``'s points stands higher than any model rests: else nothing hides a cell."""
        points = cloud.points[cloud.valid_mask]
        return bool((points @ plane[:3] + plane[3] > self.outline.tallest).any())

    def _poses(self, patch, clear=None) -> list:
        """The ordinary search's poses over ``patch``, and those of the shapes wider than it shifted within
        their reach on a grid of the distance fields' truncation (a silhouette that far from its fit still
        reads the costs falling towards it), cheapest first."""
        outline, p = self.outline, self.outline.params
        reach = patch_reach(patch)
        wide = [shape for shape in outline.shapes if shape.reach > reach + patch.tolerance + p.shift]
        wider = outline.poses(patch, wide, lambda shape: shape.reach, outline.truncation, within_reach=True)
        return cheapest(outline.patch_poses(patch, clear) + wider, p.max_cost_ratio, clear)
