"""psorr: Primitive Shape Object Recognition RANSAC.

Decompose depth clouds into planes and cylinders and their primitive shape
graph; recognise CAD-trained workpieces from it. Never imports the simulator.
"""

from psorr.decomposition import DecomposeParams, Decomposition, decompose
from psorr.errors import CloudFileError, InvalidInputError, PsorrError
from psorr.library.models import ModelLibrary
from psorr.recognize import Recognizer
from psorr.recognize_params import RecognizeParams
from psorr.types import Detection, OrientedBox, PointCloud, Primitive, PrimitiveKind, PrimitiveShapeGraph

__all__ = [
    "CloudFileError",
    "Decomposition",
    "Detection",
    "ModelLibrary",
    "Recognizer",
    "RecognizeParams",
    "DecomposeParams",
    "InvalidInputError",
    "OrientedBox",
    "PointCloud",
    "Primitive",
    "PrimitiveKind",
    "PrimitiveShapeGraph",
    "PsorrError",
    "decompose",
]
__version__ = "0.1.0"
