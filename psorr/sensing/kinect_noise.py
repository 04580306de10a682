"""The Kinect v1 (structured light) depth-noise model, applied to a clean depth image.

Effects, each switchable in KinectNoise:

- axial noise: Gaussian, sigma(z) = 0.0012 + 0.0019 (z - 0.4)^2 m (Nguyen, Izadi and
  Lovell, "Modeling Kinect sensor noise", 3DIMPVT 2012);
- lateral noise: each pixel takes the depth of a pixel at a Gaussian-jittered position
  (sigma ~0.5 px, nearest neighbour), which makes depth edges ragged;
- disparity quantisation: disparity d = f b / z is rounded to multiples of 1/8 px, so
  the depth step grows as z^2 / (8 f b);
- dropouts at grazing angles (view ray nearly in the surface) and beside depth edges;
- the projector shadow: the projector sits b = 7.5 cm along +x of the IR camera, so the
  background just left (-x side) of a foreground edge is lit by no pattern; the band is
  f b (1/z_fg - 1/z_bg) pixels wide;
- the working range: depths outside (min, max) give no return.

Masks (shadow, grazing, edges) are computed from the clean image; all randomness comes
from the rng argument in a fixed order, so a seed gives bit-identical output.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.special import ndtri

from psorr.errors import InvalidInputError
from psorr.sensing.camera import CameraIntrinsics, checked_depth


@dataclass(frozen=True)
class KinectNoise:
    """Parameters of the Kinect v1 depth-noise model (metres, pixels, degrees).

    Attributes:
        axial: add axial Gaussian noise sigma(z) = sigma_base + sigma_quad (z - sigma_z0)^2.
        lateral: resample depth at positions jittered by lateral_sigma_px (nearest pixel).
        quantise: round disparity f * baseline / z to multiples of disparity_step_px.
        baseline: projector offset along +x of the camera in metres (negative for -x).
        grazing: drop pixels whose view ray is nearly in the surface; the probability rises
            linearly from 0 at grazing_start_deg to grazing_max_prob at grazing_end_deg
            (angle between the ray and the surface normal, normals from the depth image).
        edges: drop pixels with a 4-neighbour more than edge_jump metres nearer or farther
            (or without a return) with probability edge_prob.
        shadow: invalidate the background the projector cannot light beside foreground edges.
        depth_range: (min, max) metres with a return, or None for no limit.
    """

    axial: bool = True
    sigma_base: float = 0.0012
    sigma_quad: float = 0.0019
    sigma_z0: float = 0.4
    lateral: bool = True
    lateral_sigma_px: float = 0.5
    quantise: bool = True
    disparity_step_px: float = 0.125
    baseline: float = 0.075
    grazing: bool = True
    grazing_start_deg: float = 75.0
    grazing_end_deg: float = 85.0
    grazing_max_prob: float = 1.0
    edges: bool = True
    edge_jump: float = 0.03
    edge_prob: float = 0.5
    shadow: bool = True
    depth_range: tuple[float, float] | None = (0.4, 4.0)

    def __post_init__(self):
        if self.baseline == 0 and (self.quantise or self.shadow):
            raise InvalidInputError("baseline must be non-zero for quantisation or shadows")
        if not self.grazing_end_deg > self.grazing_start_deg:
            raise InvalidInputError("grazing_end_deg must be larger than grazing_start_deg")
        for name in ("grazing_max_prob", "edge_prob"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise InvalidInputError(f"{name} is a probability and must lie in [0, 1]")
        if min(self.lateral_sigma_px, self.disparity_step_px, self.edge_jump) <= 0:
            raise InvalidInputError("lateral_sigma_px, disparity_step_px and edge_jump must be > 0")

    def noisier(self, factor: float) -> KinectNoise:
        """This model with its axial noise ``factor`` times as large, its quantisation as it is: a sensor measured
        noisier or cleaner than this one. ``factor`` 1 gives this model itself."""
        if factor == 1:
            return self
        if not factor > 0:
            raise InvalidInputError(f"a noise factor must be above 0, got {factor!r}")
        return replace(self, sigma_base=self.sigma_base * factor, sigma_quad=self.sigma_quad * factor)

    def axial_sigma(self, z) -> np.ndarray:
        """Standard deviation of the axial noise (metres) at depth z (metres)."""
        z = np.asarray(z, dtype=np.float64)
        return self.sigma_base + self.sigma_quad * (z - self.sigma_z0) ** 2

    def depth_sigma(self, z, fx: float = 525.0) -> np.ndarray:
        """Total depth standard deviation (metres) at depth z: axial noise and disparity
        quantisation (uniform over a step, so step^2 / 12) added in quadrature."""
        return np.sqrt(self.axial_sigma(z) ** 2 + self.quantisation_step(z, fx) ** 2 / 12.0)

    def height_sigma(self, points, normal, fx: float = 525.0) -> np.ndarray:
        """(N,) standard deviation (metres) of the measured height over a plane of unit ``normal`` (3,) of points
        (N, 3) that lie on it: the depth noise along each point's ray projected on the normal, and the lateral
        jitter, which on a plane seen obliquely reads the depth of a neighbouring pixel's ray."""
        points, normal = np.asarray(points, dtype=np.float64), np.asarray(normal, dtype=np.float64)
        z = points[:, 2]
        axial = self.depth_sigma(z, fx) * np.abs(points @ normal) / z
        lateral = self.lateral_sigma_px * z / fx * np.hypot(normal[0], normal[1])
        return np.hypot(axial, lateral)

    def height_lifted(self, points, normal, share: float, fx: float = 525.0) -> np.ndarray:
        """(N,) the height (metres) over a plane of unit ``normal`` (3,) that the noise lifts ``share`` (0, 1) of
        the plane's own points (N, 3) past: a one-sided Gaussian bar of :meth:`height_sigma`."""
        return -ndtri(share) * self.height_sigma(points, normal, fx)

    def quantisation_step(self, z, fx: float = 525.0) -> np.ndarray:
        """Depth step (metres) between neighbouring disparity levels at depth z."""
        z = np.asarray(z, dtype=np.float64)
        return z**2 * self.disparity_step_px / (fx * abs(self.baseline))


KINECT_V1 = KinectNoise()
"""The default Kinect v1 noise model."""


def grazing_angles(depth, intrinsics: CameraIntrinsics) -> np.ndarray:
    """(H, W) angle in degrees between each pixel's view ray and the surface normal.

    Normals come from the depth image: along each image axis the one-sided difference with
    the smaller depth change is used, so normals do not smear across depth edges. NaN where
    a pixel or both neighbours along an axis have no return.
    """
    depth, valid = checked_depth(depth, intrinsics)
    points = intrinsics.pixel_rays() * np.where(valid, depth, np.nan)[..., None]
    tangents = []
    for axis in (1, 0):
        fwd = np.full_like(points, np.nan)
        if axis == 1:
            fwd[:, :-1] = points[:, 1:] - points[:, :-1]
        else:
            fwd[:-1] = points[1:] - points[:-1]
        bwd = np.roll(fwd, 1, axis=axis)
        if axis == 1:
            bwd[:, 0] = np.nan
        else:
            bwd[0] = np.nan
        use_fwd = np.nan_to_num(np.abs(fwd[..., 2]), nan=np.inf) <= np.nan_to_num(
            np.abs(bwd[..., 2]), nan=np.inf
        )
        tangents.append(np.where(use_fwd[..., None], fwd, bwd))
    normals = np.cross(tangents[0], tangents[1])
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.abs(np.einsum("hwc,hwc->hw", normals, points)) / (
            np.linalg.norm(normals, axis=2) * np.linalg.norm(points, axis=2)
        )
    return np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))


def edge_mask(depth, jump: float) -> np.ndarray:
    """(H, W) bool: pixels with a return whose 4-neighbour differs by more than jump metres
    or has no return (the image border does not count)."""
    depth = np.asarray(depth, dtype=np.float64)
    z = np.where(np.isfinite(depth) & (depth > 0), depth, np.inf)
    mask = np.zeros(z.shape, dtype=bool)
    with np.errstate(invalid="ignore"):
        dx = ~(np.abs(z[:, 1:] - z[:, :-1]) <= jump)
        dy = ~(np.abs(z[1:] - z[:-1]) <= jump)
    mask[:, 1:] |= dx
    mask[:, :-1] |= dx
    mask[1:] |= dy
    mask[:-1] |= dy
    return mask & np.isfinite(z)


def shadow_mask(depth, intrinsics: CameraIntrinsics, baseline: float = 0.075) -> np.ndarray:
    """(H, W) bool: pixels the projector (baseline metres along +x) cannot light.

    A pixel u seen at depth z meets the projector at column u - f b / z; it is shadowed when
    a pixel further towards the projector maps to the same or a smaller projector column,
    i.e. something nearer blocks the projector's ray.
    """
    depth, valid = checked_depth(depth, intrinsics)
    if baseline < 0:
        return shadow_mask(depth[:, ::-1], intrinsics, -baseline)[:, ::-1]
    columns = np.arange(intrinsics.width, dtype=np.float64)[None, :]
    with np.errstate(divide="ignore"):
        proj = np.where(valid, columns - intrinsics.fx * baseline / depth, np.inf)
    suffix_min = np.minimum.accumulate(proj[:, ::-1], axis=1)[:, ::-1]
    blocker = np.full_like(proj, np.inf)
    blocker[:, :-1] = suffix_min[:, 1:]
    return valid & (proj > blocker + 1e-9)


def kinect_noise_with_source(
    depth, intrinsics: CameraIntrinsics, rng: np.random.Generator, noise: KinectNoise = KINECT_V1
) -> tuple[np.ndarray, np.ndarray]:
    """Apply the noise model and say where each output pixel's depth came from.

    Args:
        depth: (H, W) clean depth in metres, 0 or NaN where there is no return.
        intrinsics: the camera (fx is the f in the disparity f * baseline / z).
        rng: the only source of randomness.
        noise: the model parameters.

    Returns:
        (noisy, source): noisy (H, W) float64 depth in metres, 0 where dropped; source
        (H, W) int64 flat index (v * W + u) of the clean pixel each output pixel samples,
        so per-pixel labels can follow the lateral jitter (labels.ravel()[source]).
    """
    depth, valid = checked_depth(depth, intrinsics)
    h, w = depth.shape
    drop_prob = np.zeros((h, w))
    dropped = ~valid
    if noise.shadow:
        dropped = dropped | shadow_mask(depth, intrinsics, noise.baseline)
    if noise.grazing:
        angle = np.nan_to_num(grazing_angles(depth, intrinsics), nan=0.0)
        ramp = (angle - noise.grazing_start_deg) / (noise.grazing_end_deg - noise.grazing_start_deg)
        drop_prob = noise.grazing_max_prob * np.clip(ramp, 0.0, 1.0)
    if noise.edges:
        edge_prob = np.where(edge_mask(depth, noise.edge_jump), noise.edge_prob, 0.0)
        drop_prob = 1.0 - (1.0 - drop_prob) * (1.0 - edge_prob)

    rows, cols = np.mgrid[0:h, 0:w]
    if noise.lateral:
        rows = np.clip(rows + np.rint(rng.normal(0.0, noise.lateral_sigma_px, (h, w))), 0, h - 1)
        cols = np.clip(cols + np.rint(rng.normal(0.0, noise.lateral_sigma_px, (h, w))), 0, w - 1)
    source = (rows * w + cols).astype(np.int64)
    z = depth.ravel()[source]
    dropped = dropped.ravel()[source]
    drop_prob = drop_prob.ravel()[source]

    if noise.axial:
        z = z + noise.axial_sigma(z) * rng.standard_normal((h, w))
    if noise.quantise:
        fb = intrinsics.fx * abs(noise.baseline)
        step = noise.disparity_step_px
        with np.errstate(divide="ignore", invalid="ignore"):
            disparity = np.rint(fb / np.where(z > 0, z, np.nan) / step) * step
            z = fb / disparity
    if noise.edges or noise.grazing:
        dropped = dropped | (rng.random((h, w)) < drop_prob)
    ok = ~dropped & np.isfinite(z) & (z > 0)
    if noise.depth_range is not None:
        ok &= (z >= noise.depth_range[0]) & (z <= noise.depth_range[1])
    return np.where(ok, z, 0.0), source


def apply_kinect_noise(
    depth, intrinsics: CameraIntrinsics, rng: np.random.Generator, noise: KinectNoise = KINECT_V1
) -> np.ndarray:
    """Return a new (H, W) depth image (metres) with Kinect v1 noise, 0 where dropped.

    See kinect_noise_with_source for the arguments.
    """
    return kinect_noise_with_source(depth, intrinsics, rng, noise)[0]
