"""Typed, frozen values passed between the stages of the pipeline.

Units are metres; clouds live in the sensor frame with OpenCV axes (x right,
y down, z forward). Arrays are copied on construction and made read-only, so a
value cannot change under a later stage.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from functools import cached_property

import numpy as np

from psorr.errors import InvalidInputError


def _frozen_array(value, name: str, dtype, shape_tail: tuple[int, ...], n: int | None = None):
    if getattr(value, "dtype", np.dtype(float)).kind in "cb":  # numpy would drop an imaginary part, or take True as 1
        raise InvalidInputError(f"{name} must be real numbers, got a {value.dtype.name} array")
    try:
        array = np.array(value, dtype=dtype, copy=True)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"{name} must be convertible to a {np.dtype(dtype).name} array: {exc}") from None
    expected_ndim = 1 + len(shape_tail)
    if array.ndim != expected_ndim or array.shape[1:] != shape_tail:
        want = "(N" + "".join(f", {s}" for s in shape_tail) + ")"
        raise InvalidInputError(f"{name} must have shape {want}, got {array.shape}")
    if n is not None and array.shape[0] != n:
        raise InvalidInputError(f"{name} has {array.shape[0]} rows but the cloud has {n} points")
    array.setflags(write=False)
    return array


def _integer_labels(value, n: int) -> np.ndarray:
    """``value`` as read-only (N,) int64 labels, refusing values that int64 would change (0.5, 2**64 - 1)."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise InvalidInputError(f"labels must be convertible to an int64 array: {exc}") from None
    rule = "labels must be whole numbers that fit int64, -1 for no label"
    if raw.dtype.kind == "f":
        fractional = ~(raw == np.rint(raw))  # NaN too
        if fractional.any():
            raise InvalidInputError(f"labels hold {int(fractional.sum())} non-integer values (first: "
                                    f"{raw[fractional].flat[0]:g}); {rule}")
    # int64 holds [-2**63, 2**63): floats that large, and uint64 above it, would wrap.
    if raw.dtype.kind in "fu" and raw.size and (raw.max() >= 2**63 or raw.min() < -(2**63)):
        raise InvalidInputError(f"labels hold values from {raw.min()} to {raw.max()}, beyond int64; {rule}")
    return _frozen_array(raw, "labels", np.int64, (), n)


@dataclass(frozen=True, eq=False)
class PointCloud:
    """A cloud of N points, optionally organised as a height x width image.

    Attributes:
        points: (N, 3) float64 metres. Rows may be NaN (invalid pixels of an
            organised cloud); they keep their place so that per-point outputs
            line up with the file.
        normals: optional (N, 3) float64 unit vectors.
        colors: optional (N, 3) float64 RGB in [0, 1].
        labels: optional (N,) int64 per-point labels (for example ground truth).
        width, height: the organised image size, or None for an unorganised cloud.
    """

    points: np.ndarray
    normals: np.ndarray | None = None
    colors: np.ndarray | None = None
    labels: np.ndarray | None = None
    width: int | None = None
    height: int | None = None

    def __post_init__(self):
        points = _frozen_array(self.points, "points", np.float64, (3,))
        n = len(points)
        object.__setattr__(self, "points", points)
        if self.normals is not None:
            object.__setattr__(self, "normals", _frozen_array(self.normals, "normals", np.float64, (3,), n))
        if self.colors is not None:
            colors = _frozen_array(self.colors, "colors", np.float64, (3,), n)
            finite = colors[np.isfinite(colors)]
            if finite.size and (finite.min() < 0.0 or finite.max() > 1.0):
                raise InvalidInputError("colors must be RGB floats in [0, 1]; divide 8-bit colours by 255")
            object.__setattr__(self, "colors", colors)
        if self.labels is not None:
            object.__setattr__(self, "labels", _integer_labels(self.labels, n))
        if (self.width is None) != (self.height is None):
            raise InvalidInputError("give both width and height for an organised cloud, or neither")
        for name in ("width", "height"):
            size = getattr(self, name)
            if size is not None and (isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 1):
                raise InvalidInputError(f"PointCloud.{name} must be a whole number >= 1 (or None for an "
                                        f"unorganised cloud), got {size!r}")
        if self.width is not None and self.width * self.height != n:
            raise InvalidInputError(
                f"an organised cloud of {self.width}x{self.height} needs {self.width * self.height} points, got {n}"
            )

    def __len__(self) -> int:
        return len(self.points)

    @property
    def is_organised(self) -> bool:
        return self.width is not None

    @cached_property
    def valid_mask(self) -> np.ndarray:
        """(N,) bool: True where the point is finite (computed once; read-only)."""
        # Per column: np.isfinite(points).all(axis=1) is several times slower on (N, 3).
        p = self.points
        mask = np.isfinite(p[:, 0]) & np.isfinite(p[:, 1]) & np.isfinite(p[:, 2])
        mask.setflags(write=False)
        return mask


class PrimitiveKind(StrEnum):
    """The shape families a cloud is decomposed into."""

    PLANE = "plane"
    CYLINDER = "cylinder"

    @property
    def n_params(self) -> int:
        """Descriptor length used by the MDL fitness."""
        return {PrimitiveKind.PLANE: 4, PrimitiveKind.CYLINDER: 7}[self]


@dataclass(frozen=True, eq=False)
class OrientedBox:
    """A box with centre (3,), rotation (3, 3) whose columns are its axes in the
    cloud frame, and extent (3,) full side lengths in metres."""

    center: np.ndarray
    rotation: np.ndarray
    extent: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "center", _frozen_array(np.ravel(self.center), "center", np.float64, ()))
        object.__setattr__(self, "extent", _frozen_array(np.ravel(self.extent), "extent", np.float64, ()))
        rotation = np.array(self.rotation, dtype=np.float64)
        if rotation.shape != (3, 3) or self.center.shape != (3,) or self.extent.shape != (3,):
            raise InvalidInputError("an OrientedBox needs center (3,), rotation (3, 3) and extent (3,)")
        rotation.setflags(write=False)
        object.__setattr__(self, "rotation", rotation)

    @property
    def volume(self) -> float:
        return float(np.prod(self.extent))

    def corners(self) -> np.ndarray:
        """(8, 3) corner points in the cloud frame."""
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
        return self.center + (signs * self.extent / 2.0) @ self.rotation.T


@dataclass(frozen=True, eq=False)
class Primitive:
    """One shape found in a cloud.

    Attributes:
        kind: plane or cylinder.
        params: plane (nx, ny, nz, d) with n.x + d = 0 and n towards the sensor;
            cylinder (px, py, pz, ax, ay, az, r): a point on the axis, the unit
            axis direction and the radius, all in metres.
        inliers: (M,) int64 indices into the decomposed cloud's points.
        centroid: (3,) mean of the inlier points.
        box: the minimum-volume oriented bounding box of the inliers.
    """

    kind: PrimitiveKind
    params: tuple[float, ...]
    inliers: np.ndarray
    centroid: np.ndarray
    box: OrientedBox

    def __post_init__(self):
        kind = PrimitiveKind(self.kind)
        object.__setattr__(self, "kind", kind)
        params = tuple(float(p) for p in self.params)
        if len(params) != kind.n_params:
            raise InvalidInputError(f"a {kind.value} has {kind.n_params} params, got {len(params)}")
        object.__setattr__(self, "params", params)
        object.__setattr__(self, "inliers", _frozen_array(self.inliers, "inliers", np.int64, ()))
        object.__setattr__(self, "centroid", _frozen_array(np.ravel(self.centroid), "centroid", np.float64, ()))

    def _require(self, kind: PrimitiveKind, what: str):
        if self.kind is not kind:
            raise InvalidInputError(f"{what} is defined for a {kind.value}, this primitive is a {self.kind.value}")

    @property
    def normal(self) -> np.ndarray:
        """(3,) unit normal of a plane, pointing towards the sensor."""
        self._require(PrimitiveKind.PLANE, "normal")
        return np.array(self.params[:3])

    @property
    def offset(self) -> float:
        """d of the plane n.x + d = 0, metres."""
        self._require(PrimitiveKind.PLANE, "offset")
        return self.params[3]

    @property
    def axis_point(self) -> np.ndarray:
        self._require(PrimitiveKind.CYLINDER, "axis_point")
        return np.array(self.params[:3])

    @property
    def axis(self) -> np.ndarray:
        """(3,) unit direction of a cylinder's axis."""
        self._require(PrimitiveKind.CYLINDER, "axis")
        return np.array(self.params[3:6])

    @property
    def radius(self) -> float:
        self._require(PrimitiveKind.CYLINDER, "radius")
        return self.params[6]

    @property
    def n_points(self) -> int:
        return len(self.inliers)


@dataclass(frozen=True, eq=False)
class PrimitiveShapeGraph:
    """Primitives as nodes; an edge (i, j), i < j, joins primitives whose inlier
    points come within the adjacency distance of each other."""

    primitives: tuple[Primitive, ...]
    edges: tuple[tuple[int, int], ...] = field(default_factory=tuple)

    def __post_init__(self):
        primitives = tuple(self.primitives)
        n = len(primitives)
        edges = sorted({(min(int(i), int(j)), max(int(i), int(j))) for i, j in self.edges})
        for i, j in edges:
            if i == j or not (0 <= i < n and 0 <= j < n):
                raise InvalidInputError(f"edge ({i}, {j}) does not join two of the {n} primitives")
        object.__setattr__(self, "primitives", primitives)
        object.__setattr__(self, "edges", tuple(edges))

    def __len__(self) -> int:
        return len(self.primitives)

    def neighbours(self, index: int) -> list[int]:
        return sorted({j for i, j in self.edges if i == index} | {i for i, j in self.edges if j == index})


def random_generator(rng, caller: str) -> np.random.Generator:
    """``rng`` if it is a numpy Generator, a fresh ``default_rng(0)`` if it is None; anything else (a
    seed, the legacy RandomState) is refused, naming ``caller`` and the fix."""
    if rng is None:
        return np.random.default_rng(0)
    if not isinstance(rng, np.random.Generator):
        raise InvalidInputError(f"{caller} takes rng=np.random.default_rng(seed), a numpy Generator; got "
                                f"{type(rng).__name__} {rng!r:.40}")
    return rng


def _rigid_pose(value, name: str) -> np.ndarray:
    """``value`` as a read-only (4, 4) float array, checked to be a rigid transform."""
    pose = np.array(value, dtype=np.float64)
    if pose.shape != (4, 4) or not np.isfinite(pose).all():
        raise InvalidInputError(f"Detection.{name} must be a finite (4, 4) array, got shape {pose.shape}")
    if not np.allclose(pose[3], (0, 0, 0, 1)) or not np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-6):
        raise InvalidInputError(f"Detection.{name} must be a rigid transform (orthonormal rotation, last row 0 0 0 1)")
    pose.setflags(write=False)
    return pose


@dataclass(frozen=True, eq=False)
class Detection:
    """One recognised workpiece instance.

    Attributes:
        model: the model's name (its mesh file stem).
        T_cloud_model: (4, 4) pose mapping model coordinates (metres) into the cloud's frame.
        score: confidence in [0, 1].
        visible_fraction: the share of the model's surface samples that the
            sensor saw (in front of nothing, matched by a measured point), in [0, 1].
        alternatives: poses (4, 4) of the same model, each the pose turned by one of the model's
            near-symmetries (a tray turned end for end), that the view could not rule out: the
            small features that tell them apart were hidden or seen edge-on. Empty when the view
            settled it, or the model has no near-symmetry. A robot can look again from elsewhere
            (``Recognizer.refine`` judges given poses in a new view).
    """

    model: str
    T_cloud_model: np.ndarray
    score: float
    visible_fraction: float = 0.0
    alternatives: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "T_cloud_model", _rigid_pose(self.T_cloud_model, "T_cloud_model"))
        object.__setattr__(self, "alternatives", tuple(_rigid_pose(P, f"alternatives[{k}]")
                                                       for k, P in enumerate(self.alternatives)))
        for name in ("score", "visible_fraction"):
            value = float(getattr(self, name))
            if not 0.0 <= value <= 1.0:
                raise InvalidInputError(f"Detection.{name} must lie in [0, 1], got {value}")
            object.__setattr__(self, name, value)
