"""Pinhole camera intrinsics, depth-image back-projection and point projection.

Pixel (u, v) has its centre at integer coordinates: column u, row v, so a camera-frame
point (x, y, z) (OpenCV axes: x right, y down, z forward, metres) lands at
u = fx * x / z + cx, v = fy * y / z + cy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from psorr.errors import InvalidInputError
from psorr.types import PointCloud


@dataclass(frozen=True)
class CameraIntrinsics:
    """A pinhole camera without distortion.

    Attributes:
        width, height: image size in pixels.
        fx, fy: focal lengths in pixels.
        cx, cy: principal point in pixels (pixel centres are at integer coordinates).
    """

    width: int = 640
    height: int = 480
    fx: float = 525.0
    fy: float = 525.0
    cx: float = 319.5
    cy: float = 239.5

    def __post_init__(self):
        if int(self.width) <= 0 or int(self.height) <= 0:
            raise InvalidInputError(f"image size must be positive, got {self.width}x{self.height}")
        if not (self.fx > 0 and self.fy > 0):
            raise InvalidInputError(f"focal lengths must be positive, got {self.fx}, {self.fy}")
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))

    @classmethod
    def kinect_v1(cls) -> CameraIntrinsics:
        """The nominal Kinect v1 depth camera: 640x480, f = 525 px."""
        return cls()

    @property
    def K(self) -> np.ndarray:
        """(3, 3) camera matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) of an image from this camera."""
        return self.height, self.width

    def pixel_rays(self) -> np.ndarray:
        """(H, W, 3) ray direction through every pixel centre, scaled so that z = 1."""
        u = (np.arange(self.width, dtype=np.float64) - self.cx) / self.fx
        v = (np.arange(self.height, dtype=np.float64) - self.cy) / self.fy
        rays = np.empty((self.height, self.width, 3))
        rays[..., 0] = u[None, :]
        rays[..., 1] = v[:, None]
        rays[..., 2] = 1.0
        return rays

    def project(self, points) -> np.ndarray:
        """Project (N, 3) camera-frame points (metres) to (N, 2) pixel coordinates (u, v).

        Points at or behind the camera (z <= 0) and non-finite points give NaN rows.
        """
        points = np.asarray(points, dtype=np.float64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise InvalidInputError(f"points must have shape (N, 3), got {points.shape}")
        z = points[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = np.stack(
                [self.fx * points[:, 0] / z + self.cx, self.fy * points[:, 1] / z + self.cy], axis=1
            )
        uv[~(z > 0)] = np.nan
        return uv


def project(points, intrinsics: CameraIntrinsics) -> np.ndarray:
    """Project (N, 3) camera-frame points to (N, 2) pixels; see CameraIntrinsics.project."""
    return intrinsics.project(points)


def look_at(eye, target, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """(4, 4) T_world_camera of a camera at eye (3,) looking at target (3,), OpenCV axes:
    z towards the target, x to the right, y down (away from the world up direction)."""
    eye, target, up = (np.asarray(a, dtype=np.float64) for a in (eye, target, up))
    forward = target - eye
    if np.linalg.norm(forward) == 0:
        raise InvalidInputError("eye and target must differ")
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, up)
    if np.linalg.norm(right) < 1e-9:
        raise InvalidInputError("up must not be parallel to the viewing direction")
    right /= np.linalg.norm(right)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([right, np.cross(forward, right), forward])
    T[:3, 3] = eye
    return T


def _per_pixel(value, name: str, intrinsics: CameraIntrinsics, tail: tuple[int, ...]):
    array = np.asarray(value)
    h, w = intrinsics.shape
    if array.shape == (h, w) + tail:
        return array.reshape((h * w,) + tail)
    if array.shape == (h * w,) + tail:
        return array
    raise InvalidInputError(
        f"{name} must have shape {(h, w) + tail} or {(h * w,) + tail} to match the camera, "
        f"got {array.shape}"
    )


def checked_depth(depth, intrinsics: CameraIntrinsics) -> tuple[np.ndarray, np.ndarray]:
    """(depth (H, W) float64 with 0 where there is no return, valid (H, W) bool) of a depth
    image, whose shape must match the intrinsics; 0, negative and NaN depths are no return."""
    depth = np.asarray(depth, dtype=np.float64)
    if depth.shape != intrinsics.shape:
        raise InvalidInputError(
            f"depth must have shape (H, W) = {intrinsics.shape} to match the intrinsics, "
            f"got {depth.shape}"
        )
    valid = np.isfinite(depth) & (depth > 0)
    return np.where(valid, depth, 0.0), valid


def depth_to_cloud(depth, intrinsics: CameraIntrinsics, colors=None, labels=None) -> PointCloud:
    """Back-project a depth image into an organised cloud in the camera frame.

    Args:
        depth: (H, W) depth along the optical axis (z) in metres; 0, negative or NaN
            means no return. H, W must match the intrinsics.
        intrinsics: the camera that took the image.
        colors: optional (H, W, 3) or (H*W, 3) RGB floats in [0, 1].
        labels: optional (H, W) or (H*W,) integer labels; set to -1 at invalid pixels.

    Returns:
        An organised PointCloud of H*W points in row-major pixel order (index v * W + u),
        with NaN rows where there is no return.
    """
    depth, valid = checked_depth(depth, intrinsics)
    points = intrinsics.pixel_rays() * np.where(valid, depth, np.nan)[..., None]
    points = points.reshape(-1, 3)
    if colors is not None:
        colors = _per_pixel(colors, "colors", intrinsics, (3,))
    if labels is not None:
        labels = np.array(_per_pixel(labels, "labels", intrinsics, ()), dtype=np.int64)
        labels[~valid.ravel()] = -1
    return PointCloud(
        points=points,
        colors=colors,
        labels=labels,
        width=intrinsics.width,
        height=intrinsics.height,
    )
