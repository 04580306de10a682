"""Parts made from a user's own mesh: everything the cell needs derived from the mesh alone.

:mod:`~sim.parts.collision` decomposes a mesh into convex collision hulls (CoACD, in a subprocess);
:mod:`~sim.parts.grasp_synthesis` finds parallel-jaw grasps on it. Each result is cached under the
training cache's folder by the mesh's hash, so a part costs its synthesis once.
"""

import sys


def tell(line: str) -> None:
    """The default ``progress`` of a slow first derivation: one line on stderr, since stdout carries the
    results (``psorr-sim ... --json`` prints exactly one line there)."""
    print(line, file=sys.stderr, flush=True)
