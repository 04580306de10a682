"""What a robot cell is built from: :class:`WorldConfig`, the parameter object of
:func:`sim.world.build_world` (which assembles the scene; this module only describes it)."""

from __future__ import annotations

from dataclasses import dataclass

from psorr.sensing.camera import CameraIntrinsics
from sim.devices.sensor import KINECT_V1_CAMERA, check_intrinsics
from sim.errors import SimInputError
from sim.parts.source import MeshPart

RESTING = ("upright", "any")
CATALOG_GRASPS = ("synthesised", "hand-written")


@dataclass(frozen=True)
class WorldConfig:
    """What to build (metres, degrees, seconds).

    Attributes:
        workpieces: names of the parts to place, each once: catalog parts
            (``psorr.synthetic.catalog.load_catalog()``) and the names of ``mesh_parts``.
        mesh_parts: parts made from the user's own meshes (:class:`sim.parts.source.MeshPart`), each named
            in ``workpieces``; everything else they need is derived from the mesh (:mod:`sim.parts`).
        table_size: (x, y) of the table top; the arm stands at the -x edge.
        table_height: height of the table top above the floor.
        arm_inset: distance of the arm's base axis from the table's -x edge.
        camera_height: camera height above the table top, in [0.6, 1.0].
        camera_tilt_deg: angle of the optical axis from straight down, in [0, 45]; the camera
            stands on the +x side and leans towards the arm.
        camera_target: (x, y) of the table-top point on the optical axis.
        fixtures: add a place for every workpiece: a fixture for a part resting upright, the tote otherwise.
        resting: ``"upright"``: each part on its largest stable face (its model frame's rest); ``"any"``: each
            in one of its stable rests, drawn by probability (``psorr.synthetic.resting.stable_rests``). A
            part not resting upright is placed in the tote.
        catalog_grasps: where an upright catalog part's grasps come from: ``"synthesised"`` from its mesh, as
            any part's (:mod:`sim.parts.catalog_grasps`), or ``"hand-written"`` in the catalog, kept as the
            reference the episodes benchmark compares them with.
        tote_wall: (thickness, height) of the tote's walls; its inside is sized for the parts it takes.
        fixture_clearance: gap between a part's footprint and its fixture's walls, per side.
        fixture_wall: (thickness, height) of the fixture walls.
        reach: (min, max) horizontal distance from the arm's base axis to anything placed.
        gap: least distance between placed footprints.
        drop_height: height above the table the parts are released from.
        settle_time: simulated time the parts are left to settle before the home keyframe.
        intrinsics: the camera; MuJoCo needs fx == fy and a centred principal point.
        occluder: add the human arm (``sim/people/occluder.py``) and draw its reach schedule.
        reach_gap_s: (min, max) seconds the person waits between reaches (each wait drawn uniformly).
        pick: the parts an episode picks, in this order: each a part's name, or a colour of
            ``psorr.segment.PALETTE`` and a part's name (``"red idler"``: the instance the robot sees as red);
            empty: every part, in task order. Parts not named stay on the table.
    """

    workpieces: tuple[str, ...] = ("u_channel", "chassis", "transformer", "flanged_hub")
    mesh_parts: tuple[MeshPart, ...] = ()
    table_size: tuple[float, float] = (0.9, 1.0)
    table_height: float = 0.75
    arm_inset: float = 0.1
    camera_height: float = 0.8
    camera_tilt_deg: float = 30.0
    camera_target: tuple[float, float] = (0.0, 0.0)
    fixtures: bool = True
    resting: str = "upright"
    catalog_grasps: str = "synthesised"
    tote_wall: tuple[float, float] = (0.006, 0.03)
    fixture_clearance: float = 0.004
    fixture_wall: tuple[float, float] = (0.006, 0.012)
    reach: tuple[float, float] = (0.25, 0.7)
    gap: float = 0.02
    drop_height: float = 0.003
    settle_time: float = 0.5
    intrinsics: CameraIntrinsics = KINECT_V1_CAMERA
    occluder: bool = True
    reach_gap_s: tuple[float, float] = (2.0, 8.0)
    pick: tuple[str, ...] = ()

    def __post_init__(self):
        object.__setattr__(self, "workpieces", tuple(self.workpieces))
        object.__setattr__(self, "mesh_parts", tuple(self.mesh_parts))
        if not self.workpieces or len(set(self.workpieces)) != len(self.workpieces):
            raise SimInputError(f"workpieces must name at least one part, each once; got {self.workpieces}")
        unnamed = [getattr(p, "name", p) for p in self.mesh_parts
                   if not isinstance(p, MeshPart) or p.name not in self.workpieces]
        if unnamed or len({p.name for p in self.mesh_parts}) != len(self.mesh_parts):
            raise SimInputError(f"each of mesh_parts must be a MeshPart named once in workpieces; {unnamed} are not")
        if self.resting not in RESTING:
            raise SimInputError(f"resting must be one of {', '.join(RESTING)}, got {self.resting!r}")
        if self.catalog_grasps not in CATALOG_GRASPS:
            raise SimInputError(f"catalog_grasps must be one of {', '.join(CATALOG_GRASPS)}, "
                                f"got {self.catalog_grasps!r}")
        if self.resting == "any" and any(p.place == "fixture" for p in self.mesh_parts):
            raise SimInputError("a part resting any way cannot go to a fixture, which holds it upright: give it "
                                "place: tote, or resting: upright")
        if not 0.6 <= self.camera_height <= 1.0:
            raise SimInputError(f"camera_height must lie in [0.6, 1.0] m, got {self.camera_height}")
        if not 0.0 <= self.camera_tilt_deg <= 45.0:
            raise SimInputError(f"camera_tilt_deg must lie in [0, 45], got {self.camera_tilt_deg}")
        if min(*self.table_size, self.table_height, *self.fixture_wall, self.fixture_clearance, *self.tote_wall) <= 0:
            raise SimInputError("table_size, table_height, fixture_wall, fixture_clearance and tote_wall must be > 0")
        if not 0 <= self.reach[0] < self.reach[1] or min(self.gap, self.drop_height, self.settle_time) < 0:
            raise SimInputError("reach must be (min, max) with 0 <= min < max; gap, drop_height, settle_time >= 0")
        if len(self.reach_gap_s) != 2 or not 0 < self.reach_gap_s[0] <= self.reach_gap_s[1]:
            raise SimInputError(f"reach_gap_s must be (min, max) seconds with 0 < min <= max, got {self.reach_gap_s}")
        check_intrinsics(self.intrinsics)
        object.__setattr__(self, "pick", tuple(self.pick))
        for wanted in self.pick:
            pick_target(wanted, self.workpieces)


def pick_target(wanted, workpieces) -> tuple[str | None, str]:
    """(colour or None, part) of an entry of :attr:`WorldConfig.pick`, such as ``"red idler"``."""
    from psorr.segment.colour import PALETTE

    words = wanted.split() if isinstance(wanted, str) else []
    if len(words) not in (1, 2) or words[-1] not in workpieces:
        raise SimInputError(f"pick {wanted!r}: name a part on the table ({', '.join(workpieces)}), optionally "
                            "after its colour, as in 'red idler'")
    if len(words) == 2 and words[0] not in PALETTE:
        raise SimInputError(f"pick {wanted!r}: {words[0]!r} is not a colour; colours are {', '.join(PALETTE)}")
    return (words[0] if len(words) == 2 else None), words[-1]
