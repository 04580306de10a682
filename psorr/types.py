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

from psorr.checks.arrays import UNIT_TOLERANCE, frozen_array, integer_labels, not_unit, rigid_pose, unit_share
from psorr.detection_fields import DetectionColour, Rival, UnfixedTurn
from psorr.errors import InvalidInputError


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
        points = frozen_array(self.points, "points", np.float64, (3,))
        n = len(points)
        object.__setattr__(self, "points", points)
        if self.normals is not None:
            normals = frozen_array(self.normals, "normals", np.float64, (3,), n)
            off, finite, median = not_unit(normals)
            if off:  # colours or unnormalised sums taken as normals would silently spoil decomposition
                raise InvalidInputError(f"normals must be unit vectors: {off} of {finite} finite rows have a norm "
                                        f"outside 1 +- {UNIT_TOLERANCE} (median {median:.3g}); divide them by "
                                        "their norms, or pass normals=None to have them estimated")
            object.__setattr__(self, "normals", normals)
        if self.colors is not None:
            colors = frozen_array(self.colors, "colors", np.float64, (3,), n)
            finite = colors[np.isfinite(colors)]
            if finite.size and (finite.min() < 0.0 or finite.max() > 1.0):
                raise InvalidInputError("colors must be RGB floats in [0, 1]; divide 8-bit colours by 255")
            object.__setattr__(self, "colors", colors)
        if self.labels is not None:
            object.__setattr__(self, "labels", integer_labels(self.labels, n))
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


class Method(StrEnum):
    """Where recognition's hypotheses come from: PSORR's pairs of scene primitives, PSG's matched cliques of
    the primitive shape graph, ORR's random pairs of points (Papazov and Burschka's baseline), or AUTO:
    PSG's cliques for the models of many primitives, where it is the faster, and PSORR's pairs for all."""

    PSORR = "psorr"
    PSG = "psg"
    ORR = "orr"
    AUTO = "auto"


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
        object.__setattr__(self, "center", frozen_array(np.ravel(self.center), "center", np.float64, ()))
        object.__setattr__(self, "extent", frozen_array(np.ravel(self.extent), "extent", np.float64, ()))
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
        object.__setattr__(self, "inliers", frozen_array(self.inliers, "inliers", np.int64, ()))
        object.__setattr__(self, "centroid", frozen_array(np.ravel(self.centroid), "centroid", np.float64, ()))

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

    def count(self, kind: PrimitiveKind) -> int:
        """How many of the primitives are of ``kind`` (planes, say)."""
        return sum(p.kind is kind for p in self.primitives)


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
        colour: with ``Recognizer(..., use_colour=True)``, the colour of the segment it was found in;
            otherwise None.
        rivals: other models' poses over its pixels that the view could not rule out (:class:`Rival`).
        unfixed_turn: the turn about the model's near-continuous axis that nothing in view fixed
            (:class:`UnfixedTurn`), or None.
    """

    model: str
    T_cloud_model: np.ndarray
    score: float
    visible_fraction: float = 0.0
    alternatives: tuple = ()
    colour: DetectionColour | None = None
    rivals: tuple[Rival, ...] = ()
    unfixed_turn: UnfixedTurn | None = None

    def __post_init__(self):
        object.__setattr__(self, "T_cloud_model", rigid_pose(self.T_cloud_model, "Detection.T_cloud_model"))
        rivals = tuple(self.rivals)
        if not all(isinstance(r, Rival) for r in rivals):
            raise InvalidInputError("Detection.rivals holds psorr.Rival values (a model's name, pose and score)")
        object.__setattr__(self, "rivals", rivals)
        object.__setattr__(self, "alternatives", tuple(rigid_pose(P, f"Detection.alternatives[{k}]")
                                                       for k, P in enumerate(self.alternatives)))
        for name in ("score", "visible_fraction"):
            object.__setattr__(self, name, unit_share(getattr(self, name), f"Detection.{name}"))
