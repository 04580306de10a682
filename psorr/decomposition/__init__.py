"""Primitive shape decomposition: planes and cylinders by RANSAC, alpha-expansion
graph cut and MDL merging, plus the primitive shape graph."""

from psorr.decomposition.pipeline import (
    DecomposeParams,
    Decomposition,
    DecompositionStats,
    decompose,
    inlier_threshold,
)

__all__ = ["Decomposition", "DecompositionStats", "DecomposeParams", "decompose", "inlier_threshold"]
