"""Pictures of a part's grasps (``psorr-sim grasps``): one PNG per part, a panel per way it rests.

A panel shows the part resting on the table (grey, z = 0) seen obliquely from above, shaded by its faces'
normals; the rest's best grasp (its first) as the gripper's two pads (``GraspSynthesisParams.pad_half_size``
boxes, their faces the grasp's width apart) in a strong colour with a line between them, and the others
faded: each pad's face outlined, and the line. Axes are the table frame in millimetres.

Synthesised grasps named ``rest{k}_synth_{j}`` (:mod:`sim.parts.derive`) were made for the part in its k-th
stable rest (:func:`psorr.synthetic.resting.stable_rests`); others (a catalog part's) for the upright part.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # headless: pictures go to files, never to a window
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import open3d as o3d  # noqa: E402
import trimesh  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402
from PIL import Image  # noqa: E402

from sim.errors import RecordingError, SimInputError  # noqa: E402
from sim.parts.grasp import Grasp  # noqa: E402
from sim.parts.grasp_synthesis import GraspSynthesisParams  # noqa: E402

MAX_PANELS = 4  # rests drawn per part: the most probable that have grasps
MAX_FACES = 60_000  # faces of a mesh split for drawing (about half face the viewer); a larger one is decimated
PANEL_INCHES = (3.6, 3.9)  # width, height of a panel; a part drawn in one panel gets half as much again
DPI = 100
VIEW_ELEVATION, VIEW_AZIMUTH = 40.0, -60.0  # deg: above the table, from its -y side
LIGHT = np.array([0.4, -0.5, 0.77]) / np.linalg.norm([0.4, -0.5, 0.77])  # from the viewer's upper left
BEST_COLOURS = ((0.85, 0.0, 0.55), (0.0, 0.6, 0.25), (0.1, 0.35, 0.95))  # the one least like the part's
OTHER_COLOUR, OTHER_ALPHA = (0.1, 0.1, 0.2), 0.6  # the other grasps' lines; their pads' outlines half as strong
_EYE = trimesh.unitize([np.cos(np.radians(VIEW_AZIMUTH)), np.sin(np.radians(VIEW_AZIMUTH)),
                        np.tan(np.radians(VIEW_ELEVATION))])  # towards the (orthographic) viewer
_REST_NAME = re.compile(r"^rest(\d+)_")
_DOWN = np.array([0.0, 0.0, -1.0])
_SAME_DIRECTION = np.cos(np.radians(1.0))  # a rest fits grasps that point within 1 deg of straight down in it


@dataclass(frozen=True, eq=False)
class RestGrasps:
    """The grasps made for one way a part rests: one panel of the picture.

    Attributes:
        rest: the index of the stable rest (``stable_rests(mesh)[rest]``), or None for the upright part.
        probability: the chance that a dropped part comes to rest so; None when not known (upright grasps).
        T_table_model: (4, 4) model -> table frame of the rest (metres).
        grasps: the rest's grasps, best first, in the model frame.
    """

    rest: int | None
    probability: float | None
    T_table_model: np.ndarray
    grasps: tuple[Grasp, ...]

    @property
    def title(self) -> str:
        where = "upright" if self.rest is None else f"rest {self.rest}"
        chance = "" if self.probability is None else f", p = {self.probability:.2f}"
        made = "synthesised" if all("synth" in g.name for g in self.grasps) else "hand-written"
        return f"{where}{chance}\n{_count(len(self.grasps), made + ' grasp')}"


@dataclass(frozen=True, eq=False)
class GraspPicture:
    """A written picture: its PNG, the panels drawn, the part's grasps and its rests with grasps (all)."""

    path: Path
    panels: tuple[RestGrasps, ...]
    grasp_count: int
    rests_with_grasps: int

    @property
    def summary(self) -> str:
        """E.g. "64 grasps in 8 rests (the 4 most probable drawn)", or "3 grasps of the upright part"."""
        grasps, rests = _count(self.grasp_count, "grasp"), self.rests_with_grasps
        if self.grasp_count and rests == 1 and self.panels[0].rest is None:
            return f"{grasps} of the upright part"
        drawn = "" if rests <= len(self.panels) else f" (the {len(self.panels)} most probable drawn)"
        return f"{grasps} in {_count(rests, 'rest')}{drawn}" if rests else grasps


def _count(n: int, thing: str) -> str:
    return f"{n} {thing}{'s' * (n != 1)}" if n else f"no {thing.split()[-1]}"


def grasps_by_rest(mesh: trimesh.Trimesh, grasps) -> list[RestGrasps]:
    """``grasps`` grouped by the rest they were made for, in rest order (upright first), best first in each.

    Args:
        mesh: the part in its model frame (metres), as the cell builds it (``CellPart.info.load_mesh()``).
        grasps: :class:`~sim.parts.grasp.Grasp` s in the model frame, named as the module says.
    """
    groups: dict[int, list[Grasp]] = {}
    for grasp in grasps:
        match = _REST_NAME.match(grasp.name)
        groups.setdefault(int(match.group(1)) if match else -1, []).append(grasp)
    out = [RestGrasps(None, None, np.eye(4), tuple(groups.pop(-1)))] if -1 in groups else []
    if groups:
        from psorr.synthetic.resting import stable_rests

        rests = stable_rests(mesh)
        out += [_rest_of(k, tuple(groups[k]), rests, mesh) for k in sorted(groups)]
    return out


def _rest_of(k: int, grasps: tuple[Grasp, ...], rests, mesh: trimesh.Trimesh) -> RestGrasps:
    """Rest ``k`` if it turns the grasps' approach straight down, as it did when they were made; else the first
    rest that does (a mesh read back from its file may order rests of near equal chance otherwise); else the
    part turned so that it does, lowest point on the table, of unknown probability."""
    approach = grasps[0].approach
    fits = [j for j, rest in enumerate(rests) if rest.T_table_model[:3, :3] @ approach @ _DOWN > _SAME_DIRECTION]
    if fits:
        j = k if k in fits else fits[0]
        return RestGrasps(k, rests[j].probability, rests[j].T_table_model, grasps)
    T = trimesh.geometry.align_vectors(approach, _DOWN)
    T[2, 3] = -(mesh.vertices @ T[2, :3]).min()
    return RestGrasps(k, None, T, grasps)


def save_grasp_picture(path, part: str, mesh: trimesh.Trimesh, grasps, color=(0.6, 0.6, 0.65),
                       params: GraspSynthesisParams | None = None) -> GraspPicture:
    """Draw ``part``'s grasps, a panel for each of its first :data:`MAX_PANELS` rests with grasps, to ``path``.

    Args:
        path: the PNG to write; its folder is created if missing.
        part: the part's name, the figure's title.
        mesh: the part in its model frame (metres).
        grasps: its grasps (model frame, metres), best first within each rest; none draws the part upright.
        color: the part's RGB in [0, 1].
        params: the gripper whose pads are drawn (default: the cell's).

    Raises:
        SimInputError: ``mesh`` is not a trimesh with faces, or a grasp is not a Grasp.
        RecordingError: ``path`` cannot be written (its folder is a file, or not writable); the CLI checks its
            ``--out`` before drawing (``psorr.cli.check_output``).
    """
    grasps, path, params = tuple(grasps), Path(path), params or GraspSynthesisParams()
    _check_input(mesh, grasps)
    rests = grasps_by_rest(mesh, grasps) or [RestGrasps(None, None, np.eye(4), ())]
    picture = GraspPicture(path, tuple(rests[:MAX_PANELS]), len(grasps), len(rests) if grasps else 0)
    drawn = _for_drawing(mesh)
    best = max(BEST_COLOURS, key=lambda c: np.linalg.norm(np.subtract(c, color[:3])))
    scale = 1.5 if len(picture.panels) == 1 else 1.0
    fig = plt.figure(figsize=(PANEL_INCHES[0] * len(picture.panels) * scale, PANEL_INCHES[1] * scale), dpi=DPI)
    try:
        for i, rest in enumerate(picture.panels):
            _draw_rest(fig.add_subplot(1, len(picture.panels), i + 1, projection="3d"), drawn, rest, color, best,
                       params)
        fig.suptitle(f"{part}: {picture.summary}", fontsize=11, y=0.985)
        fig.legend(handles=[Line2D([], [], color=best, linewidth=2.2, marker="s", label="best grasp of the rest: pads"),
                            Line2D([], [], color=OTHER_COLOUR, alpha=OTHER_ALPHA, linewidth=1.2, marker="s",
                                   markerfacecolor="none", label="its other grasps")],
                   loc="lower center", ncol=2, fontsize=8, frameon=False)
        fig.subplots_adjust(left=0.0, right=0.96, bottom=0.08, top=0.82, wspace=0.0)
        _write(fig, path)
    finally:
        plt.close(fig)
    return picture


def _check_input(mesh, grasps) -> None:
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise SimInputError(f"a grasp picture needs a trimesh.Trimesh with faces, got {type(mesh).__name__}")
    wrong = sorted({type(g).__name__ for g in grasps if not isinstance(g, Grasp)})
    if wrong:
        raise SimInputError(f"grasps must be sim.parts.grasp.Grasp objects, got {', '.join(wrong)}")


def _for_drawing(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, float]:
    """``mesh`` (past :data:`MAX_FACES` faces decimated by Open3D's quadrics), and the longest edge (m) to
    split faces to: matplotlib sorts whole faces by their centres, so a long one can hide what is in front of
    it. The shortest edge that keeps the faces within the budget."""
    if len(mesh.faces) > MAX_FACES:
        full = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(mesh.vertices),
                                         o3d.utility.Vector3iVector(mesh.faces))
        small = full.simplify_quadric_decimation(target_number_of_triangles=MAX_FACES)
        mesh = trimesh.Trimesh(np.asarray(small.vertices), np.asarray(small.triangles), process=False)
    for edge in mesh.scale / np.array([40.0, 30.0, 20.0, 15.0, 10.0]):
        if len(trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, edge, max_iter=20)[1]) <= MAX_FACES:
            return mesh, edge
    return mesh, np.inf


def _draw_rest(ax, drawn: tuple[trimesh.Trimesh, float], rest: RestGrasps, color, best,
               params: GraspSynthesisParams) -> None:
    """One panel, in this order: the table; the part and its best grasp's pads in small faces, hidden then in
    sight; the other grasps' pads' outlines; the lines between pads, the best's on top. Millimetres."""
    poses = [_pad_poses(g, rest.T_table_model, params) for g in rest.grasps]
    triangles, colours, seen = _solids(drawn, rest.T_table_model, poses[0] if poses else (), color, best, params)
    outlines = [_inner_face(pose, side, params) for pair in poses[1:] for side, pose in zip((-1, 1), pair)]
    corners = np.vstack([triangles.reshape(-1, 3), *outlines])
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    ax.computed_zorder = False
    (x0, y0), (x1, y1) = lo[:2] - 0.1 * (hi - lo)[:2].max(), hi[:2] + 0.1 * (hi - lo)[:2].max()
    ax.add_collection3d(Poly3DCollection([[(x0, y0, 0), (x1, y0, 0), (x1, y1, 0), (x0, y1, 0)]], zorder=0,
                                         facecolors=(0.88, 0.88, 0.86), edgecolors="none"))  # the table
    # The faces in sight over the hidden ones, which fill the gaps a face partly in sight leaves; each face's
    # edge in its own colour closes the hairline seams between the triangles.
    for layer, z in ((~seen, 1), (seen, 2)):
        ax.add_collection3d(Poly3DCollection(triangles[layer], facecolors=colours[layer], edgecolors=colours[layer],
                                             linewidths=0.3, zorder=z))
    ax.add_collection3d(Poly3DCollection(outlines, facecolors="none", linewidths=0.7, zorder=3,
                                         edgecolors=(*OTHER_COLOUR, OTHER_ALPHA / 2)))
    for pair in poses[:0:-1]:
        ax.plot(*(pair[:, :3, 3].T * 1e3), color=OTHER_COLOUR, alpha=OTHER_ALPHA, linewidth=1.2, zorder=4)
    if poses:
        ax.plot(*(poses[0][:, :3, 3].T * 1e3), color=best, linewidth=2.2, zorder=4)
    _frame(ax, lo, hi)
    ax.set_title(rest.title, fontsize=9)


def _solids(drawn: tuple[trimesh.Trimesh, float], T_table_model: np.ndarray, pad_poses, color, best,
            params: GraspSynthesisParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The posed part and the pads at ``pad_poses``, split to the drawn edge: (F, 3, 3) mm the triangles that
    face the viewer, (F, 3) their shaded RGB, and (F,) whether each is in sight (the ray from its centre to
    the viewer clear): matplotlib sorts faces by their centres, so a hidden one might show through."""
    mesh, edge = drawn
    posed = mesh.copy()
    posed.apply_transform(T_table_model)
    boxes = [trimesh.creation.box(2 * np.array(params.pad_half_size), pose) for pose in pad_poses]
    scene = trimesh.util.concatenate([posed, *boxes])
    base = np.vstack([np.tile(color[:3], (len(posed.faces), 1)), np.tile(best, (12 * len(boxes), 1))])
    vertices, faces, index = trimesh.remesh.subdivide_to_size(scene.vertices, scene.faces, edge, max_iter=20,
                                                              return_index=True)
    facing = scene.face_normals[index] @ _EYE > 0
    lambert = np.clip(scene.face_normals @ LIGHT, 0.0, 1.0)  # with an ambient floor: faces turned away stay seen
    shaded = np.clip((0.4 + 0.6 * lambert)[:, None] * base, 0.0, 1.0)
    return vertices[faces[facing]] * 1e3, shaded[index[facing]], ~_occluded(vertices, faces[facing])


def _occluded(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F,) bool: is the centre of each face hidden from the viewer by another (Open3D's ray casting)?"""
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.core.Tensor(vertices.astype(np.float32)), o3d.core.Tensor(faces.astype(np.uint32)))
    rays = np.hstack([vertices[faces].mean(axis=1), np.tile(_EYE, (len(faces), 1))]).astype(np.float32)
    return scene.test_occlusions(o3d.core.Tensor(rays), tnear=1e-6).numpy().astype(bool)


def _pad_poses(grasp: Grasp, T_table_model: np.ndarray, params: GraspSynthesisParams) -> np.ndarray:
    """(2, 4, 4) the poses of the pads' boxes in the table frame (metres; x along closing, z along approach):
    each box's face towards the other ``width / 2`` from the grasp's point, centred level with it."""
    R, t = T_table_model[:3, :3], T_table_model[:3, 3]
    point, closing, approach = R @ grasp.point + t, R @ grasp.closing, R @ grasp.approach
    poses = np.tile(np.eye(4), (2, 1, 1))
    for pose, side in zip(poses, (-1, 1)):
        pose[:3, :3] = np.column_stack([closing, np.cross(approach, closing), approach])
        pose[:3, 3] = point + side * (grasp.width / 2 + params.pad_half_size[0]) * closing
    return poses


def _inner_face(pose: np.ndarray, side: int, params: GraspSynthesisParams) -> np.ndarray:
    """(4, 3) mm: the corners of the face a pad (of ``pose``, on ``side`` of the grasp) closes with."""
    thick, across, high = params.pad_half_size
    square = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * (across, high)
    return (np.column_stack([np.full(4, -side * thick), square, np.ones(4)]) @ pose.T)[:, :3] * 1e3


def _frame(ax, lo: np.ndarray, hi: np.ndarray) -> None:
    """Axes in mm at one scale on all three around ``lo``..``hi`` (the table at the bottom), seen from above."""
    centre, half = (lo + hi) / 2, np.maximum(0.55 * (hi - lo), 0.1 * (hi - lo).max())
    half[:2] = half[:2].max()  # a square of table, so that turning the part between rests keeps its scale
    ax.set(xlim=(centre[0] - half[0], centre[0] + half[0]), ylim=(centre[1] - half[1], centre[1] + half[1]),
           zlim=(0.0, 2 * half[2]), proj_type="ortho")
    ax.set_box_aspect(tuple(half), zoom=0.92)  # room for the tick labels
    ax.view_init(elev=VIEW_ELEVATION, azim=VIEW_AZIMUTH)
    for axis, name in zip((ax.xaxis, ax.yaxis, ax.zaxis), "xyz"):
        axis.set_label_text(f"{name} mm", fontsize=7)
        axis.labelpad = -6
        axis.set_pane_color((1.0, 1.0, 1.0, 0.0))
        axis.set_major_locator(MaxNLocator(4))
    ax.grid(False)  # grid lines would read as the other grasps' outlines
    ax.tick_params(labelsize=6, pad=-3)


def _write(fig, path: Path) -> None:
    """Save ``fig`` as a PNG of 256 colours: a fifth of the full colour one's bytes, the same to the eye."""
    picture = BytesIO()
    fig.savefig(picture, dpi=DPI, format="png")
    picture.seek(0)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        Image.open(picture).convert("RGB").quantize(256, method=Image.Quantize.FASTOCTREE).save(path, optimize=True)
    except (FileExistsError, NotADirectoryError):
        raise RecordingError(f"cannot write {path}: {path.parent} or a folder above it is a file; give a "
                             "folder (it is created if missing)") from None
    except OSError as exc:
        raise RecordingError(f"cannot write {path} ({exc.strerror or exc}): give a writable folder") from None
