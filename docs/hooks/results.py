"""An mkdocs hook: the benchmark pages' tables, generated from ``benchmarks/results/*.json`` at build time.

A page asks for a table with a placeholder on a line of its own, ``<!-- table: NAME -->``; NAME is a key
of ``TABLES``. An unknown name, or a results file that is missing, fails the build, so a table can never
be stale or copied by hand. The benchmarks' pictures (``benchmarks/results/*.png``) are added to the site
at the same path, so a page under ``docs/benchmarks/`` shows one as ``results/NAME.png``.

The README's table of headline results is the ``headline`` table with links into ``docs/``; the build
fails when the README's copy (between ``<!-- headline: start -->`` and ``<!-- headline: end -->``) differs
from what the results give. ``python docs/hooks/results.py --readme`` rewrites that copy.
"""

from __future__ import annotations

import re
import statistics
import sys

import cell_tables as cell
import generalization_tables as generalization
import recognition_tables as recognition
from tables_common import RESULTS, ROOT, TableError, load, table

README = ROOT / "README.md"
DECISIONS = ROOT / "docs" / "decisions"
PLACEHOLDER = re.compile(r"^<!-- table: ([a-z0-9-]+) -->$", re.MULTILINE)
README_BLOCK = re.compile(r"(<!-- headline: start -->\n)(.*?)(<!-- headline: end -->)", re.DOTALL)
RECORD_TITLE = re.compile(r"^# (\d{4})\. (.+)$", re.MULTILINE)


# ---- headline results (the benchmarks' index page, and the README) ---------------------------------------------

def headline(base: str = "") -> str:
    """The results a newcomer asks about first, one line per benchmark; links go to ``base`` + page."""
    dec, pe = load("decompose_osd"), load("peers")
    sen, ep, osd = load("sensors"), load("episodes"), load("osd_false_positives")
    ps, fp = pe["results"]["psorr"], pe["results"]["fpfh"]
    share = statistics.median(ps["ms"]) / statistics.median(fp["ms"])
    rec = next(r for r in ep["rows"] if r["mode"] == "recognized")
    osd_false = sum(len(s["detections"]) for s in osd["psorr"])
    ora = next(r for r in ep["rows"] if r["mode"] == "oracle")
    d, o3 = dec["summary"]["psorr"], dec["summary"]["open3d segment_plane loop"]
    rows = [
        [f"[Decomposition, {len(dec['scenes'])} real Kinect clouds]({base}decompose.md)",
         f"object coverage {d['coverage']:.3f}, purity {d['purity']:.3f}, a median {d['median_ms']:.0f} ms a cloud "
         f"on one core (Open3D's plane loop: {o3['coverage']:.3f}, {o3['purity']:.3f})"],
        [f"[Against peers, {len(pe['scenes'])} seeded scenes]({base}peers.md)",
         f"{ps['single'][0]}/{ps['single'][1]} single parts, {ps['clutter'][0]}/{ps['clutter'][1]} in 4-part clutter "
         f"with an occluder, {(ps['single'][2] + ps['clutter'][2]) / len(pe['scenes']):.2f} false positives a scene; "
         f"{share:.3f} of Open3D FPFH's time"],
        [f"[The paper's Table 1]({base}table1.md)", recognition.table1_headline()],
        generalization.headline_row(base),
        generalization.library_size_row(base),
        [f"[Other sensors, {sen['clutter_scenes']} clutter scenes]({base}sensors.md)",
         recognition.sensors_headline(sen["rows"])],
        [f"[Real clouds without our parts]({base}osd-false-positives.md)",
         f"{osd_false} false detection{'' if osd_false == 1 else 's'} over {len(osd['psorr'])} OSD clouds"],
        [f"[Episodes, {rec['episodes']} seeded, a person reaching in]({base}episodes.md)",
         f"{_share(rec['grasp_success_rate'])} grasped, {_share(rec['place_success_rate'])} placed from recognised "
         f"poses (true poses: {_share(ora['grasp_success_rate'])}, {_share(ora['place_success_rate'])}); "
         f"{rec['wall_s_per_episode']:.1f} s a mean episode on one core"],
    ]
    return table(["benchmark", "result"], rows)


def _share(rate: float) -> str:
    """A success rate as a percentage, to one decimal unless whole: 99.5% is not rounded up to 100%."""
    return f"{rate:.0%}" if round(rate * 100, 1) == round(rate * 100) else f"{rate:.1%}"


# ---- the decision records' index (docs/decisions/NNNN-title.md) -----------------------------------------------

def decisions() -> str:
    rows = []
    for path in sorted(DECISIONS.glob("[0-9][0-9][0-9][0-9]-*.md")):
        title = RECORD_TITLE.search(path.read_text())
        if title is None or title.group(1) != path.name[:4]:
            raise TableError(f"{path.relative_to(ROOT)} must open with '# {path.name[:4]}. Title'")
        rows.append([title.group(1), f"[{title.group(2)}]({path.name})"])
    return table(["record", "decision"], rows, "rl")


TABLES = {
    "decompose": recognition.decompose_summary, "decompose-groups": recognition.decompose_groups,
    "kernels-pcd": recognition.kernels_pcd, "kernels-boxes": recognition.kernels_boxes,
    "osd-false-positives": recognition.osd_false_positives, "osd-false-by-model": recognition.osd_false_by_model,
    "table1": recognition.table1_summary, "table1-cases": recognition.table1_cases,
    "table1-target": recognition.table1_target,
    "verify-compiled": recognition.verify_compiled, "verify-compiled-detail": recognition.verify_compiled_detail,
    "peers": recognition.peers, "peers-per-scene": recognition.peers_per_scene,
    "sensors": recognition.sensors, "density": recognition.density, "segment-osd": recognition.segment_osd,
    "psg": recognition.psg, "rerun-overhead": recognition.rerun_overhead,
    **generalization.TABLES,
    "grasp-tolerance": cell.grasp_tolerance,
    "episodes": cell.episodes, "episodes-per-part": cell.episodes_per_part, "episodes-in-hand": cell.episodes_in_hand,
    **cell.task_tables("clutter"), **cell.task_tables("printed_parts"), "plans": cell.plans,
    "sweep-throughput": cell.sweep_throughput, "soak": cell.soak, "part-derivation": cell.part_derivation,
    "headline": headline,
    "decisions": decisions,
}


def render(markdown: str, where: str) -> str:
    def one(match: re.Match) -> str:
        name = match.group(1)
        if name not in TABLES:
            raise TableError(f"{where}: no table {name!r}; known: {', '.join(sorted(TABLES))}")
        return TABLES[name]()
    return PLACEHOLDER.sub(one, markdown)


def readme_headline() -> str:
    return headline(base="docs/benchmarks/") + "\n"


# ---- mkdocs events ---------------------------------------------------------------------------------------------

def on_config(config, **kwargs):
    found = README_BLOCK.search(README.read_text())
    if found is None:
        raise _plugin_error("README.md has no <!-- headline: start --> ... <!-- headline: end --> block")
    if found.group(2) != readme_headline():
        raise _plugin_error("README.md's headline table differs from benchmarks/results/*.json: "
                            "run `python docs/hooks/results.py --readme`")
    return config


def on_files(files, config, **kwargs):
    from mkdocs.structure.files import File

    for png in sorted(RESULTS.glob("*.png")):
        files.append(File.generated(config, f"benchmarks/results/{png.name}", abs_src_path=str(png)))
    return files


def on_page_markdown(markdown, page, config, files, **kwargs):
    try:
        return render(markdown, page.file.src_uri)
    except TableError as exc:
        raise _plugin_error(str(exc)) from None


def _plugin_error(message: str):
    from mkdocs.exceptions import PluginError

    return PluginError(message)


if __name__ == "__main__":
    if sys.argv[1:] != ["--readme"]:
        sys.exit("usage: python docs/hooks/results.py --readme   (rewrites README.md's headline table)")
    text = README.read_text()
    if README_BLOCK.search(text) is None:
        sys.exit("README.md has no <!-- headline: start --> ... <!-- headline: end --> block")
    README.write_text(README_BLOCK.sub(lambda m: m.group(1) + readme_headline() + m.group(3), text))
    print("README.md: headline table rewritten from benchmarks/results/*.json")
