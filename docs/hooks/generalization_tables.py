"""The generalization benchmark's tables, from ``benchmarks/results/generalization.json`` by the benchmark's
own report code (benchmarks/generalization_report.py), so that the site and the script print the same; and the
library-size benchmark's (``library_size.json``, benchmarks/library_size_report.py)."""

from __future__ import annotations

from tables_common import benchmark_module, load


def _report():
    return benchmark_module("generalization_report")


def _rendered(name: str):
    def render() -> str:
        return getattr(_report(), name)(load("generalization"))
    return render


TABLES = {"generalization-scenes": _rendered("scenes_lines"), "generalization": _rendered("methods_table"),
          "generalization-targets": _rendered("targets_table"),
          "generalization-times": _rendered("times_table"), "generalization-sizes": _rendered("sizes_table"),
          "generalization-classes": _rendered("classes_table"), "generalization-parts": _rendered("parts_table"),
          "generalization-shapes": _rendered("shapes_table"),
          "library-size": lambda: benchmark_module("library_size_report").table(load("library_size")),
          "library-size-false": lambda: benchmark_module("library_size_report").false_table(load("library_size"))}


def library_size_row(base: str = "") -> list[str]:
    """The README's line of the library-size benchmark: per library size, what the same scenes give."""
    report = benchmark_module("library_size_report")
    rows = report.summary(load("library_size"))

    def each(value, form: str) -> str:
        return " / ".join(format(value(r), form) for r in rows)
    return [f"[Larger libraries, the same scenes]({base}library-size.md)",
            f"{each(lambda r: r['models'], 'd')} models: clutter and occlusion "
            f"{each(lambda r: report.recall(r['multi']), '.2f')}, false "
            f"{each(lambda r: r['false_per_scene'], '.2f')} a scene, median {each(lambda r: r['median_ms'], '.0f')} ms"]


def headline_row(base: str = "") -> list[str]:
    """The README's line: PSORR's recall and false detections on each half, against the issue's targets, and
    with its outline hypotheses on when the results hold that row."""
    data, report = load("generalization"), _report()

    def line(name: str, split: dict, method: str) -> str:
        s = report.summary(split, method)
        crowded = [a + b for a, b in zip(s["clutter"], s["occluded"])]
        return (f"{name} {s['single'][0]}/{s['single'][1]} alone, {crowded[0]}/{crowded[1]} in clutter and "
                f"occlusion, {s['false_per_scene']:.2f} false a scene")

    fewer = True
    for split in data["splits"].values():
        found = {m: report.recall(report.instances(split, m))[0] for m in split["methods"]}
        fewer &= all(n < found["psorr"] for m, n in found.items() if not m.startswith("psorr"))
    text = "; ".join(line(n, s, "psorr") for n, s in data["splits"].items())
    text += " (targets 0.95, 0.85 and 0.2: **missed**" + ("; each peer finds fewer" if fewer else "") + ")"
    parts = sum(len(split["parts"]) for split in data["splits"].values())
    return [f"[Parts we have never seen, {parts} real CAD parts]({base}generalization.md)", text]
