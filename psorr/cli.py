"""The `psorr` command line. Results go to stdout; progress and logs to stderr."""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from psorr.checks.clouds import require_seen_from_origin
from psorr.cli_labels import decompose_command, segment_command
from psorr.cli_train import add_train_parser
from psorr.errors import PsorrError
from psorr.io.meshes import UNITS
from psorr.types import Method

# DecomposeParams.voxel_size, which a test holds this to: importing the pipeline for --help costs a second.
DEFAULT_VOXEL_SIZE = 0.012


def check_output(path: str | None, what: str, suffix: str | None = None) -> Path | None:
    """``path`` as a Path, once it is known that it can be written: before the work, not after it.

    ``suffix`` (".png", ".npy") is required as given, since the writers would otherwise change the name or
    fail on the format; without one, ``path`` is a folder. The nearest existing folder on the way must take
    a new file (tried with a temporary one), so that missing folders can be made.
    """
    if path is None:
        return None
    out = Path(path)
    if suffix is not None and (out.suffix.lower() != suffix or out.is_dir()):
        raise PsorrError(f"{what} {path}: must be a {suffix} file name (it is written as {suffix})")
    if suffix is None and out.exists() and not out.is_dir():
        raise PsorrError(f"{what} {path}: is a file; give a folder to write into")
    base = out if suffix is None else out.parent
    while not base.exists() and base != base.parent:
        base = base.parent
    try:
        if not base.is_dir():
            raise NotADirectoryError(f"{base} is not a folder")
        with tempfile.TemporaryFile(dir=base):
            pass
    except OSError as exc:
        raise PsorrError(f"{what} {path}: cannot write there ({exc.strerror or exc}); choose another place") from None
    return out


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


RERUN_HELP = ("record every stage for the Rerun viewer into OUT.rrd (without a file: stream to a viewer spawned "
              "now); needs pip install 'psorr[viz]'")


def rerun_target(path: str) -> Path | None:
    """Where a --rerun option records: None to stream to a viewer (the option without a file), else the
    ``.rrd`` file, checked to be writable before the work."""
    return check_output(path, "--rerun", ".rrd") if path else None


def rerun_logger(path: str | None):
    """The RerunLogger of a --rerun option (None without one), made before the work so that a missing extra or
    an unwritable file is told at once."""
    if path is None:
        return None
    from psorr.viz.rerun_log import RerunLogger

    target = rerun_target(path)
    logger = RerunLogger(target)
    if target is not None:
        _log(f"recording to {target}")
    return logger


def _recognize(args) -> int:
    from tqdm import tqdm

    from psorr.io.clouds import read_cloud
    from psorr.library.sources import library_from_arguments
    from psorr.recognize import Recognizer
    from psorr.recognize_params import RecognizeParams
    from psorr.sensing.kinect_noise import KINECT_V1

    # The outputs and the scene first: a wrong path should not wait for a new library to train.
    check_output(args.png, "--png", ".png")
    logger = rerun_logger(args.rerun)
    cloud = read_cloud(args.scene)
    require_seen_from_origin(cloud, str(args.scene))
    library = library_from_arguments(args.models, units=args.units,
                                     progress=lambda xs: tqdm(xs, desc="training", file=sys.stderr))
    _log(f"read {args.scene}: {len(cloud)} points; models {', '.join(library.names)}")
    params = RecognizeParams(sensor=KINECT_V1.noisier(args.noise_scale))
    params = params.for_stacked_parts() if args.stacked else params
    recognizer = Recognizer(library, method=args.method, params=params, use_colour=args.colour)
    result = recognizer.recognize(cloud, np.random.default_rng(args.seed), observer=logger)
    if logger is not None:
        logger.close()
    stats = result.stats
    if args.png:
        from psorr.viz.render import save_detections_png

        save_detections_png(args.png, cloud, result.detections, library)
        _log(f"wrote overlay to {args.png}")
    if args.json:
        print(json.dumps({
            "detections": [{"model": d.model, "pose": d.T_cloud_model.tolist(), "score": float(d.score),
                            **_colour_record(d), **_left_open_record(d)} for d in result.detections],
            "stats": {"method": stats.method, "hypotheses": int(stats.hypotheses),
                      "verify_ms_per_hypothesis": float(stats.verify_ms_per_hypothesis),
                      "total_ms": float(stats.total_ms), "train_ms": float(stats.train_ms),
                      **({"qpbo_nodes": stats.qpbo_nodes, "qpbo_unlabelled": stats.qpbo_unlabelled}
                         if stats.method in ("psg", "auto") else {})},
        }))
    else:
        print(f"{'model':<16} {'score':>6} {'seen':>5}  position (m)" + (" " * 15 + "colour" if args.colour else ""))
        for d in result.detections:
            where = " ".join(f"{v:+.3f}" for v in d.T_cloud_model[:3, 3])
            colour = f"  {d.colour.name}" if d.colour else ""
            rivals = "".join(f"  (or {r.model}, {r.score:.3f})" for r in d.rivals)
            print(f"{d.model:<16} {d.score:>6.3f} {d.visible_fraction:>5.2f}  {where}{colour}{rivals}")
        print(f"{len(result.detections)} detections; {stats.method}: {stats.hypotheses} hypotheses, "
              f"{stats.verify_ms_per_hypothesis:.2f} ms verification each, {stats.total_ms:.0f} ms in all")
    return 0


def _colour_record(detection) -> dict:
    """The JSON fields of a detection's colour: none without --colour."""
    if detection.colour is None:
        return {}
    return {"colour": detection.colour.name, "mean_rgb": [round(v, 4) for v in detection.colour.mean_rgb]}


def _left_open_record(detection) -> dict:
    """The JSON fields of what the view left open: twin poses, other models' poses (rivals), and the axis of a
    turn nothing in view fixed (model frame); none if it settled all."""
    record = {}
    if detection.alternatives:
        record["alternatives"] = [T.tolist() for T in detection.alternatives]
    if detection.rivals:
        record["rivals"] = [{"model": r.model, "pose": r.T_cloud_model.tolist(), "score": float(r.score)}
                            for r in detection.rivals]
    if detection.unfixed_turn is not None:
        axis = detection.unfixed_turn
        record["unfixed_turn"] = {"point": axis.point.tolist(), "direction": axis.direction.tolist()}
    return record


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="psorr", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    dec = sub.add_parser("decompose", help="split a depth cloud into planes and cylinders")
    dec.add_argument("cloud", help="cloud file: .pcd, .ply, .xyz/.txt or .npy, metres, sensor frame")
    dec.add_argument("--out", metavar="LABELS.npy", help="write one int64 primitive index per input point (-1: none)")
    dec.add_argument("--json", action="store_true", help="print one JSON line instead of a table")
    dec.add_argument("--png", metavar="PICTURE.png", help="render the cloud coloured by primitive")
    dec.add_argument("--voxel-size", type=voxel_metres, default=None,
                     help=f"working resolution in metres (default {DEFAULT_VOXEL_SIZE}), from 0.001 to 0.1; "
                          "time grows about as its inverse square: minutes for a 640x480 cloud at 0.002")
    dec.add_argument("--seed", type=seed, default=0, help="seed of the RANSAC sampling (default 0)")
    dec.add_argument("--rerun", nargs="?", const="", metavar="OUT.rrd", help=RERUN_HELP)
    dec.set_defaults(run=decompose_command)
    seg = sub.add_parser("segment", help="split the objects on the table of a cloud by colour and distance")
    seg.add_argument("cloud", help="cloud file: .pcd, .ply, .xyz/.txt or .npy, metres, sensor frame")
    seg.add_argument("--out", metavar="LABELS.npy", help="write one int64 segment per input point (-1: the table, "
                                                         "what is off it, NaN points)")
    seg.add_argument("--json", action="store_true", help="print one JSON line instead of a table")
    seg.add_argument("--png", metavar="PICTURE.png", help="render the cloud coloured by segment")
    seg.add_argument("--seed", type=seed, default=0, help="seed of the colour models' k-means (default 0)")
    seg.add_argument("--no-creases", dest="creases", action="store_false",
                     help="do not split a segment where its surface folds inwards, as objects that touch do "
                          "(a concave part, such as a bracket or a channel, then stays whole)")
    seg.set_defaults(run=segment_command)
    rec = sub.add_parser("recognize", help="find CAD-trained workpieces and their poses in a depth cloud")
    rec.add_argument("models", nargs="+", metavar="MODELS",
                     help="a folder of meshes (.stl/.obj/.ply/.step), mesh files, or a saved library (.npz, from "
                          "psorr train); each model is named by its file stem")
    rec.add_argument("scene", metavar="SCENE", help="cloud file in metres, sensor frame, table and all")
    rec.add_argument("--method", choices=[m.value for m in Method], default=Method.PSORR.value,
                     help="psorr: pairs of primitives (default); psg: cliques of the shape graph first; auto: "
                          "cliques for the models of many primitives only; orr: random point pairs (the baseline)")
    rec.add_argument("--units", choices=tuple(UNITS), default=None,
                     help="units of the meshes (default m, or a STEP file's own; meshes of implausible size are "
                          "refused without it)")
    rec.add_argument("--json", action="store_true", help="print exactly one JSON line to stdout")
    rec.add_argument("--png", metavar="OVERLAY.png", help="draw the recognised models over the cloud")
    rec.add_argument("--seed", type=seed, default=0)
    rec.add_argument("--rerun", nargs="?", const="", metavar="OUT.rrd", help=RERUN_HELP)
    rec.add_argument("--stacked", action="store_true",
                     help="parts may lie on other objects or sit flush with them: no limit on how high a part "
                          "floats over the table, and no continuation check (by default a part whose faces "
                          "the measured surface continues past its outline is taken to be a larger object)")
    rec.add_argument("--noise-scale", type=noise_scale, default=1.0, metavar="F",
                     help="the sensor's axial depth noise as F times a Kinect v1's (default 1), which every "
                          "noise-scaled threshold follows: a flat table's depth spread about its plane, over the "
                          "Kinect's at that depth (psorr.sensing.KINECT_V1.depth_sigma)")
    rec.add_argument("--colour", action="store_true",
                     help="segment the scene by colour and distance first and recognise each segment alone; "
                          "each detection carries its segment's colour (a cloud without colours: by distance)")
    rec.set_defaults(run=_recognize)
    add_train_parser(sub, tuple(UNITS))
    return parser


def _whole_number(text: str, least: int, what: str, most: int | None = None) -> int:
    try:
        n = int(text)
    except ValueError:
        n = least - 1
    if n < least or (most is not None and n > most):
        span = f"of at least {least}" if most is None else f"from {least} to {most}"
        raise argparse.ArgumentTypeError(f"expected {what}, a whole number {span}, got {text!r}")
    return n


def seed(text: str) -> int:
    """An argparse type: a seed, which numpy's generators take only as a whole number >= 0."""
    return _whole_number(text, 0, "a seed")


def _number_within(text: str, least: float, most: float, what: str, hint: str = "") -> float:
    try:
        number = float(text)
    except ValueError:
        number = float("nan")
    if not least <= number <= most:  # NaN too
        raise argparse.ArgumentTypeError(f"expected {what} from {least:g} to {most:g}, got {text!r}{hint}")
    return number


def voxel_metres(text: str) -> float:
    """An argparse type: a voxel size in metres, from 1 mm to 10 cm. Under a millimetre no depth sensor's
    points fill voxels (a cloud of 5 clumps gave 0 primitives at 1e-6 m); beyond 10 cm a voxel holds a part."""
    return _number_within(text, 0.001, 0.1, "a voxel size in metres", f" (the default is {DEFAULT_VOXEL_SIZE}; "
                          "a value in millimetres is 1000x too big)")


def noise_scale(text: str) -> float:
    """An argparse type: a sensor's depth noise as a multiple of a Kinect v1's, from 0.1 to 10."""
    return _number_within(text, 0.1, 10, "the sensor's noise as a multiple of a Kinect v1's,")


def at_least_one(text: str) -> int:
    """An argparse type: a count of at least 1 (and at most a billion: progress bars take no more)."""
    return _whole_number(text, 1, "a count", most=10**9)


def run_parsed(parser: argparse.ArgumentParser, argv: list[str] | None) -> int:
    """Run the chosen subcommand; a PsorrError becomes one line on stderr and exit status 2."""
    args = parser.parse_args(argv)

    def one_line(message, category, filename, lineno, file=None, line=None):
        # A warning for the user (an unwritable cache), not a source line of ours to read; on a line of its
        # own, not at the end of a progress bar's.
        from tqdm import tqdm

        tqdm.write(f"{parser.prog} {args.command}: warning: {message}", file=sys.stderr)

    try:
        with warnings.catch_warnings():
            warnings.showwarning = one_line
            return args.run(args)
    except PsorrError as exc:
        print(f"{parser.prog} {args.command}: error: {exc}", file=sys.stderr)
        return 2


def main(argv: list[str] | None = None) -> int:
    return run_parsed(build_parser(), argv)


if __name__ == "__main__":
    sys.exit(main())
