"""psorr.acceptance.claims: which detection keeps pixels that two explain."""

import numpy as np

from psorr.acceptance.claims import PixelClaims
from psorr.types import Detection


def _detection(name: str, score: float) -> Detection:
    return Detection(name, np.eye(4), score)


def test_a_candidate_on_free_pixels_displaces_no_one():
    claims = PixelClaims(100, max_shared=0.3)
    claims.add(_detection("hub", 0.8), np.arange(0, 20), 0.8, [])
    # 2 of its 10 blocks are held: within the share two neighbours may have in common.
    assert claims.rivals(np.arange(18, 28), 0.1) == []


def test_a_worse_candidate_on_held_pixels_is_dropped():
    claims = PixelClaims(100, max_shared=0.3)
    claims.add(_detection("board", 0.8), np.arange(0, 20), 0.8, [])
    assert claims.rivals(np.arange(5, 15), 0.5) is None
    assert claims.rivals(np.arange(5, 15), 0.8) is None  # a tie keeps the one found first


def test_a_better_candidate_displaces_the_detection_found_first():
    claims = PixelClaims(100, max_shared=0.3)
    bracket, hub = _detection("bracket", 0.48), _detection("hub", 0.7)
    claims.add(bracket, np.arange(0, 20), 0.48, [])
    claims.add(hub, np.arange(40, 60), 0.7, [])
    board = _detection("board", 0.81)
    displaced = claims.rivals(np.arange(0, 15), 0.81)
    assert displaced == [0]
    claims.add(board, np.arange(0, 15), 0.81, displaced)
    assert claims.detections == [hub, board]
    # The bracket's blocks the board does not explain are free again; the board's are its own.
    assert claims.rivals(np.arange(15, 20), 0.01) == []
    assert claims.rivals(np.arange(0, 15), 0.5) is None


def test_only_as_many_rivals_as_needed_are_displaced():
    claims = PixelClaims(100, max_shared=0.3)
    claims.add(_detection("a", 0.5), np.arange(0, 8), 0.5, [])
    claims.add(_detection("b", 0.9), np.arange(8, 18), 0.9, [])
    # 10 blocks: 8 held by a, 2 by b. Displacing a leaves 0.2 held, so b (who outscores it, and of whose
    # own blocks the candidate covers only 0.2) stays.
    assert claims.rivals(np.arange(0, 10), 0.6) == [0]


def test_a_candidate_that_covers_a_detection_conflicts_with_it():
    # A bracket accepted on a chassis' wall holds 12 of the chassis' 60 blocks (0.2, under the share),
    # but the chassis covers all of the bracket's: both cannot be right. The one that explains more
    # (blocks weighted by score) stays: 60 x 0.3 = 18 against the bracket's 12 x 0.67 = 8.
    claims = PixelClaims(100, max_shared=0.3)
    bracket = _detection("bracket", 0.67)
    claims.add(bracket, np.arange(0, 12), 0.67, [])
    assert claims.rivals(np.arange(0, 60), 0.3) == [0]
    assert claims.rivals(np.arange(0, 60), 0.13) is None  # 7.8 blocks' worth: the bracket explains more
    # A neighbour that covers under the share of the bracket's blocks is no rival.
    assert claims.rivals(np.arange(9, 69), 0.01) == []
    chassis = _detection("chassis", 0.3)
    claims.add(chassis, np.arange(0, 60), 0.3, [0])
    assert claims.detections == [chassis]


def test_a_clean_candidate_that_explains_clearly_more_displaces_what_it_covers():
    # A chassis 37% in view under an arm scores by what it shows (0.36) but is clean (0.97 of its checked
    # points not seen through); a bracket posed on it scored 0.70, 0.87 clean. By score, and by score
    # times blocks (0.70 x 99 = 69 against 0.36 x 139 = 50), the bracket kept it out.
    claims = PixelClaims(300, max_shared=0.3)
    bracket = _detection("bracket", 0.70)
    claims.add(bracket, np.arange(0, 99), 0.70, [], clean=0.87)
    chassis_blocks = np.arange(34, 173)  # 139 blocks, 65 of them the bracket's
    assert claims.rivals(chassis_blocks, 0.36) is None  # no cleanliness given: judged by score as before
    assert claims.rivals(chassis_blocks, 0.36, clean=0.97) == [0]  # 135 clean blocks' worth against 86
    # Not clearly more (under 1.25 times the bracket's 86): the bracket stays.
    assert claims.rivals(np.arange(34, 133), 0.36, clean=0.97) is None  # 96 against 86


def test_a_near_tie_in_clean_blocks_is_settled_by_score():
    # Two poses of one part, nearly the same blocks and both clean: the better scored one, found first, stays.
    claims = PixelClaims(300, max_shared=0.3)
    claims.add(_detection("u_channel", 0.644), np.arange(0, 149), 0.644, [], clean=0.962)
    assert claims.rivals(np.arange(3, 157), 0.625, clean=0.938) is None


class _Judge:
    """Prefers the named model whatever the scores: stands in for RenderJudge's verdict."""

    def __init__(self, preferred: str | None):
        self.preferred = preferred

    def prefer(self, model_a, T_a, model_b, T_b) -> int:
        if self.preferred is None:
            return 0
        return 1 if model_a == self.preferred else -1 if model_b == self.preferred else 0


def test_the_judges_verdict_comes_before_the_scores_and_a_tie_leaves_them_to_decide():
    knob, clip = _detection("knob", 0.81), _detection("clip", 0.92)
    # The clip shows more of itself, but the judge finds the knob explains the depth better: it stays.
    claims = PixelClaims(100, max_shared=0.3, judge=_Judge("knob"))
    claims.add(knob, np.arange(0, 20), 0.81, [])
    assert claims.rivals(np.arange(5, 15), 0.92, candidate=clip) is None
    # The other way round, the knob found second displaces the clip it scores below.
    claims = PixelClaims(100, max_shared=0.3, judge=_Judge("knob"))
    claims.add(clip, np.arange(5, 15), 0.92, [])
    assert claims.rivals(np.arange(0, 20), 0.81, candidate=knob) == [0]
    # No verdict: the higher score wins, as without a judge.
    claims = PixelClaims(100, max_shared=0.3, judge=_Judge(None))
    claims.add(knob, np.arange(0, 20), 0.81, [])
    assert claims.rivals(np.arange(5, 15), 0.92, candidate=clip) == [0]


def test_a_displaced_detection_is_reported_with_its_reason_whichever_search_found_it():
    from psorr.viz.observer import RecognitionObserver, observed_by

    class Spy(RecognitionObserver):
        def __init__(self):
            self.rejected_models = []

        def rejected(self, model, T_cloud_model, reason):
            self.rejected_models.append((model, reason))

    claims = PixelClaims(100, max_shared=0.3)
    claims.add(_detection("bracket", 0.48), np.arange(0, 20), 0.48, [])  # as if from an earlier round
    spy = Spy()
    with observed_by(spy):
        displaced = claims.rivals(np.arange(0, 15), 0.81)
        claims.add(_detection("board", 0.81), np.arange(0, 15), 0.81, displaced)
    assert spy.rejected_models == [("bracket", "displaced by a better detection")]


def test_two_models_the_judge_cannot_tell_apart_on_the_same_pixels_report_each_other_as_rivals():
    clip, variant = _detection("clip", 0.85), _detection("clip_for_sleeve", 0.83)
    claims = PixelClaims(100, max_shared=0.3, judge=_Judge(None))
    claims.add(clip, np.arange(0, 20), 0.85, [])
    assert claims.rivals(np.arange(0, 20), 0.83, candidate=variant) is None  # the score keeps the clip
    claims.lost_tie(variant, 0.83)
    [reported] = claims.reported()
    assert reported.model == "clip" and [(r.model, r.score) for r in reported.rivals] == [("clip_for_sleeve", 0.83)]
    assert claims.detections == [clip]  # what the search works with is unchanged
    # The other way round, the variant found second with the higher score displaces the clip, and names it.
    claims = PixelClaims(100, max_shared=0.3, judge=_Judge(None))
    claims.add(variant, np.arange(0, 20), 0.83, [])
    displaced = claims.rivals(np.arange(0, 20), 0.85, candidate=clip)
    claims.add(clip, np.arange(0, 20), 0.85, displaced)
    [reported] = claims.reported()
    assert reported.model == "clip" and [r.model for r in reported.rivals] == ["clip_for_sleeve"]


def test_no_rival_where_the_judge_decides_or_the_pixels_are_not_the_same():
    clip, variant = _detection("clip", 0.85), _detection("clip_for_sleeve", 0.83)
    # The judge prefers the clip: the view told them apart.
    claims = PixelClaims(100, max_shared=0.3, judge=_Judge("clip"))
    claims.add(clip, np.arange(0, 20), 0.85, [])
    assert claims.rivals(np.arange(0, 20), 0.83, candidate=variant) is None
    claims.lost_tie(variant, 0.83)
    assert claims.reported()[0].rivals == ()
    # A small part whose pixels lie inside a large one's is no alternative to it, whoever keeps them.
    claims = PixelClaims(100, max_shared=0.3, judge=_Judge(None))
    claims.add(_detection("board", 0.9), np.arange(0, 40), 0.9, [])
    assert claims.rivals(np.arange(0, 10), 0.8, candidate=variant) is None
    claims.lost_tie(variant, 0.8)
    assert claims.reported()[0].rivals == ()
    # Two poses of one model are its near-symmetric twins' business (Detection.alternatives), not rivals.
    claims = PixelClaims(100, max_shared=0.3, judge=_Judge(None))
    claims.add(clip, np.arange(0, 20), 0.85, [])
    assert claims.rivals(np.arange(0, 20), 0.8, candidate=_detection("clip", 0.8)) is None
    claims.lost_tie(_detection("clip", 0.8), 0.8)
    assert claims.reported()[0].rivals == ()
