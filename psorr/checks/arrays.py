"""Checks of the values the pipeline's typed dataclasses (:mod:`psorr.types`) are built from: arrays of
the right shape and type, copied read-only; labels int64 would not change; unit normals; rigid poses;
a numpy Generator for randomness. Each failure is an InvalidInputError that names the value and the fix.
"""

from __future__ import annotations

import numpy as np

from psorr.errors import InvalidInputError


def frozen_array(value, name: str, dtype, shape_tail: tuple[int, ...], n: int | None = None) -> np.ndarray:
    """``value`` as a read-only copy of ``dtype`` and shape (N, *shape_tail) (N = ``n`` when given), or an
    InvalidInputError naming ``name`` and the shape it must have."""
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


def integer_labels(value, n: int) -> np.ndarray:
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
    return frozen_array(raw, "labels", np.int64, (), n)


UNIT_TOLERANCE = 0.01  # loose enough for normals printed with 3 digits, far tighter than colours


def not_unit(normals: np.ndarray) -> tuple[int, int, float]:
    """Of ``normals`` (N, 3), the finite rows whose norm is off 1 by more than UNIT_TOLERANCE: (how many,
    of how many finite rows, the median norm)."""
    norms = np.linalg.norm(normals[np.isfinite(normals).all(axis=1)], axis=1)
    return int((np.abs(norms - 1.0) > UNIT_TOLERANCE).sum()), len(norms), float(np.median(norms)) if len(norms) else 1.0


def random_generator(rng, caller: str) -> np.random.Generator:
    """``rng`` if it is a numpy Generator, a fresh ``default_rng(0)`` if it is None; anything else (a
    seed, the legacy RandomState) is refused, naming ``caller`` and the fix."""
    if rng is None:
        return np.random.default_rng(0)
    if not isinstance(rng, np.random.Generator):
        raise InvalidInputError(f"{caller} takes rng=np.random.default_rng(seed), a numpy Generator; got "
                                f"{type(rng).__name__} {rng!r:.40}")
    return rng


def rigid_pose(value, name: str) -> np.ndarray:
    """``value`` as a read-only (4, 4) float array, checked to be a rigid transform."""
    pose = np.array(value, dtype=np.float64)
    if pose.shape != (4, 4) or not np.isfinite(pose).all():
        raise InvalidInputError(f"{name} must be a finite (4, 4) array, got shape {pose.shape}")
    if not np.allclose(pose[3], (0, 0, 0, 1)) or not np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-6):
        raise InvalidInputError(f"{name} must be a rigid transform (orthonormal rotation, last row 0 0 0 1)")
    pose.setflags(write=False)
    return pose


def unit_share(value, name: str) -> float:
    """``value`` as a float in [0, 1] (a score, a share); an error naming ``name`` otherwise."""
    value = float(value)
    if not 0.0 <= value <= 1.0:
        raise InvalidInputError(f"{name} must lie in [0, 1], got {value}")
    return value
