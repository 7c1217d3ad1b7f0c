#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Plots the paper's Figures 3-4 (average area / volume of node volumes per level) and the
Table 1 gap sweep from paper_bench's CSV output. Usage: plot.py RESULTS_DIR (Debian's
python3-matplotlib; run with /usr/bin/python3)."""
import csv
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLORS = plt.get_cmap("tab20").colors


def style(method, index):
    """One colour per method; hybrids dashed, peers dotted."""
    dash = "--" if "+aabb@" in method else ":" if method.startswith("fcl-") else "-"
    return dict(color=COLORS[index % len(COLORS)], linestyle=dash, marker="o", ms=3, label=method)


out = sys.argv[1]
levels = defaultdict(lambda: defaultdict(list))  # model -> method -> rows
with open(os.path.join(out, "levels.csv")) as f:
    for row in csv.DictReader(f):
        levels[row["model"]][row["method"]].append(row)

for quantity, label in (("avg_area", "average surface area"), ("avg_volume", "average volume")):
    models = sorted(levels)
    fig, axes = plt.subplots(1, len(models), figsize=(4.2 * len(models), 3.8))
    for ax, model in zip(axes, models):
        for i, (method, rows) in enumerate(sorted(levels[model].items())):
            rows = [r for r in rows if int(r["level"]) <= 8]  # the paper plots the lowest levels
            ax.plot([int(r["level"]) for r in rows], [float(r[quantity]) for r in rows], **style(method, i))
        ax.set_title(f"{model} ({levels[model][next(iter(levels[model]))][0]['nodes']} facets)")
        ax.set_xlabel("level (0 = leaves)")
        ax.set_yscale("log")
    axes[0].set_ylabel(label + " per node")
    axes[-1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, f"figure_{quantity}.png"), dpi=110)
    plt.close(fig)

sweep = defaultdict(lambda: defaultdict(list))  # pair -> method -> (gap, tests)
with open(os.path.join(out, "table1.csv")) as f:
    for row in csv.DictReader(f):
        sweep[row["pair"]][row["method"]].append((float(row["gap"]), int(row["bv_tests"])))
pairs = sorted(sweep)
fig, axes = plt.subplots(1, len(pairs), figsize=(4.2 * len(pairs), 3.8))
for ax, pair in zip(axes if len(pairs) > 1 else [axes], pairs):
    for i, (method, points) in enumerate(sorted(sweep[pair].items())):
        points.sort()
        ax.plot([max(g, 1e-4) for g, _ in points], [t for _, t in points], **style(method, i))
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_title(pair)
    ax.set_xlabel("gap (0 plotted at 1e-4)" if pair.startswith("spheres") else "gap")
(axes[0] if len(pairs) > 1 else axes).set_ylabel("volume-volume tests")
(axes[-1] if len(pairs) > 1 else axes).legend(fontsize=7)
fig.tight_layout()
fig.savefig(os.path.join(out, "table1_gap_sweep.png"), dpi=110)
print("plots written to", out)
