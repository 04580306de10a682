"""`psorr train`: a library trained from a user's meshes, written as one file that `psorr recognize` takes.
Results go to stdout; progress and logs to stderr."""

from __future__ import annotations

import json
import sys

from psorr.types import PrimitiveKind


def add_train_parser(sub, units: tuple[str, ...]) -> None:
    """The ``train`` subcommand on the ``psorr`` parser's subparsers ``sub``."""
    train = sub.add_parser("train", help="train models from meshes and save them as one library file (.npz)")
    train.add_argument("models", nargs="+", metavar="MODELS",
                       help="a folder of meshes (.stl/.obj/.ply/.step), or mesh files; each model is named by its "
                            "file stem")
    train.add_argument("--out", required=True, metavar="LIBRARY.npz",
                       help="the library file to write; psorr recognize LIBRARY.npz SCENE then starts at once")
    train.add_argument("--units", choices=units, default=None,
                       help="units of the meshes (default m, or a STEP file's own; meshes of implausible size are "
                            "refused without it)")
    train.add_argument("--json", action="store_true", help="print exactly one JSON line to stdout")
    train.set_defaults(run=train_command)


def train_command(args) -> int:
    from tqdm import tqdm

    from psorr.cli import check_output  # here: psorr.cli imports this module
    from psorr.errors import CloudFileError
    from psorr.library.sources import library_from_arguments

    out = check_output(args.out, "--out", ".npz")  # before training, not after it
    saved = next((m for m in args.models if str(m).lower().endswith(".npz")), None)
    if saved is not None:
        raise CloudFileError(saved, "is a saved library: psorr train takes meshes",
                             "pass the mesh files or their folder")
    library = library_from_arguments(args.models, units=args.units,
                                     progress=lambda xs: tqdm(xs, desc="training", file=sys.stderr))
    library.save(out)
    rows = [_row(m) for m in library.models]
    if args.json:
        print(json.dumps({"library": str(out), "models": rows, "train_ms": float(library.train_ms)}))
        return 0
    print(f"{'model':<24} {'diameter mm':>11} {'planes':>6} {'cylinders':>9}")
    for row in rows:
        print(f"{row['model']:<24} {row['diameter_m'] * 1e3:>11.1f} {row['planes']:>6} {row['cylinders']:>9}")
    print(f"{len(rows)} models in {out} ({library.train_ms:.0f} ms); psorr recognize {out} SCENE")
    return 0


def _row(model) -> dict:
    graph = model.graph
    return {"model": model.name, "diameter_m": float(model.diameter),
            "planes": graph.count(PrimitiveKind.PLANE), "cylinders": graph.count(PrimitiveKind.CYLINDER)}
