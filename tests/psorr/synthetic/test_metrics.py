"""Scores of segmentations against labelled objects (psorr.synthetic.metrics)."""

import numpy as np
import pytest

from psorr.synthetic.metrics import object_segment_scores


def test_object_segment_scores_on_a_hand_made_case():
    # Objects 2 (10 points) and 3 (10 points); the table (1) and no-return (0) are not objects.
    truth = np.array([2] * 10 + [3] * 10 + [1] * 5)
    # Object 2: 8 points in segment 0, 2 in segment 1 (a second segment holding a fifth: over).
    # Object 3: all in segment 1, which also holds 2 of object 2 (a sixth of it: under).
    labels = np.array([0] * 8 + [1] * 2 + [1] * 10 + [-1] * 5)
    two, three = object_segment_scores(truth, labels)
    assert (two.object_id, two.iou, two.over, two.under) == (2, 0.8, True, False)
    assert (three.object_id, three.over, three.under) == (3, False, True)
    assert three.iou == pytest.approx(10 / 12)
