"""Settings and results of recognition (psorr.recognize): one parameter object per stage, gathered in
:class:`RecognizeParams`, each with its defaults."""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

from psorr.acceptance.params import AcceptParams
from psorr.checks import params as check
from psorr.decomposition import DecomposeParams
from psorr.decomposition.detail import DetailParams
from psorr.decomposition.support_crop import SupportCropParams
from psorr.hypotheses.orr import OrrParams
from psorr.hypotheses.outline import OutlineParams
from psorr.hypotheses.pairs import PairParams
from psorr.hypotheses.psg import PsgParams
from psorr.hypotheses.single_cylinder import SingleCylinderParams
from psorr.hypotheses.single_plane import SinglePlaneParams
from psorr.sensing.kinect_noise import KINECT_V1, KinectNoise
from psorr.types import Detection, Method


@dataclass(frozen=True)
class RecognizeParams:
    """Settings of recognition, one object per stage (distances in metres):

    - ``decompose``: the scene's decomposition into planes and cylinders (PSORR and PSG);
    - ``support_crop``: what of the supporting plane is decomposed (PSORR and PSG);
    - ``detail``: the finer passes, over the decomposition's leftovers and what stands unexplained (PSORR and PSG);
    - ``pairs``: pose hypotheses from primitive pairs, screened by box verification (PSORR);
    - ``single_plane``, ``single_cylinder``: poses from one face or one long cylinder (PSORR and PSG);
    - ``outline``: poses of parts resting on the table, from the patches they raise (PSORR and PSG; on by default);
    - ``psg``: PSG matching's cliques and QPBO (``method="psg"``, and ``"auto"`` for the models of many primitives);
    - ``orr``: the ORR baseline's random point pairs;
    - ``acceptance``: ICP, the point check's bars, and settling detections by the pixels they explain;
    - ``sensor``: the depth sensor's noise model, which every noise-scaled threshold follows (the Kinect v1's;
      a noisier sensor needs its own, ``KinectNoise(sigma_base=..., sigma_quad=...)``: see docs/why-missed.md).
    """

    decompose: DecomposeParams = field(default_factory=lambda: DecomposeParams(voxel_size=0.008))
    support_crop: SupportCropParams = field(default_factory=SupportCropParams)
    detail: DetailParams = field(default_factory=DetailParams)
    pairs: PairParams = field(default_factory=PairParams)
    single_plane: SinglePlaneParams = field(default_factory=SinglePlaneParams)
    single_cylinder: SingleCylinderParams = field(default_factory=SingleCylinderParams)
    outline: OutlineParams = field(default_factory=OutlineParams)
    psg: PsgParams = field(default_factory=PsgParams)
    orr: OrrParams = field(default_factory=OrrParams)
    acceptance: AcceptParams = field(default_factory=AcceptParams)
    sensor: KinectNoise = KINECT_V1

    def __post_init__(self):
        for name, cls in (("decompose", DecomposeParams), ("support_crop", SupportCropParams),
                          ("detail", DetailParams), ("pairs", PairParams), ("single_plane", SinglePlaneParams),
                          ("single_cylinder", SingleCylinderParams), ("outline", OutlineParams), ("psg", PsgParams),
                          ("orr", OrrParams), ("acceptance", AcceptParams), ("sensor", KinectNoise)):
            check.instance(self, name, cls)

    def for_stacked_parts(self) -> RecognizeParams:
        """These settings for parts piled on one another or flush with other objects (the CLI's --stacked):
        no limit on how far a part floats over the table, and no check for a larger object around it."""
        return replace(self, acceptance=replace(self.acceptance, max_float=None, max_continued=None))


@dataclass(frozen=True)
class RecognitionStats:
    """What a recognize() call cost: ``hypotheses`` screened, verification ms per hypothesis, decomposition
    and total ms (total excludes training), and the library's training ms. With PSG, also QPBO's nodes
    (correspondences) and how many of them it left unlabelled: undecided by roof duality (their
    persistency unknown); those poses go on to acceptance too."""

    method: Method
    hypotheses: int
    verify_ms_per_hypothesis: float
    decomposition_ms: float
    total_ms: float
    train_ms: float
    qpbo_nodes: int = 0
    qpbo_unlabelled: int = 0

    @classmethod
    def of(cls, method: Method, found, start: float, train_ms: float) -> RecognitionStats:
        """The stats of a search's result ``found`` (a SearchResult) begun at ``start`` (time.perf_counter())."""
        # No hypothesis, no verification to report: the cost of screening none is no cost per hypothesis.
        per_hypothesis = found.verify_ms / found.hypotheses if found.hypotheses else 0.0
        return cls(method, found.hypotheses, per_hypothesis, found.decomposition_ms,
                   (time.perf_counter() - start) * 1e3, train_ms, found.qpbo_nodes, found.qpbo_unlabelled)


@dataclass(frozen=True)
class Recognition:
    """The detections of a recognize() call, in the order they were accepted, and its stats."""

    detections: tuple[Detection, ...]
    stats: RecognitionStats
