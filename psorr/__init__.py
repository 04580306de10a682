"""psorr: Primitive Shape Object Recognition RANSAC.

Decompose depth clouds into planes and cylinders and their primitive shape
graph; recognise CAD-trained workpieces from it. Never imports the simulator.
The pipeline's stages live in subpackages named after them: psorr.io,
psorr.decomposition, psorr.library, psorr.hypotheses, psorr.verification,
psorr.acceptance (and psorr.sensing, psorr.synthetic for scenes); psorr.segment splits a
table-top cloud into objects by colour and distance.
"""

from psorr.acceptance.params import AcceptParams
from psorr.decomposition import DecomposeParams, Decomposition, decompose
from psorr.decomposition.detail import DetailParams
from psorr.decomposition.support_crop import SupportCropParams
from psorr.errors import CloudFileError, InvalidInputError, MissingExtraError, PsorrError
from psorr.hypotheses.orr import OrrParams
from psorr.hypotheses.outline import OutlineParams
from psorr.hypotheses.pairs import PairParams
from psorr.hypotheses.single_cylinder import SingleCylinderParams
from psorr.hypotheses.single_plane import SinglePlaneParams
from psorr.library import ModelLibrary
from psorr.recognize import Recognizer
from psorr.recognize_params import Method, Recognition, RecognitionStats, RecognizeParams
from psorr.segment import Segmentation, SegmentParams  # segment() itself: psorr.segment.segment
from psorr.types import (
    Detection,
    DetectionColour,
    OrientedBox,
    PointCloud,
    Primitive,
    PrimitiveKind,
    PrimitiveShapeGraph,
    Rival,
    UnfixedTurn,
)

__all__ = [
    "AcceptParams",
    "CloudFileError",
    "DecomposeParams",
    "Decomposition",
    "Detection",
    "DetectionColour",
    "DetailParams",
    "InvalidInputError",
    "Method",
    "MissingExtraError",
    "ModelLibrary",
    "OrientedBox",
    "OrrParams",
    "OutlineParams",
    "PairParams",
    "PointCloud",
    "Primitive",
    "PrimitiveKind",
    "PrimitiveShapeGraph",
    "PsorrError",
    "Recognition",
    "RecognitionStats",
    "RecognizeParams",
    "Recognizer",
    "Rival",
    "SegmentParams",
    "Segmentation",
    "SingleCylinderParams",
    "SinglePlaneParams",
    "SupportCropParams",
    "UnfixedTurn",
    "decompose",
]
__version__ = "0.1.0"
