"""Table 1's report (benchmarks/table1.py): per-case counts and medians over seeds, the markdown table,
the summary against the issue's target and the bar chart."""

from __future__ import annotations

from pathlib import Path

import numpy as np

METHODS = ("psorr", "orr")
TARGET_HYP_RATIO = 1 / 20    # PSORR hypotheses <= this x ORR's
TARGET_VERIFY_SPEEDUP = 50.0  # ORR ms per hypothesis >= this x PSORR's


def _median(values):
    values = [v for v in values if v is not None]
    return float(np.median(values)) if values else None


def _fmt(value, spec: str, empty: str = "-") -> str:
    return empty if value is None else format(value, spec)


def cells(runs) -> list[dict]:
    """One row per (object, view, resolution, method): counts and medians over the seeds."""
    keys = []
    for r in runs:
        k = (r["object"], r["view"], r["resolution"], r["method"])
        if k not in keys:
            keys.append(k)
    rows = []
    for k in keys:
        rs = [r for r in runs if (r["object"], r["view"], r["resolution"], r["method"]) == k]
        hit = [r for r in rs if r["recognised"]]
        rows.append(dict(
            object=k[0], view=k[1], resolution=k[2], method=k[3], n=len(rs),
            points=_median([r["points"] for r in rs]), part_points=_median([r["part_points"] for r in rs]),
            hypotheses=_median([r["hypotheses"] for r in rs]),
            # A run with no hypotheses has no verification time per hypothesis.
            verify_ms=_median([r["verify_ms_per_hypothesis"] for r in rs if r["hypotheses"] > 0]),
            recognised=len(hit), wrong=sum(r["wrong"] for r in rs),
            twin_open=sum(r["twin_open"] for r in rs), twin_true=sum(r["twin_true"] for r in rs),
            add_mm=_median([r["add_mm"] for r in hit]), rot_deg=_median([r["rot_deg"] for r in hit]),
            best_add_mm=_median([r["add_mm"] for r in rs]),
            total_ms=_median([r["total_ms"] for r in rs])))
    return rows


def table_markdown(rows) -> str:
    lines = ["| object | view | resolution (points / on the part) | algorithm | hypotheses | verify ms / hyp "
             "| recognised "
             "| twin left open (the truth, of misses) | ADD mm | rot err deg | wrong-model dets | total ms |",
             "|---|---|---|---|---:|---:|---|---|---:|---:|---:|---:|"]
    for r in rows:
        add = _fmt(r["add_mm"], ".1f")
        if r["add_mm"] is None and r["best_add_mm"] is not None:
            add = f"({r['best_add_mm']:.0f})"  # nearest detection of the right model, not within 0.1 d
        lines.append(
            f"| {r['object']} | {r['view']} | {r['resolution']} ({r['points']:.0f} / {r['part_points']:.0f}) "
            f"| {r['method']} "
            f"| {_fmt(r['hypotheses'], '.0f')} | {_fmt(r['verify_ms'], '.3f')} "
            f"| {'yes' if r['recognised'] == r['n'] else 'no' if r['recognised'] == 0 else 'partly'} "
            f"{r['recognised']}/{r['n']} | {r['twin_open']}/{r['n']} ({r['twin_true']}) | {add} "
            f"| {_fmt(r['rot_deg'], '.1f')} | {r['wrong']} "
            f"| {_fmt(r['total_ms'], '.0f')} |")
    return "\n".join(lines)


def summary(runs, rows) -> tuple[str, dict]:
    """Ratios against the target, per case and over all runs."""
    by = {m: [r for r in runs if r["method"] == m] for m in METHODS}
    hyp = {m: sum(r["hypotheses"] for r in by[m]) for m in METHODS}
    # Verification time over all runs: total verify ms / total hypotheses.
    vms = {m: sum(r["verify_ms_per_hypothesis"] * r["hypotheses"] for r in by[m]) / max(hyp[m], 1) for m in METHODS}
    rec = {m: sum(r["recognised"] for r in by[m]) for m in METHODS}
    n = {m: len(by[m]) for m in METHODS}
    hyp_ratio = hyp["psorr"] / max(hyp["orr"], 1)
    speedup = vms["orr"] / vms["psorr"] if vms["psorr"] > 0 else None
    lines = ["| case | PSORR/ORR hypotheses | ORR/PSORR verify ms per hyp | recognised PSORR | recognised ORR |",
             "|---|---:|---:|---:|---:|"]
    cases_worse, cases_over, cases_none = [], [], []
    for p in [r for r in rows if r["method"] == "psorr"]:
        o = next(r for r in rows if r["method"] == "orr" and
                 (r["object"], r["view"], r["resolution"]) == (p["object"], p["view"], p["resolution"]))
        case = f"{p['object']} {p['view']} {p['resolution']}"
        hr = None if not o["hypotheses"] else p["hypotheses"] / o["hypotheses"]
        if hr is not None and hr > TARGET_HYP_RATIO:
            cases_over.append(f"{case} ({hr:.3f})")
        if not p["hypotheses"]:
            cases_none.append(case)
        sp = None if not p["verify_ms"] or o["verify_ms"] is None else o["verify_ms"] / p["verify_ms"]
        ratio = "0 (no pairs)" if not p["hypotheses"] else _fmt(hr, ".3f")
        lines.append(f"| {case} | {ratio} | {_fmt(sp, '.3f')} | {p['recognised']}/{p['n']} "
                     f"| {o['recognised']}/{o['n']} |")
        if p["recognised"] < o["recognised"]:
            cases_worse.append(case)
    lines.append(f"| **all runs** | **{hyp_ratio:.3f}** | **{_fmt(speedup, '.3f')}** "
                 f"| **{rec['psorr']}/{n['psorr']}** | **{rec['orr']}/{n['orr']}** |")
    met_hyp = hyp_ratio <= TARGET_HYP_RATIO
    met_speed = speedup is not None and speedup >= TARGET_VERIFY_SPEEDUP
    met_rec = rec["psorr"] >= rec["orr"] and not cases_worse
    verdict = [
        "",
        f"Target: PSORR uses <= 1/20 of ORR's hypotheses, >= {TARGET_VERIFY_SPEEDUP:.0f}x less verification "
        "time per hypothesis, at equal or better recognition.",
        f"- hypotheses: PSORR {hyp['psorr']} vs ORR {hyp['orr']} over all runs, ratio {hyp_ratio:.3f} "
        f"(target <= {TARGET_HYP_RATIO:.3f}): **{'met' if met_hyp else 'MISSED'}** over all runs"
        + (f"; per case above 1/20: {', '.join(cases_over)}" if cases_over else "; met in every case")
        + (f"; PSORR found no scene pairs at all (0 hypotheses) in: {', '.join(cases_none)}" if cases_none else ""),
        f"- verification ms per hypothesis: PSORR {vms['psorr']:.3f} vs ORR {vms['orr']:.3f}, ORR/PSORR = "
        f"{_fmt(speedup, '.3f')} (target >= {TARGET_VERIFY_SPEEDUP:.0f}): **{'met' if met_speed else 'MISSED'}**",
        f"- recognition: PSORR {rec['psorr']}/{n['psorr']}, ORR {rec['orr']}/{n['orr']}"
        + (f"; PSORR worse in: {', '.join(cases_worse)}" if cases_worse else "; PSORR never worse per case")
        + f": **{'met' if met_rec else 'MISSED'}**",
    ]
    return "\n".join(lines + verdict), dict(hypotheses_ratio=hyp_ratio, verify_speedup=speedup,
                                            recognised=rec, runs=n, met=dict(hypotheses=met_hyp,
                                                                             verification=met_speed,
                                                                             recognition=met_rec))


def plot(rows, path: Path) -> None:
    """Hypotheses and verification ms per hypothesis per case, PSORR beside ORR, as a PNG at path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    cases = [r for r in rows if r["method"] == "psorr"]
    labels = [f"{r['object'].replace('_', ' ')}\n{r['view']}, {r['resolution']}" for r in cases]
    x = np.arange(len(cases))
    width = 0.38
    fig, axes = plt.subplots(2, 1, figsize=(max(7, 1.15 * len(cases) + 2), 7.2), sharex=True)
    colors = {"psorr": "tab:blue", "orr": "tab:orange"}
    for ax, key, title in ((axes[0], "hypotheses", "hypotheses (median over seeds)"),
                           (axes[1], "verify_ms", "verification ms per hypothesis (median, 1 core)")):
        for i, method in enumerate(METHODS):
            mine = [next(r for r in rows if r["method"] == method and (r["object"], r["view"], r["resolution"])
                         == (c["object"], c["view"], c["resolution"])) for c in cases]
            vals = np.array([r[key] if r[key] else np.nan for r in mine], dtype=float)
            bars = ax.bar(x + (i - 0.5) * width, vals, width, color=colors[method], label=method)
            for b, r, v in zip(bars, mine, vals):
                text = f"{r['recognised']}/{r['n']}" if key == "hypotheses" else ""
                if np.isnan(v):
                    ax.text(b.get_x() + b.get_width() / 2, 0.03, "no hypotheses", ha="center", va="bottom",
                            fontsize=7, rotation=90, transform=ax.get_xaxis_transform())
                elif text:
                    ax.text(b.get_x() + b.get_width() / 2, v * 1.15, text, ha="center", va="bottom", fontsize=7)
        ax.set_yscale("log")
        ax.set_title(title, fontsize=10)
        ax.grid(axis="y", which="both", alpha=0.3)
    top = max((r["hypotheses"] or 1) for r in rows)
    axes[0].set_ylim(1, top * 5)
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="upper center", bbox_to_anchor=(0.5, 0.955), ncol=2, fontsize=8,
               frameon=False, title="bar labels above the hypotheses: recognised / seeds", title_fontsize=7.5)
    ms = [r["verify_ms"] for r in rows if r["verify_ms"]]
    if ms:  # whole decades, so the log bars have a common, readable base
        axes[1].set_ylim(10 ** np.floor(np.log10(min(ms))), 10 ** np.ceil(np.log10(max(ms)) + 0.3))
    for ax in axes:
        ax.yaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    axes[1].set_xticks(x, labels, fontsize=7.5)
    fig.suptitle("Table 1: PSORR vs ORR on single parts, library of all 8 catalog parts", fontsize=11)
    fig.tight_layout(rect=(0, 0, 1, 0.92))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
