"""A scene as the checks see it: the cloud rasterised into a depth buffer seen from its sensor at the
origin (SceneView), against which psorr.verification.point_check judges poses, with a downsampled copy
for point-to-plane ICP (psorr.acceptance.icp.refine_icp) and the supporting plane.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
import open3d as o3d
from scipy.spatial import cKDTree

from psorr.geometry.support_plane import support_plane
from psorr.geometry.voxels import voxel_means
from psorr.sensing.resolution import grid_focal
from psorr.types import PointCloud

KINECT_FOCAL = 525.0  # pixels of a 640-wide Kinect v1 image
_SELF_BLOCK = 4  # pixels: model samples are sparser than pixels, so self-occlusion is judged per block
_CLAIM_BLOCK = 4  # pixels of a 640-wide Kinect image: the cells in which detections claim what they explain
_NORMAL_MARGIN = 0.03  # m of ICP-target normals kept beyond the crop that needed them
# Pixels (of a 640-wide Kinect image) around an unmeasured pixel searched for a nearer surface: the
# projector's shadow beside a nearer edge is a few centimetres wide at a metre.
SHADOW_REACH = 8
_SCATTERED_FOCAL = 0.5  # buffer pixels per point spacing for scattered points (sampled surfaces, thinned clouds)
_GRID_NEIGHBOUR = 0.8  # spacings: a median nearest-neighbour gap beyond this is a grid's, not scattered points'


def buffer_focal(cloud: PointCloud, ux: np.ndarray, uy: np.ndarray) -> float:
    """Focal length (pixels) at which the cloud fills its depth buffer: an
    organised cloud's own (a Kinect's scaled to its width, unless the cloud's
    grid says otherwise by more than 2%: a 1280x720 sensor at 910 pixels,
    buffered at a Kinect's 1050, left a quarter of its pixels empty and its
    parts seen through), else a pixel two
    point spacings wide, the spacing measured by density (the median disc
    around a ray that holds its six nearest rays, over six). A fixed 640-wide
    focal would leave a 320x240 cloud's buffer three-quarters empty. Two
    spacings, because scattered points (a sampled surface, a voxel-thinned
    cloud) do not fall one per pixel: at one, about a third of a surface's
    pixels would hold no point of it, and show the surface behind, so a
    correct pose would look seen through. The nearest-neighbour gap is no
    measure of spacing: thinning a cloud to one point per voxel leaves pairs
    across voxel borders, and its median gap half the voxel.

    But rays on a camera's grid (an image stripped of its NaN pixels, as PCL
    pipelines pass clouds on) lie one grid step from their nearest neighbours,
    0.98 spacings against 0.46-0.5 for scattered points, and that step is the
    grid's own focal length, inverted. Buffered at it, the stripped image is
    its image again, pixel for pixel (the buffer's corner is the rays' own,
    as for an organised cloud), and recognition finds what it finds in the
    organised image. Buffered coarser (1.43 spacings a pixel), 36 clutter
    scenes stripped so gave 114 of 144 parts and 2 false detections from a
    Kinect (113 and 3 organised) but 107 and 10 from a 1280x720 sensor at 910
    pixels (110 and 4 organised): a coarser buffer lets more of a wrong pose
    pass as unseen."""
    if cloud.is_organised:
        kinect = KINECT_FOCAL * cloud.width / 640.0
        own = grid_focal(cloud)
        return own if own is not None and abs(own / kinect - 1.0) > 0.02 else kinect

    rays = np.column_stack([ux, uy])
    if len(rays) < 7:
        return KINECT_FOCAL
    disc, _ = cKDTree(rays).query(rays[:: max(1, len(rays) // 20000)], k=7)
    spacing = float(np.sqrt(np.pi * np.median(disc[:, 6]) ** 2 / 6))
    if not spacing > 0:
        return KINECT_FOCAL
    step = float(np.median(disc[:, 1]))
    return 1.0 / step if step > _GRID_NEIGHBOUR * spacing else _SCATTERED_FOCAL / spacing


class SceneView:
    """A depth buffer of a cloud from its sensor origin, plus an Open3D copy for ICP."""

    def __init__(self, cloud: PointCloud, icp_voxel: float = 0.004):
        pts = cloud.points[cloud.valid_mask & (cloud.points[:, 2] > 1e-3)]  # one copy, not two: 3 ms at 640x480
        self.points = pts
        ux, uy = pts[:, 0] / pts[:, 2], pts[:, 1] / pts[:, 2]
        self.focal = buffer_focal(cloud, ux, uy)
        self.organised = cloud.is_organised
        self.cx, self.cy = -self.focal * ux.min() + 2, -self.focal * uy.min() + 2
        self.width = int(self.focal * (ux.max() - ux.min())) + 5
        self.height = int(self.focal * (uy.max() - uy.min())) + 5
        # A claim cell as wide, in metres, as a Kinect's at the same distance: the checks sample a model no
        # denser on a finer image. With 4-pixel cells at 1280x720, two poses of one chassis (turned by its
        # symmetry) held different samples in 74% of their cells, and both were reported.
        self.claim_block = max(_CLAIM_BLOCK, round(_CLAIM_BLOCK * self.focal / KINECT_FOCAL))
        u, v, _ = self.project(pts)
        self.depth = _nearest_per_pixel(self.width * self.height, v * self.width + u, pts[:, 2])
        down = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(voxel_means(pts, icp_voxel)))
        self.down = down
        # The supporting plane (the largest one, normal towards the sensor): no
        # part can sit below it, and ORR samples what stands on it.
        found = support_plane(down)
        self.support_plane = None if found is None else found.plane
        keep = np.ones(len(down.points), dtype=bool)
        if found is not None:
            keep[found.inliers] = False
        self._object_mask = keep
        self.icp_voxel = icp_voxel
        self._down_points = np.asarray(down.points)
        # scipy's tree, built flat: half the build time of Open3D's FLANN tree or a balanced one, and
        # ICP's few radius searches a scene take no longer.
        self._down_tree = cKDTree(self._down_points, compact_nodes=False, balanced_tree=False)
        self._normals = np.zeros_like(self._down_points)
        self._has_normal = np.zeros(len(self._down_points), dtype=bool)

    @cached_property
    def objects(self) -> o3d.geometry.PointCloud:
        """The downsampled points off the supporting plane, with normals facing the sensor: ORR's
        scene samples. Built on first use, as PSORR never needs them."""
        objects = self.down.select_by_index(np.flatnonzero(self._object_mask).tolist())
        _estimate_normals(objects, 3 * self.icp_voxel, max_nn=20)
        return objects

    @property
    def object_points(self) -> np.ndarray:
        return np.asarray(self.objects.points)

    @cached_property
    def object_tree(self) -> o3d.geometry.KDTreeFlann | None:
        return o3d.geometry.KDTreeFlann(self.objects) if len(self.objects.points) else None

    def icp_target(self, centre: np.ndarray, radius: float) -> o3d.geometry.PointCloud:
        """The downsampled points within ``radius`` m of ``centre`` (3,), with normals facing the
        sensor: point-to-plane ICP's target.

        Normals come from up to 12 neighbours within 3 voxels, as one estimate over the whole cloud
        would give them, but only where ICP looks: on a 640x480 scene the whole estimate costs more
        than all ICP iterations, and most of the table is never a target. A region's normals are
        estimated once, on a patch wide enough to hold every neighbour of every point they are kept
        for, so they equal the whole-cloud estimate; later crops reuse them.
        """
        near = np.sort(np.asarray(self._down_tree.query_ball_point(centre, radius), dtype=np.int64))
        if not self._has_normal[near].all():
            # Keep a margin beyond this crop: the next crop of the same part is rarely the same sphere.
            keep_radius = radius + _NORMAL_MARGIN
            wide = self._down_tree.query_ball_point(centre, keep_radius + 3 * self.icp_voxel)
            wide = np.sort(np.asarray(wide, dtype=np.int64))
            patch = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(self._down_points[wide]))
            _estimate_normals(patch, 3 * self.icp_voxel, max_nn=12)
            inner = np.linalg.norm(self._down_points[wide] - centre, axis=1) <= keep_radius
            fresh = inner & ~self._has_normal[wide]
            self._normals[wide[fresh]] = np.asarray(patch.normals)[fresh]
            self._has_normal[wide[fresh]] = True
        target = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(self._down_points[near]))
        target.normals = o3d.utility.Vector3dVector(self._normals[near])
        return target

    @cached_property
    def neighbour_depth(self) -> np.ndarray:
        """(width x height,) the nearest measured depth at each pixel and its 8 neighbours (inf if none)."""
        return self._nearest_within(1)

    @cached_property
    def nearby_depth(self) -> np.ndarray:
        """(width x height,) the nearest measured depth within SHADOW_REACH pixels of each pixel (inf if none)."""
        return self._nearest_within(max(1, round(SHADOW_REACH * self.focal / KINECT_FOCAL)))

    @cached_property
    def out_of_sight(self) -> np.ndarray:
        """(width x height,) bool: the pixel lies in a region where the sensor measured nothing that holds a
        pixel with nothing measured within SHADOW_REACH: wider than a projector's shadow or a dropout beside
        an edge, it is something the sensor cannot measure (nearer than its range, or absorbing its light)
        that may hide what lies behind it. None in an unorganised cloud: what it lacks may have been cropped
        or thinned away, and was not out of the sensor's sight."""
        from scipy.ndimage import binary_propagation

        nothing = np.zeros(self.width * self.height, dtype=bool)
        if not self.organised:
            return nothing
        deep = ~np.isfinite(self.nearby_depth).reshape(self.height, self.width)
        if not deep.any():
            return nothing
        unmeasured = ~np.isfinite(self.depth).reshape(self.height, self.width)
        return binary_propagation(deep, mask=unmeasured).ravel()

    def _nearest_within(self, reach: int) -> np.ndarray:
        """(width x height,) the least depth in the square of ``reach`` pixels around each pixel; the buffer
        holds inf where nothing was measured, so those read inf unless a neighbour measured."""
        from scipy.ndimage import minimum_filter

        depth = self.depth.reshape(self.height, self.width)
        return minimum_filter(depth, size=2 * reach + 1, mode="nearest").ravel()

    @cached_property
    def measured_near(self) -> np.ndarray:
        """(width x height,) bool: a depth was measured at the pixel or at one of its 8 neighbours. A wider
        gap is a hole of the sensor's (a shadow, a surface seen edge on), not the spacing of the points."""
        from scipy.ndimage import binary_dilation

        finite = np.isfinite(self.depth).reshape(self.height, self.width)
        return binary_dilation(finite, structure=np.ones((3, 3), dtype=bool)).ravel()

    @property
    def n_blocks(self) -> int:
        """How many claim cells (``claim_block`` pixels square) the buffer has: the size of a claim mask."""
        return (self.width // self.claim_block + 1) * (self.height // self.claim_block + 1)

    def claim_cell_of(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Flat index of the claim cell each pixel (u, v) falls in."""
        return (v // self.claim_block) * (self.width // self.claim_block + 1) + u // self.claim_block

    def block_of(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Flat index of the pixel block each pixel (u, v) falls in."""
        return (v // _SELF_BLOCK) * (self.width // _SELF_BLOCK + 1) + u // _SELF_BLOCK

    def rays(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(P, 3) rays through the pixels (u, v) (P,), scaled to z = 1: the point at depth z is z times its ray."""
        return np.column_stack([(u - self.cx) / self.focal, (v - self.cy) / self.focal, np.ones(len(u))])

    def project(self, points: np.ndarray):
        """Pixel (u, v) of (N, 3) points and an in-bounds mask (N,)."""
        z = np.maximum(points[:, 2], 1e-9)
        u = np.round(self.focal * points[:, 0] / z + self.cx).astype(np.int64)
        v = np.round(self.focal * points[:, 1] / z + self.cy).astype(np.int64)
        inside = (u >= 0) & (u < self.width) & (v >= 0) & (v < self.height) & (points[:, 2] > 1e-3)
        return np.clip(u, 0, self.width - 1), np.clip(v, 0, self.height - 1), inside


def _nearest_per_pixel(size: int, pixel: np.ndarray, z: np.ndarray) -> np.ndarray:
    """(size,) the least of the depths ``z`` (N,) that fall in each pixel (flat indices (N,)), inf in the
    others: np.minimum.at's result. That takes 12-19 ms for a 640x480 image, and most pixels hold one point
    (all of an organised cloud's at its own focal length): those are written directly, and only pixels
    holding more go through minimum.at."""
    depth = np.full(size, np.inf)
    alone = np.bincount(pixel, minlength=size)[pixel] == 1
    depth[pixel[alone]] = z[alone]
    if not alone.all():
        np.minimum.at(depth, pixel[~alone], z[~alone])
    return depth


def _estimate_normals(cloud: o3d.geometry.PointCloud, radius: float, max_nn: int) -> None:
    """Give ``cloud`` normals (from up to ``max_nn`` neighbours within ``radius`` m) facing the sensor."""
    if len(cloud.points) >= 3:
        cloud.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=radius, max_nn=max_nn))
        cloud.orient_normals_towards_camera_location(np.zeros(3))
