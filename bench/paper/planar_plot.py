#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Plots of bench/paper/results/planar/*.csv (written by planar_bench): planar height and
stabbing number against the paper's bounds, build and point-location time, and the stabbing
number on Section 5's constructions beside random spheres and terrains."""
import csv
import math
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

out = sys.argv[1] if len(sys.argv) > 1 else "bench/paper/results/planar"


def rows(name):
    with open(f"{out}/{name}") as f:
        return list(csv.DictReader(f))


planar = defaultdict(list)
for r in rows("planar.csv"):
    planar[r["generator"]].append(r)

# Height and stabbing number vs n, with log2 n and the paper's 2 * height.
fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
for g, rs in planar.items():
    n = [int(r["n"]) for r in rs]
    axes[0].plot(n, [int(r["height"]) for r in rs], "o-", label=g)
    axes[1].plot(n, [int(r["stabbing"]) for r in rs], "o-", label=g)
    axes[1].plot(n, [int(r["two_height"]) for r in rs], ":", color=axes[1].lines[-1].get_color(), alpha=0.6)
ns = sorted({int(r["n"]) for rs in planar.values() for r in rs})
axes[0].plot(ns, [math.log2(x) for x in ns], "k--", label="log2 n (binary lower bound)")
axes[0].plot(ns, [math.log(x) / math.log(12 / 11) for x in ns], "k:", label="log_{12/11} n (Thm 2.2 bound)")
axes[0].set_ylim(0, 60)
axes[0].set_title("Planar boxtree height")
axes[1].set_title("Stabbing number (max #node boxes over a point); dotted: 2*height")
for ax in axes:
    ax.set_xscale("log")
    ax.set_xlabel("n (rectangles)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(f"{out}/planar_height_stabbing.png", dpi=110)

# Build time (per cell: flat = linear) and point-location time.
fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
for g, rs in planar.items():
    n = [int(r["n"]) for r in rs]
    axes[0].plot(n, [1e9 * float(r["build_s"]) / int(r["n"]) for r in rs], "o-", label=f"{g} build")
    axes[0].plot(n, [1e9 * float(r["validate_s"]) / int(r["n"]) for r in rs], "x:", color=axes[0].lines[-1].get_color(), alpha=0.6)
    axes[1].plot(n, [float(r["locate_ns"]) for r in rs], "o-", label=g)
axes[0].set_title("Build time per rectangle (ns); dotted: input validation")
axes[1].set_title("Point location: ns per query (random points)")
for ax in axes:
    ax.set_xscale("log")
    ax.set_xlabel("n (rectangles)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(f"{out}/planar_time.png", dpi=110)

# Lower bounds: stabbing number vs facets per construction and method.
lb = defaultdict(list)
for r in rows("lower_bounds.csv"):
    lb[(r["construction"], r["method"])].append(r)
constructions = ["cone", "polytope", "sphere", "terrain"]
fig, axes = plt.subplots(1, 4, figsize=(18, 4.5))
for ax, c in zip(axes, constructions):
    for (cc, m), rs in lb.items():
        if cc != c:
            continue
        ax.plot([int(r["n"]) for r in rs], [int(r["stabbing"]) for r in rs], "o-", label=m, markersize=3)
    ax.set_title({"cone": "cone over (n-1)-gon", "polytope": "Sec. 5 polytope (n segments)",
                  "sphere": "random sphere (n points)", "terrain": "fractal terrain (n cells)"}[c])
    ax.set_xlabel("n")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
axes[0].set_ylabel("stabbing number (max #volumes met by a line)")
fig.tight_layout()
fig.savefig(f"{out}/lower_bounds_stabbing.png", dpi=110)
print("plots written to", out)
