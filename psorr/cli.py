"""The `psorr` command line. Results go to stdout; progress and logs to stderr."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from psorr.errors import PsorrError


def _log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def _decompose(args) -> int:
    from psorr.decomposition import DecomposeParams, decompose
    from psorr.io import read_cloud

    cloud = read_cloud(args.cloud)
    _log(f"read {args.cloud}: {len(cloud)} points, {int(cloud.valid_mask.sum())} finite")
    params = DecomposeParams(voxel_size=args.voxel_size) if args.voxel_size else DecomposeParams()
    result = decompose(cloud, params, np.random.default_rng(args.seed))
    graph = result.graph
    if args.out:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        np.save(out, result.labels.astype(np.int64))
        _log(f"wrote {len(result.labels)} labels to {out}")
    if args.png:
        from psorr.render import save_decomposition_png

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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="psorr", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    dec = sub.add_parser("decompose", help="split a depth cloud into planes and cylinders")
    dec.add_argument("cloud", help="cloud file: .pcd, .ply, .xyz/.txt or .npy, metres, sensor frame")
    dec.add_argument("--out", metavar="LABELS.npy", help="write one int64 primitive index per input point (-1: none)")
    dec.add_argument("--json", action="store_true", help="print one JSON line instead of a table")
    dec.add_argument("--png", metavar="PICTURE.png", help="render the cloud coloured by primitive")
    dec.add_argument("--voxel-size", type=float, default=None, help="working resolution in metres (default 0.01)")
    dec.add_argument("--seed", type=int, default=0, help="seed of the RANSAC sampling (default 0)")
    dec.set_defaults(run=_decompose)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except PsorrError as exc:
        print(f"psorr {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
