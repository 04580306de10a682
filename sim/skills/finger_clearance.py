"""Where the gripper's fingers are, in the tool's frame, and whether they fit a fixture's pocket.

A part is let go just above its seat only when everything on the fingers (the pads and the fingers behind
them) stays inside the fixture's pocket, closed on the part and eased open to let it go; otherwise the
fingers would come down on the pocket's walls, or be pinned against them as they open, and the part is
let go from above the walls instead. The fingers, opened wide on the way down to a grasp, must not land
on a fixture or the tote beside the part either: they would hold the arm up short of the grasp, and the
pads would close off centre. Read from the robot's own model and the cell's furniture: nothing here is
simulator truth.
"""

from __future__ import annotations

import weakref

import mujoco
import numpy as np

from sim.control.cell import ArmCell

PRESHAPE = 0.006  # m the pads stand open past the grasp's width just before they close on the part
RELEASE_EASE = 0.012  # m the pads open past the grasp's width to let go: enough to free the part, no fling
WALL_CLEARANCE = 0.002  # m between the fingers' lower ends and the fixture walls' tops at release

_AFFINE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # cell -> corners closed, and per metre open
_SIGNS = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], dtype=float)


def finger_corners(cell: ArmCell, opening: float) -> np.ndarray:
    """(8 G, 3) corners of the bounding boxes of the fingers' G collision geoms (pads included) in the tool
    frame (m; z along the approach), with the pads ``opening`` m apart."""
    if cell not in _AFFINE:
        closed = _corners_at(cell, 0.0)
        _AFFINE[cell] = (closed, _corners_at(cell, 1.0) - closed)
    closed, per_metre = _AFFINE[cell]
    return closed + opening * per_metre  # the fingers slide: their corners move in proportion


def _corners_at(cell: ArmCell, opening: float) -> np.ndarray:
    model, cfg = cell.model, cell.cfg
    data = cell.world.kinematics(_opened(cell, model.key(cfg.home_key).qpos, opening))
    tool = model.site(cfg.tool_site).id
    R_tool, p_tool = data.site_xmat[tool].reshape(3, 3), data.site_xpos[tool]
    corners = []
    for g in sorted(cell.finger_geoms):
        if model.geom_contype[g] == 0 and model.geom_conaffinity[g] == 0:
            continue  # visual only
        centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
        local = centre + _SIGNS * half
        world = local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]
        corners.append((world - p_tool) @ R_tool)
    return np.concatenate(corners)


def finger_reach(cell: ArmCell, opening: float) -> float:
    """How far (m) the fingers reach beyond the tool site along the approach, ``opening`` m apart."""
    return float(finger_corners(cell, opening)[:, 2].max())


def fingers_clear_fixture(cell: ArmCell, info, T_fix_tool: np.ndarray, width: float) -> bool:
    """Whether the fingers, closed to ``width`` around the seated part and then eased open by
    ``RELEASE_EASE``, stay inside the fixture's pocket wherever they are lower than its walls' tops;
    ``T_fix_tool`` is the tool pose in the fixture's frame. The pocket is convex and the fingers move
    straight out, so the two ends of the opening bound every position between them."""
    cfg = cell.world.config
    lo = info.bounds()[0, :2] - cfg.fixture_clearance
    hi = info.bounds()[1, :2] + cfg.fixture_clearance
    for opening in (width, width + RELEASE_EASE):
        pts = finger_corners(cell, opening) @ T_fix_tool[:3, :3].T + T_fix_tool[:3, 3]
        low = pts[:, 2] < cfg.fixture_wall[1] + WALL_CLEARANCE
        if np.any(low & np.any((pts[:, :2] < lo) | (pts[:, :2] > hi), axis=1)):
            return False
    return True


def approach_opening(cell: ArmCell, q_grasp: np.ndarray, width: float) -> tuple[float | None, str]:
    """How far (m) to open the pads on the way down to a grasp ``width`` m wide with the arm ending at
    ``q_grasp`` (nq,): the gripper's widest, which forgives the most pose error, or else just past the
    grasp's width (``PRESHAPE``) when wide open the fingers would land on a fixture or the tote beside the
    part; (None, why) when they would either way."""
    widest = cell.world.arm.gripper_open
    why = ""
    for opening in (widest, min(widest, width + PRESHAPE)):
        why = fingers_on_furniture(cell, q_grasp, opening)
        if not why:
            return opening, ""
    return None, why


def fingers_on_furniture(cell: ArmCell, q: np.ndarray, opening: float) -> str:
    """Which fixture or tote the fingers, ``opening`` m apart, would touch with the arm at ``q`` (nq,), or "".
    Unlike a neighbouring part, these never move out of the way."""
    model, world = cell.model, cell.world
    furniture = {model.body(name).id for name in world.place_bodies}
    data = world.kinematics(_opened(cell, q, opening))
    mujoco.mj_collision(model, data)
    for contact in data.contact[: data.ncon]:
        for mine, other in ((contact.geom1, contact.geom2), (contact.geom2, contact.geom1)):
            if contact.dist < 0 and mine in cell.finger_geoms and model.geom_bodyid[other] in furniture:
                return f"the fingers would land on {model.body(model.geom_bodyid[other]).name}"
    return ""


def _opened(cell: ArmCell, q: np.ndarray, opening: float) -> np.ndarray:
    """A copy of ``q`` (nq,) with the pads ``opening`` m apart: a finger joint is its pad's distance from the tool."""
    q = q.copy()
    for joint in cell.cfg.finger_joints:
        q[cell.model.joint(joint).qposadr[0]] = opening / 2.0
    return q
