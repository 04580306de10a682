"""The robot cell, assembled in code with ``mujoco.MjSpec`` (the only place a scene is built).

World frame: metres, z up, origin on the floor below the table's centre. The table top is at
``table_height``; the arm (``sim/world/robot.py``, attached with the prefix ``"arm/"``) stands on it
``arm_inset`` from the -x edge and faces +x. Each workpiece is a free body named after its part,
whose body frame is the part's model frame (origin at the centre of the resting face, +z up): its
mesh is the visual mesh, its CoACD hulls (``assets/workpieces/collision`` for a catalog part,
derived by :mod:`sim.parts` for a user's mesh) its collision meshes. Each part has a fixture: a pocket of four
thin walls on the table, ``fixture_clearance`` wider than the part's footprint on every side; a
part seated in it has the fixture's pose. A fixed camera (``"kinect"``, Kinect v1 intrinsics)
looks at the table from the +x side. Keyframe ``"home"``: arm at home, parts settled.

With ``WorldConfig.occluder`` a human arm (``sim/people/occluder.py``) stands beyond the +x edge: four
mocap capsules (``World.occluder_geoms``, geom class ``"occluder"``) that collide with nothing,
so they never push a part, but render and can serve as collision-avoidance geoms for the robot.
Its :class:`~sim.people.occluder.ReachSchedule` (``World.occluder``) is drawn from the build rng after
the layout, so a seed gives the same layout with or without it; ``World.apply_occluder(data, t)``
poses the arm at time t. The home keyframe holds it at rest, out of the camera's view.
"""

from __future__ import annotations

import dataclasses
import math
from types import MappingProxyType

import mujoco
import numpy as np

from sim.devices.sensor import T_world_camera_opencv, fovy_deg
from sim.errors import SimInputError
from sim.parts.derive import CellPart
from sim.people.occluder import RADII, ReachSchedule, occluder_pose, segment_half_lengths
from sim.world.built import HOME_KEY, World, pose_matrix, quat_of
from sim.world.config import WorldConfig
from sim.world.layout import place_parts, yaw_matrix
from sim.world.parts import (
    cell_parts,
    drawn_rests,
    footprint_bounds,
    footprint_sides,
    instance_colours,
    instance_names,
    places,
)
from sim.world.robot import ArmConfig, apply_arm_options, load_arm_spec
from sim.world.tote import ToteLayout

CAMERA_NAME = "kinect"
ARM_PREFIX = "arm/"
_GEOM = mujoco.mjtGeom


def _add_boxes(spec, body, name: str, boxes, material: str) -> None:
    """A visual and a collision box geom per (centre, half sizes) in ``body``'s frame."""
    vis, col = spec.find_default("visual"), spec.find_default("collision")
    for k, (centre, half) in enumerate(boxes):
        suffix = f"_{k}" if len(boxes) > 1 else ""
        body.add_geom(default=vis, name=f"{name}_visual{suffix}", type=_GEOM.mjGEOM_BOX, pos=centre, size=half,
                      material=material)
        body.add_geom(default=col, name=f"{name}_collision{suffix}", type=_GEOM.mjGEOM_BOX, pos=centre, size=half)


def _scene(spec: mujoco.MjSpec, cfg: WorldConfig) -> None:
    """Options, defaults, materials, floor, light, table and camera."""
    apply_arm_options(spec)
    # Parts at rest sleep until an awake body touches them (MuJoCo >= 3.15; 3.4-3.14 take the flag but
    # never put these parts to sleep). Resting on the table as about 30 convex pieces each, they made
    # 120 contacts, and stepping cost 9x what it does asleep. "At rest" is under 0.1 mm/s, a tenth of
    # MuJoCo's default, so that a part sliding slowly down a fixture wall is not taken for one at rest;
    # parts still sleep within 0.1 s of coming to rest. sim.skills.pick keeps the part it handles awake.
    spec.option.enableflags |= mujoco.mjtEnableBit.mjENBL_SLEEP
    spec.option.sleep_tolerance = 1e-4
    spec.modelname = "psorr_cell"
    spec.visual.global_.offwidth = max(640, cfg.intrinsics.width)
    spec.visual.global_.offheight = max(480, cfg.intrinsics.height)
    vis = spec.add_default("visual", spec.default)
    vis.geom.contype, vis.geom.conaffinity, vis.geom.group, vis.geom.density = 0, 0, 2, 0.0
    spec.add_default("collision", spec.default).geom.group = 3
    for name, rgba in (("floor", (0.32, 0.34, 0.37, 1)), ("table", (0.62, 0.63, 0.65, 1)),
                       ("fixture", (0.12, 0.13, 0.15, 1))):
        spec.add_material(name=name, rgba=rgba, specular=0.2)
    spec.worldbody.add_geom(name="floor", type=_GEOM.mjGEOM_PLANE, size=[0, 0, 0.05], material="floor")
    spec.worldbody.add_light(name="top_light", pos=[0, 0, cfg.table_height + 1.8], dir=[0, 0, -1],
                             diffuse=[0.7, 0.7, 0.7], castshadow=True)
    tx, ty, top, t = cfg.table_size[0] / 2, cfg.table_size[1] / 2, cfg.table_height, 0.04
    body = spec.worldbody.add_body(name="table", pos=[0, 0, top - t / 2])
    _add_boxes(spec, body, "table", [([0, 0, 0], [tx, ty, t / 2])], "table")
    legs = [([sx * (tx - 0.04), sy * (ty - 0.04), -top / 2], [0.025, 0.025, (top - t) / 2])
            for sx in (-1, 1) for sy in (-1, 1)]
    for k, (centre, half) in enumerate(legs):
        body.add_geom(default=vis, name=f"table_leg_visual_{k}", type=_GEOM.mjGEOM_BOX, pos=centre, size=half,
                      material="table")
    theta = math.radians(cfg.camera_tilt_deg)
    target = np.array([*cfg.camera_target, top])
    eye = target + cfg.camera_height * np.array([math.tan(theta), 0.0, 1.0])
    # MuJoCo camera axes: x = image right (+y: the camera faces -x), y = image up (towards the arm), z = -forward.
    right, up = np.array([0.0, 1.0, 0.0]), np.array([-math.cos(theta), 0.0, math.sin(theta)])
    R = np.column_stack([right, up, np.cross(right, up)])
    spec.worldbody.add_camera(name=CAMERA_NAME, pos=eye, quat=quat_of(R), fovy=fovy_deg(cfg.intrinsics))


def _add_part_assets(spec, part: CellPart) -> None:
    """The meshes and material every instance of ``part`` shares: visual mesh, collision hulls, colour."""
    name = part.name
    spec.add_mesh(name=name, file=str(part.info.mesh_path))
    spec.add_material(name=f"{name}_material", rgba=[*part.info.color, 1.0], specular=0.3)
    for k, file in enumerate(part.collision_files):
        spec.add_mesh(name=f"{name}_collision_{k}", file=str(file))


def add_part_body(spec: mujoco.MjSpec, body_name: str, mesh, mass: float, pos, quat):
    """A free body ``body_name`` (its joint ``<body_name>_joint``; body frame = model frame) of ``mass`` kg with
    the inertia of the solid ``mesh`` (model frame, metres), at ``pos``, ``quat``; its geoms are the caller's."""
    body = spec.worldbody.add_body(name=body_name, pos=pos, quat=quat)
    body.add_freejoint(name=f"{body_name}_joint")
    body.explicitinertial = True
    body.mass = mass
    body.ipos = mesh.center_mass
    I = mesh.moment_inertia * (mass / mesh.mass)  # noqa: E741 - about the centre of mass, model axes
    body.fullinertia = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
    return body


def _add_workpiece(spec, body_name: str, part: CellPart, mesh, pos, quat, rgb=None) -> None:
    """A free body ``body_name`` of ``part``: its visual mesh (in ``rgb``, its own colour, when given; else the
    part's), collision hulls, mass and inertia."""
    name = part.name
    material = f"{name}_material"
    if rgb is not None:
        material = f"{body_name}_material"
        spec.add_material(name=material, rgba=[*rgb, 1.0], specular=0.3)
    body = add_part_body(spec, body_name, mesh, part.info.mass, pos, quat)
    body.add_geom(default=spec.find_default("visual"), name=f"{body_name}_visual", type=_GEOM.mjGEOM_MESH,
                  meshname=name, material=material)
    for k in range(len(part.collision_files)):
        body.add_geom(default=spec.find_default("collision"), name=f"{body_name}_collision_{k}",
                      type=_GEOM.mjGEOM_MESH, meshname=f"{name}_collision_{k}")


def _coloured(info, rgb):
    """``info`` in the body's own colour ``rgb`` (unchanged for None)."""
    return info if rgb is None else dataclasses.replace(info, color=np.array(rgb))


def _fixture_walls(bounds, cfg: WorldConfig, clearance: float | None = None, wall=None):
    """(centre, half size) of the 4 walls of a pocket around ``bounds``, in the fixture (= seated part) frame
    (``clearance`` and ``wall``: the fixtures' unless given)."""
    clearance = cfg.fixture_clearance if clearance is None else clearance
    (x0, y0), (x1, y1) = bounds[0] - clearance, bounds[1] + clearance
    (t, h), cx, cy = cfg.fixture_wall if wall is None else wall, (x0 + x1) / 2, (y0 + y1) / 2
    ends = [([x, cy, h / 2], [t / 2, (y1 - y0) / 2 + t, h / 2]) for x in (x0 - t / 2, x1 + t / 2)]
    return ends + [([cx, y, h / 2], [(x1 - x0) / 2, t / 2, h / 2]) for y in (y0 - t / 2, y1 + t / 2)]


def _add_occluder(spec: mujoco.MjSpec, schedule: ReachSchedule) -> tuple[str, ...]:
    """Mocap capsule bodies of the human arm at rest, one geom each of the same name, in class ``"occluder"``."""
    cls = spec.add_default("occluder", spec.default)
    cls.geom.contype, cls.geom.conaffinity, cls.geom.group, cls.geom.density = 0, 0, 1, 0.0
    spec.add_material(name="skin", rgba=(0.80, 0.62, 0.50, 1), specular=0.1)
    half = segment_half_lengths()
    for name, T in occluder_pose(schedule, -math.inf).items():
        body = spec.worldbody.add_body(name=name, mocap=True, pos=T[:3, 3], quat=quat_of(T[:3, :3]))
        body.add_geom(default=cls, name=name, type=_GEOM.mjGEOM_CAPSULE,
                      size=[RADII[name.split("/")[-1]], half[name], 0], material="skin")
    return tuple(half)


def build_world(config: WorldConfig = WorldConfig(), rng: np.random.Generator | None = None) -> World:
    """Assemble, compile and settle the cell; the same ``config`` and seed give the same world.

    Args:
        config: what to build.
        rng: the only randomness (where the parts and fixtures go, and their yaw; then the occluder's
            schedule, which targets one of the parts).

    Raises:
        SimInputError: an unknown workpiece name or no rng.
        WorldBuildError: the collision parts are missing or stale, or the parts do not fit.
        PartMeshError: a mesh part's mesh cannot become a part.
    """
    if not isinstance(rng, np.random.Generator):
        raise SimInputError("build_world needs rng, a numpy.random.Generator (e.g. np.random.default_rng(0))")
    cfg = config
    parts = cell_parts(cfg)
    types = instance_names(cfg)  # body -> part
    bodies = tuple(types)

    spec = mujoco.MjSpec()
    _scene(spec, cfg)
    base = np.array([-cfg.table_size[0] / 2 + cfg.arm_inset, 0.0, cfg.table_height])
    spec.attach(load_arm_spec(), prefix=ARM_PREFIX, frame=spec.worldbody.add_frame(name="arm_mount", pos=base))
    arm = ArmConfig().with_prefix(ARM_PREFIX)
    bare = spec.compile()  # table, arm and camera only: to see where the camera sees the table

    meshes = {n: parts[n].info.load_mesh() for n in cfg.workpieces}
    where = places(cfg) if cfg.fixtures else {}
    rests = drawn_rests(cfg, types, meshes, rng)
    bounds = {b: footprint_bounds(meshes[t], rests.get(b)) for b, t in types.items()}
    items = [(b, bounds[b], cfg.gap / 2) for b in bodies]
    pad = cfg.fixture_clearance + cfg.fixture_wall[0] + cfg.gap / 2
    items += [(f"{b}_fixture", bounds[b], pad) for b in bodies if where.get(b) == "fixture"]
    tote = ToteLayout.for_parts({b: footprint_sides(meshes[types[b]], rests.get(b)) for b in bodies
                                 if where.get(b) == "tote"}) if "tote" in where.values() else None
    if tote is not None:
        items.append(("tote", tote.bounds(), cfg.tote_wall[0] + cfg.gap / 2))
    spots = place_parts(cfg, items, base[:2], bare, arm.home_key, CAMERA_NAME, rng)
    fixtures = {}
    for name in bodies:
        if where.get(name) != "fixture":
            continue
        x, y, yaw = spots[f"{name}_fixture"]
        R = yaw_matrix(yaw)
        fixtures[name] = pose_matrix([x, y, cfg.table_height], R)
        body = spec.worldbody.add_body(name=f"{name}_fixture", pos=[x, y, cfg.table_height], quat=quat_of(R))
        _add_boxes(spec, body, f"{name}_fixture", _fixture_walls(bounds[name], cfg), "fixture")
    T_world_tote = None
    if tote is not None:
        x, y, yaw = spots["tote"]
        T_world_tote = pose_matrix([x, y, cfg.table_height], yaw_matrix(yaw))
        body = spec.worldbody.add_body(name="tote", pos=T_world_tote[:3, 3], quat=quat_of(T_world_tote[:3, :3]))
        _add_boxes(spec, body, "tote", _fixture_walls(tote.bounds(), cfg, 0.0, cfg.tote_wall), "fixture")
    for part in parts.values():
        _add_part_assets(spec, part)
    colours = instance_colours(cfg)
    for name in bodies:
        x, y, yaw = spots[name]
        T = pose_matrix([x, y, cfg.table_height + cfg.drop_height], yaw_matrix(yaw))
        if name in rests:
            T = T @ rests[name]
        _add_workpiece(spec, name, parts[types[name]], meshes[types[name]], T[:3, 3], quat_of(T[:3, :3]),
                       colours.get(name))
    schedule, occluder_geoms = None, ()
    if cfg.occluder:  # drawn last: the layout above does not depend on it
        data = mujoco.MjData(bare)
        mujoco.mj_forward(bare, data)
        eye = T_world_camera_opencv(bare, data, CAMERA_NAME)[:3, 3]
        targets = [spots[n][:2] for n in bodies]
        schedule = ReachSchedule.sample(rng, cfg.table_size, cfg.table_height, targets=targets, eye=eye)
        occluder_geoms = _add_occluder(spec, schedule)

    # Settle the dropped parts with the arm holding home, then make their rest the initial state.
    model = spec.compile()
    data = mujoco.MjData(model)
    key = model.key(arm.home_key)
    mujoco.mj_resetDataKeyframe(model, data, key.id)
    for _ in range(round(cfg.settle_time / model.opt.timestep)):
        mujoco.mj_step(model, data)
    home_qpos = key.qpos.copy()
    for name in bodies:
        adr = model.joint(f"{name}_joint").qposadr[0]
        home_qpos[adr:adr + 7] = data.qpos[adr:adr + 7]
        spec.body(name).pos = data.qpos[adr:adr + 3]
        spec.body(name).quat = data.qpos[adr + 3:adr + 7] / np.linalg.norm(data.qpos[adr + 3:adr + 7])
    spec.add_key(name=HOME_KEY, qpos=home_qpos, ctrl=key.ctrl)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key(HOME_KEY).id)
    mujoco.mj_forward(model, data)

    def frozen(T):
        T = np.array(T, dtype=np.float64)
        T.setflags(write=False)
        return T

    ids = {n: model.body(n).id for n in bodies}
    return World(
        config=cfg, spec=spec, model=model, data=data, arm=arm, workpieces=bodies,
        part_types=MappingProxyType(types),
        catalog=MappingProxyType({b: _coloured(parts[t].info, colours.get(b)) for b, t in types.items()}),
        grasps=MappingProxyType({b: parts[t].grasps for b, t in types.items()}),
        T_world_workpieces=MappingProxyType(
            {n: frozen(pose_matrix(data.xpos[i], data.xmat[i].reshape(3, 3))) for n, i in ids.items()}
        ),
        T_world_fixtures=MappingProxyType({n: frozen(T) for n, T in fixtures.items()}),
        places=MappingProxyType(where), tote=tote, T_world_tote=None if tote is None else frozen(T_world_tote),
        T_world_camera=frozen(T_world_camera_opencv(model, data, CAMERA_NAME)),
        camera_name=CAMERA_NAME, table_top=cfg.table_height, T_world_arm_base=frozen(pose_matrix(base, np.eye(3))),
        occluder=schedule, occluder_geoms=occluder_geoms,
    )
