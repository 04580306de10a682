"""The `psorr` commands that label every point of a cloud: decompose (primitives) and segment (objects).
Results go to stdout; progress and logs to stderr."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from psorr.checks.clouds import require_sensor_metres
from psorr.errors import CloudFileError, InvalidInputError


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _labelling_input(args):
    """The cloud of a command that labels every point (decompose, segment): its --out and --png checked
    first, then the cloud read and checked for metres in the sensor frame."""
    from psorr.cli import check_output  # here: psorr.cli imports this module
    from psorr.io.clouds import read_cloud

    check_output(args.out, "--out", ".npy")
    check_output(args.png, "--png", ".png")
    cloud = read_cloud(args.cloud)
    require_sensor_metres(cloud, str(args.cloud))
    _log(f"read {args.cloud}: {len(cloud)} points, {int(cloud.valid_mask.sum())} finite")
    return cloud


def _write_labels(path: str | None, labels: np.ndarray) -> None:
    if path:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        np.save(path, labels.astype(np.int64))
        _log(f"wrote {len(labels)} labels to {path}")


def decompose_command(args) -> int:
    """psorr decompose: print (or --json) the primitives and shape graph of a cloud."""
    from psorr.cli import rerun_logger  # here: psorr.cli imports this module
    from psorr.decomposition import DecomposeParams, decompose

    logger = rerun_logger(args.rerun)  # first: a missing extra is told before the cloud is read
    cloud = _labelling_input(args)
    params = DecomposeParams() if args.voxel_size is None else DecomposeParams(voxel_size=args.voxel_size)
    try:
        result = decompose(cloud, params, np.random.default_rng(args.seed))
    except InvalidInputError as exc:
        # Too few points, or too few voxels at this size: a problem of this file, so it is named.
        raise CloudFileError(args.cloud, str(exc).replace("voxel_size", "--voxel-size")) from None
    graph = result.graph
    if logger is not None:
        with logger:
            logger.cloud(cloud)
            logger.decomposition("scene", cloud, result)
            logger.stage_ms("decomposition", result.stats.total_ms)
    _write_labels(args.out, result.labels)
    if args.png:
        from psorr.viz.render import save_decomposition_png

        save_decomposition_png(args.png, cloud, result.labels, graph,
                               title=f"{Path(args.cloud).name}: {len(graph)} primitives, "
                                     f"{len(graph.edges)} edges, {result.stats.total_ms:.0f} ms")
        _log(f"wrote picture to {args.png}")
    if args.json:
        record = {
            "primitives": [
                {"id": i, "kind": p.kind.value, "params": [round(v, 6) for v in p.params],
                 "n_points": p.n_points, "centroid": [round(float(v), 6) for v in p.centroid]}
                for i, p in enumerate(graph.primitives)
            ],
            "edges": [list(e) for e in graph.edges],
            "stats": {"total_ms": round(result.stats.total_ms, 3), "n_voxels": result.stats.n_voxels,
                      "n_hypotheses": result.stats.n_hypotheses, "n_merges": result.stats.n_merges},
        }
        print(json.dumps(record))
    else:
        print(f"{'id':>3} {'kind':<9} {'points':>7}  centroid (m)               detail")
        for i, p in enumerate(graph.primitives):
            c = " ".join(f"{v:+.3f}" for v in p.centroid)
            if p.kind.value == "plane":
                detail = "normal " + " ".join(f"{v:+.3f}" for v in p.normal)
            else:
                detail = f"radius {p.radius * 1000:.1f} mm, axis " + " ".join(f"{v:+.3f}" for v in p.axis)
            print(f"{i:>3} {p.kind.value:<9} {p.n_points:>7}  {c:<26} {detail}")
        print(f"{len(graph)} primitives, {len(graph.edges)} edges, {result.stats.total_ms:.1f} ms")
    return 0


def segment_command(args) -> int:
    """psorr segment: print (or --json) the segments of a cloud's table top."""
    from psorr.segment import SegmentParams, segment

    cloud = _labelling_input(args)
    if cloud.colors is None:
        _log(f"{args.cloud} has no colours: segmented by distance alone")
    params = SegmentParams() if args.creases else SegmentParams(crease_noise=None)
    result = segment(cloud, params, np.random.default_rng(args.seed))
    _write_labels(args.out, result.labels)
    if args.png:
        from psorr.viz.render import save_segmentation_png

        save_segmentation_png(args.png, cloud, result.labels, result.segments,
                              title=f"{Path(args.cloud).name}: {len(result.segments)} segments, "
                                    f"{result.stats.total_ms:.0f} ms")
        _log(f"wrote picture to {args.png}")
    rounded = [[round(float(v), 6) for v in s.centroid] for s in result.segments]
    if args.json:
        print(json.dumps({"segments": [
            {"id": s.id, "n_points": s.n_points, "centroid": c,
             "mean_rgb": None if s.mean_rgb is None else [round(float(v), 4) for v in s.mean_rgb]}
            for s, c in zip(result.segments, rounded)], "stats": {"total_ms": round(result.stats.total_ms, 3)}}))
    else:
        print(f"{'id':>3} {'points':>7}  centroid (m)               colour")
        for s, c in zip(result.segments, rounded):
            print(f"{s.id:>3} {s.n_points:>7}  {' '.join(f'{v:+.3f}' for v in c):<26} {s.colour or '-'}")
        print(f"{len(result.segments)} segments, {result.stats.total_ms:.1f} ms")
    return 0
