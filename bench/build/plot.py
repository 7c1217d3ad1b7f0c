#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Plots build_bench's CSV: build time and hierarchy bytes per facet against the facet count.

usage: plot.py build_memory.csv OUT_DIR   (writes OUT_DIR/build_time.png, OUT_DIR/build_bytes.png)
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    series = defaultdict(list)  # engine -> [(facets, seconds, bytes_per_facet, kind)]
    with open(sys.argv[1], newline="") as f:
        for row in csv.DictReader(f):
            series[row["engine"]].append(
                (int(row["facets"]), float(row["build_seconds"]), float(row["bytes_per_facet"]), row["kind"]))
    out = sys.argv[2]
    for column, name, ylabel, log_y in ((1, "build_time.png", "build time (s, single thread)", True),
                                        (2, "build_bytes.png", "hierarchy bytes per facet", False)):
        fig, ax = plt.subplots(figsize=(8, 5.5))
        colors = plt.get_cmap("tab20").colors  # 20 distinct colours: one per engine
        for index, (engine, points) in enumerate(sorted(series.items())):
            points.sort()
            boxtree = points[0][3] == "boxtree"
            ax.plot([p[0] for p in points], [p[column] for p in points], marker="o" if boxtree else "s",
                    linestyle="-" if boxtree else "--", color=colors[index % len(colors)], label=engine)
        if column == 1:  # reference slope: linear growth
            xs = sorted({p[0] for pts in series.values() for p in pts})
            if xs:
                ref = [1e-6 * x for x in xs]
                ax.plot(xs, ref, color="gray", linewidth=0.8, linestyle=":", label="1 us per facet (linear)")
        ax.set_xscale("log")
        if log_y:
            ax.set_yscale("log")
        ax.set_xlabel("facets (fractal terrain)")
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
        fig.tight_layout()
        fig.savefig(f"{out}/{name}", dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    main()
