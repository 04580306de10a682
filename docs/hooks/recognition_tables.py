"""The recognition benchmarks' tables (decomposition, kernels, false detections, Table 1, compiled
verification, peers, sensors, point density, colour segmentation, PSG), each from its ``benchmarks/results/*.json``."""

from __future__ import annotations

import statistics

from tables_common import benchmark_module, frac, load, met, table

# ---- decomposition of the OSD learn set (benchmarks/decompose.py) -------------------------------------------

OSD_GROUPS = (("boxes (learn0-32)", range(0, 33)), ("cylinders (learn33-44)", range(33, 45)))


def decompose_summary() -> str:
    data = load("decompose_osd")
    rows = [[name, f"{s['median_ms']:.0f}", f"{s['coverage']:.3f}", f"{s['purity']:.3f}"]
            for name, s in data["summary"].items()]
    rows.append(["target", "< 150", ">= 0.85", ">= 0.95"])
    targets = ", ".join(f"{k} {'met' if v else 'missed'}" for k, v in data["targets_met"].items())
    return (table(["method (45 clouds, 640x480)", "median ms, 1 core", "object coverage", "object purity"], rows,
                  "lrrr") + f"\n\nTargets: {targets}.")


def decompose_groups() -> str:
    scenes = {int(s["scene"].removeprefix("learn")): s for s in load("decompose_osd")["scenes"]}
    rows = []
    for name, indices in OSD_GROUPS:
        group = [scenes[i] for i in indices if i in scenes]
        ms = [s["ms"] for s in group]
        peer = [s["peer_ms"] for s in group]
        rows.append([name, len(group), f"{statistics.median(ms):.0f} ({min(ms):.0f}-{max(ms):.0f})",
                     f"{statistics.mean(s['prims'] for s in group):.1f}",
                     f"{statistics.mean(s['cov'] for s in group):.3f}",
                     f"{statistics.mean(s['pur'] for s in group):.3f}",
                     f"{statistics.median(peer):.0f}", f"{statistics.mean(s['peer_cov'] for s in group):.3f}"])
    return table(["scenes", "clouds", "psorr ms, median (range)", "primitives, mean", "coverage", "purity",
                  "Open3D loop ms", "Open3D coverage"], rows, "lrrrrrrr")


# ---- kernels (benchmarks/kernels.py) ---------------------------------------------------------------------------

def kernels_pcd() -> str:
    rows = [[r["file"], r["points"], f"{r['psorr_ms']:.1f}", f"{r['open3d_ms']:.1f}",
             f"{r['open3d_ms'] / r['psorr_ms']:.2f}"] for r in load("kernels")["pcd_reads"]]
    return table(["file", "points", "psorr ms", "Open3D ms", "Open3D / psorr"], rows, "lrrrr")


def kernels_boxes() -> str:
    data = load("kernels")
    rows = [[r["method"], r["pairs"], f"{r['us_per_pair']:.1f}", f"{r['max_rel_diff_vs_qhull']:.1e}"]
            for r in data["box_intersection"]]
    targets = ", ".join(f"{k} {'met' if v else 'missed'}" for k, v in data["targets_met"].items())
    return (table(["method", "pairs", "us per pair", "largest difference from Qhull (share of box volume)"], rows,
                  "lrrr") + f"\n\nTargets: {targets}.")


# ---- false detections on the OSD learn set (benchmarks/osd_false_positives.py) ----------------------------------

def osd_false_positives() -> str:
    data = load("osd_false_positives")
    groups = list(dict.fromkeys(s["group"] for clouds in data.values() for s in clouds))  # in scene order
    rows = []
    for method, clouds in data.items():
        dets = [d for s in clouds for d in s["detections"]]
        per_group = [sum(len(s["detections"]) for s in clouds if s["group"] == g) for g in groups]
        rows.append([method, len(dets), sum(1 for s in clouds if s["detections"]),
                     sum(1 for d in dets if d["score"] >= 0.8), *per_group])
    return table(["method (45 clouds, all 8 parts as candidates)", "false detections", "clouds with any",
                  "score >= 0.8", *groups], rows, "l" + "r" * (3 + len(groups)))


def osd_false_by_model() -> str:
    rows = []
    for method, clouds in load("osd_false_positives").items():
        counts: dict[str, int] = {}
        for s in clouds:
            for d in s["detections"]:
                counts[d["model"]] = counts.get(d["model"], 0) + 1
        rows.append([method, ", ".join(f"{m} {n}" for m, n in sorted(counts.items(), key=lambda kv: -kv[1])) or "-"])
    return table(["method", "false detections by model"], rows)


# ---- the paper's Table 1 (benchmarks/table1.py, whose own report formats the cases) ----------------------------

def _table1_report():
    return benchmark_module("table1_report")


def table1_summary() -> str:
    report = _table1_report()
    runs = load("table1")["runs"]
    ratios = report.summary(runs, report.cells(runs))[1]
    t, ps, orr = ratios["totals"], ratios["totals"]["psorr"], ratios["totals"]["orr"]
    n = ps["runs"]
    rows = [
        ["verification ms per scene (mean)", f"{ps['verify_ms_per_scene']:.1f}", f"{orr['verify_ms_per_scene']:.0f}",
         f"PSORR <= 1/20 of ORR's: {met(ratios['met']['verification'])} (1/{1 / ratios['verify_ratio']:.0f})"],
        ["recognised (ADD < 0.1 d)", f"{ps['recognised']}/{n}", f"{orr['recognised']}/{orr['runs']}",
         f"equal or better: {met(ratios['met']['recognition'])} over all runs"
         + (f", not in {len(ratios['cases_worse'])} of the cases" if ratios["cases_worse"] else ", and in every case")],
        ["hypotheses", ps["hypotheses"], orr["hypotheses"], f"1/{1 / ratios['hypotheses_ratio']:.0f} (not a target)"],
        ["verification us per hypothesis", f"{t['psorr']['verify_us_per_hypothesis']:.0f}",
         f"{t['orr']['verify_us_per_hypothesis']:.0f}", "not a target (50x per hypothesis was withdrawn)"],
    ]
    return table([f"over all {n} runs per method", "PSORR", "ORR (Papazov's, dense pairs)", "target"], rows, "lrrl")


def table1_headline() -> str:
    """Table 1 in one line, for the README and the benchmarks' index."""
    report = _table1_report()
    runs = load("table1")["runs"]
    ratios = report.summary(runs, report.cells(runs))[1]
    ps, orr = ratios["totals"]["psorr"], ratios["totals"]["orr"]
    return (f"PSORR's verification 1/{1 / ratios['verify_ratio']:.0f} of ORR's a scene (target 1/20: "
            f"{met(ratios['met']['verification'])}), {ps['verify_ms_per_scene']:.1f} against "
            f"{orr['verify_ms_per_scene']:.0f} ms, with 1/{1 / ratios['hypotheses_ratio']:.0f} of its hypotheses; "
            f"recognised {ps['recognised']}/{ps['runs']} against ORR's {orr['recognised']}/{orr['runs']}")


def table1_cases() -> str:
    report = _table1_report()
    return report.table_markdown(report.cells(load("table1")["runs"]))


def table1_target() -> str:
    report = _table1_report()
    runs = load("table1")["runs"]
    return report.summary(runs, report.cells(runs))[0]


# ---- verification compiled (benchmarks/verify_compiled.py) -----------------------------------------------------

def verify_compiled() -> str:
    data = load("verify_compiled")
    p, o = data["methods"]["psorr"], data["methods"]["orr"]
    ratio = data["ratios"]
    rows = [["numpy, both (the library)", f"{p['numpy_us']:.1f}", f"{o['numpy_us']:.1f}", f"{ratio['numpy']:.1f}"],
            ["compiled, both", f"{p['compiled_us']:.1f}", f"{o['compiled_us']:.1f}", f"{ratio['compiled']:.1f}"],
            ["compiled PSORR against numpy ORR", f"{p['compiled_us']:.1f}", f"{o['numpy_us']:.1f}",
             f"{ratio['mixed']:.1f}"]]
    return table(["per hypothesis", "PSORR us", "ORR us", f"ORR / PSORR (target {data['target']:.0f})"], rows, "lrrr")


def verify_compiled_detail() -> str:
    data = load("verify_compiled")
    rows = [[name.upper(), m["hypotheses"], m["box_hypotheses"], f"{m['numpy_us']:.1f}", f"{m['compiled_us']:.1f}",
             f"{m['numpy_us'] / m['compiled_us']:.1f}", f"{data['measured_in_recognition_us'][name]:.1f}"]
            for name, m in data["methods"].items()]
    pairs = data["exact_box_pairs"]
    return (table(["method", "hypotheses", "of them box-scored", "numpy us / hyp", "compiled us / hyp",
                   "numpy / compiled", "us / hyp inside recognition"], rows, "lrrrrrr")
            + f"\n\nExact box intersections: {pairs['pairs']} pairs, {pairs['numpy_us_per_pair']:.1f} us each in "
              f"numpy, {pairs['compiled_us_per_pair']:.1f} us compiled (ratios within {pairs['max_ratio_diff']:.1e}).")


# ---- against peers (benchmarks/peers.py) -----------------------------------------------------------------------

PEER_NAMES = {"psorr": "psorr", "psg": "psg (ours)", "auto": "auto (ours: psg for large models)", "orr": "orr (ours)",
              "fpfh": "Open3D FPFH + RANSAC + ICP", "opencv_ppf": "OpenCV PPF3DDetector + ICP"}


def peers() -> str:
    data = load("peers")
    n_scenes = len(data["scenes"])
    rows = []
    for method, r in data["results"].items():
        (s_found, s_n, s_false), (c_found, c_n, c_false) = r["single"], r["clutter"]
        rows.append([PEER_NAMES.get(method, method), frac(s_found, s_n), frac(c_found, c_n),
                     f"{(s_false + c_false) / n_scenes:.2f}", f"{statistics.median(r['ms']):.0f}"])
    rows.append(["target (psorr)", ">= 0.95", ">= 0.85", "", "<= 1/10 of FPFH's"])
    share = statistics.median(data["results"]["psorr"]["ms"]) / statistics.median(data["results"]["fpfh"]["ms"])
    return (table(["method", "single-part recall", "4-part clutter + occluder recall", "false positives / scene",
                   "median ms / scene"], rows, "lrrrr")
            + f"\n\nPSORR's median time is {share:.3f} of FPFH's (target <= 0.10: {met(share <= 0.1)}).")


def peers_per_scene() -> str:
    data = load("peers")
    psorr, fpfh = data["results"]["psorr"]["ms"], data["results"]["fpfh"]["ms"]
    shares = [a / b for a, b in zip(psorr, fpfh, strict=True)]
    return table(["PSORR / FPFH time per scene", "min", "median", "max"],
                 [[f"{len(shares)} scenes", f"{min(shares):.2f}", f"{statistics.median(shares):.2f}",
                   f"{max(shares):.2f}"]], "lrrr")


# ---- other sensors (benchmarks/sensors.py) ---------------------------------------------------------------------

def sensors() -> str:
    rows = [[r["sensor"], r["cloud"], frac(r["found"], r["instances"]), r["false"],
             f"{statistics.median(r['ms']) / 1e3:.1f}"] for r in load("sensors")["rows"]]
    return table(["sensor", "cloud", "recall", "false detections", "median s / scene"], rows, "llrrr")


def sensors_headline(rows) -> str:
    outcomes = {(r["found"], r["instances"], r["false"]) for r in rows}
    if len(outcomes) == 1:
        found, n, false = outcomes.pop()
        return (f"{found}/{n} parts, {false} false detections, from each of the {len(rows)} clouds (two sensors, "
                "organised or stripped of NaNs)")
    return "; ".join(f"{r['sensor']}, {r['cloud']}: {r['found']}/{r['instances']}, {r['false']} false" for r in rows)


# ---- point density (benchmarks/density.py) ---------------------------------------------------------------------

def density() -> str:
    data = load("density")
    rows = []
    for r in data["rows"]:
        found = frac(r["found"], r["instances"]) if "found" in r else ""
        rows.append([r["scene"], f"{r['points'] / 1e6:.2f}M", f"{r['sampled'] / 1e6:.2f}M",
                     ", ".join(map(str, r["primitives"])), f"{r['ms']:.0f}",
                     ", ".join(map(str, r["peer_planes"])), f"{r['peer_ms']:.0f}", found, str(r.get("false", "")),
                     f"{r['recognize_ms']:.0f}" if "recognize_ms" in r else ""])
    verdicts = "\n".join(f"- {v}" for v in data["verdicts"])
    return table(["scene", "points", "sampled", "PSORR primitives (per draw)", "decompose ms", "Open3D planes",
                  "Open3D ms", "found", "false", "recognize ms"], rows, "lrrlrlrrrr") + "\n\n" + verdicts


# ---- colour segmentation of the OSD learn set (benchmarks/segment_osd.py) ---------------------------------------

def segment_osd() -> str:
    data = load("segment_osd")
    rows = [[name, f"{s['iou']:.3f}", f"{s['over']:.2f}", f"{s['under']:.2f}", f"{s['median_ms']:.0f}"]
            for name, s in data["summary"].items()]
    rows.append(["target", ">= 0.85", "", "", "< 300"])
    targets = ", ".join(f"{k} {'met' if v else 'missed'}" for k, v in data["targets_met"].items())
    return (table(["method (45 clouds, 112 objects)", "mean object IoU", "over-segmented", "under-segmented",
                   "median ms, 1 core"], rows, "lrrrr") + f"\n\nTargets: {targets}.")


# ---- PSG matching against PSORR (benchmarks/psg.py) -------------------------------------------------------------

def psg() -> str:
    """benchmarks/psg.py: its report's own table (benchmarks/psg_report.py) and verdicts."""
    data = load("psg")
    header = data["table"]["header"]
    verdicts = "\n".join(f"- {v}" for v in data["verdicts"])
    return table(header, data["table"]["cells"], "l" + "r" * (len(header) - 1)) + "\n\n" + verdicts


def rerun_overhead() -> str:
    """benchmarks/rerun_overhead.py: what a Rerun recording adds to a recognition."""
    d = load("rerun_overhead")
    rows = [["plain", f"{d['plain_ms_median']:.0f}"], ["recorded (--rerun)", f"{d['recorded_ms_median']:.0f}"]]
    return table(["", "median ms a scene"], rows, "lr") + (
        f"\n\n{d['scenes']} scenes of the peers benchmark, 1 core: recording adds {d['added']:.1%} in all (target at "
        f"most {d['target']:.0%}: {met(d['added'] <= d['target'])}); the same detections in {d['same_detections']}/"
        f"{d['scenes']} scenes; recordings of {d['rrd_mb_median']:.1f} MB (median), {d['rrd_mb_max']:.1f} MB at most."
        f"\n\nA demo episode's recording (`psorr-sim run tasks/demo.yaml --rerun`, seed 0, recognised poses, the "
        f"person about) takes {d['episode_rrd_mb']:.1f} MB (target under {d['episode_target_mb']:.0f} MB: "
        f"{met(d['episode_rrd_mb'] < d['episode_target_mb'])}).")
