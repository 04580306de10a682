"""Where the tests find the repository's folders and the shared development data."""

from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
BENCHMARKS = REPO / "benchmarks"
SHARED = REPO.parent / "shared"  # real CAD and Kinect clouds beside the checkout; tests skip without them
