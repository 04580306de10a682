"""The resting-pose trial's patch-by-patch verdict (psorr.acceptance.by_patch), with acceptance stood in for."""

import numpy as np

from psorr.acceptance.by_patch import every_patch_found
from psorr.hypotheses.candidates import Candidate, CandidateSet
from psorr.types import Detection


class _Acceptance:
    """Accepts one detection for each patch named in ``gives`` (with an open twin where ``twin``), none
    for any other, and records the patches it was asked to fit."""

    def __init__(self, gives: set[int], twin: bool = False):
        self.gives, self.twin, self.asked = gives, twin, []

    def __call__(self, view, candidates, claims, fine_starts=False):
        region = candidates[0].region
        self.asked.append(region)
        if region not in self.gives:
            return []
        return [Detection("part", np.eye(4), 0.9, alternatives=(np.eye(4),) if self.twin else ())]


def _rests(*regions: int, searched: int | None = None) -> CandidateSet:
    candidates = tuple(Candidate(0, np.eye(4), region=r) for r in regions)
    return CandidateSet(candidates, len(candidates), 0.0, len(set(regions)) if searched is None else searched)


def test_every_patch_giving_a_detection_settles_the_trial():
    assert every_patch_found(_Acceptance({0, 1}), None, _rests(0, 0, 1), None)


def test_a_detection_with_an_open_twin_still_counts_as_found():
    assert every_patch_found(_Acceptance({0}, twin=True), None, _rests(0), None)


def test_the_first_patch_without_a_detection_ends_the_trial_before_the_rest_are_fitted():
    acceptance = _Acceptance({1})
    assert not every_patch_found(acceptance, None, _rests(0, 1), None)
    assert acceptance.asked == [0]


def test_a_searched_patch_with_no_candidate_ends_the_trial_before_anything_is_fitted():
    acceptance = _Acceptance({0, 1})
    assert not every_patch_found(acceptance, None, _rests(0, searched=2), None)
    assert not every_patch_found(acceptance, None, _rests(searched=1), None)
    assert acceptance.asked == []
