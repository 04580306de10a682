"""The resting-pose candidates accepted patch by patch: does every patch standing on the table give a part?

A lone part at rest, or a few apart, is found by the resting poses alone, and then the scene need not be
decomposed (docs/decisions/0066-resting-poses-first.md). Whether that holds is known patch by patch: the
first patch no part explains settles it, and the patches after it are not fitted.
"""

from __future__ import annotations

from psorr.acceptance.accept import Acceptance
from psorr.acceptance.claims import PixelClaims
from psorr.hypotheses.candidates import CandidateSet
from psorr.verification.scene_view import SceneView


def every_patch_found(acceptance: Acceptance, view: SceneView, rests: CandidateSet, claims: PixelClaims) -> bool:
    """Accept ``rests`` (the outline's candidates, each with its patch as ``region``) into ``claims``, one patch
    at a time. True when every patch the outline searched gives a detection; the first patch that does not
    ends it. A patch with no candidate at all ends it before anything is fitted. A detection whose
    near-symmetric twin the view leaves open counts: acceptance has already judged both twins on the view,
    and the full search, which sees the same view, does not tell them apart (decision 0066)."""
    regions = dict.fromkeys(c.region for c in rests.candidates)
    if not regions or len(regions) < rests.regions:
        return False
    for region in regions:
        patch = tuple(c for c in rests.candidates if c.region == region)
        found = acceptance(view, patch, claims, fine_starts=True)
        if not found:
            return False
    return True
