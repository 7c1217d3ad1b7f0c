#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""bench/report.py --check (what `bash bench/run` and its --quick mode end with) fails when boxtree
differs from an exact reference, and passes when it does not. Synthetic results folders: one row
per agreement metric, each set to a disagreement in turn.
Usage: test_bench_report.py REPORT_PY SCRATCH_DIR"""
import json
import os
import shutil
import subprocess
import sys

report, scratch = sys.argv[1], sys.argv[2]
SECTIONS = ["simulation", "mesh_vs_mesh", "rays", "box_queries", "build_memory"]
failed = 0


def row(section, metric, boxtree, peer_value, ratio=None, method="aabb", peer="peer"):
    return {"section": section, "case": "case-1", "metric": metric, "boxtree_method": method, "boxtree": boxtree,
            "peer": peer, "peer_value": peer_value, "ratio": ratio}


def rows_with(disagreeing=None):
    counts = {"pairs_disagree": 0, "disagreeing_rays (count: ...)": 0, "missed_queries (must be 0)": 0}
    if disagreeing:
        counts[disagreeing] = 3
    return {
        "simulation": [row("simulation", "collision_ms_per_step", 1.0, 2.0, 0.5)],
        "mesh_vs_mesh": [row("mesh_vs_mesh", "seconds", 1.0, 4.0, 0.25),
                         row("mesh_vs_mesh", "pairs_disagree", counts["pairs_disagree"], 0, None, "all", "all sources")],
        "rays": [row("rays", "rays_per_second (higher is better)", 2.0, 1.0, 2.0),
                 row("rays", "disagreeing_rays (count: ...)", counts["disagreeing_rays (count: ...)"], 5, None, "obb-min")],
        "box_queries": [row("box_queries", "us_per_query (midphase only)", 1.0, 1.0, 1.0),
                        row("box_queries", "missed_queries (must be 0)", counts["missed_queries (must be 0)"], 0)],
        "build_memory": [row("build_memory", "build_seconds (lower is better)", 1.0, 1.0, 1.0)],
    }


def run(name, sections):
    global failed
    folder = os.path.join(scratch, name)
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    for section, rows in sections.items():
        with open(os.path.join(folder, section + ".json"), "w") as f:
            json.dump(rows, f)
    p = subprocess.run([sys.executable, report, "--results", folder, "--json", os.path.join(folder, "all.json"),
                        "--check"], capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr


code, out = run("agree", rows_with())
if code != 0:
    failed += 1
    print(f"FAIL: agreeing results rejected (exit {code}):\n{out}")
# A peer's own count (peer_value 5 disagreeing rays against this method) is information, not a failure.
for metric in ["pairs_disagree", "disagreeing_rays (count: ...)", "missed_queries (must be 0)"]:
    code, out = run("disagree-" + metric.split()[0], rows_with(metric))
    if code == 0 or "disagreement" not in out or metric.split()[0] not in out:
        failed += 1
        print(f"FAIL: a boxtree {metric} of 3 passed --check or was not named (exit {code}):\n{out}")
# A malformed ratio fails too.
bad = rows_with()
bad["simulation"][0]["ratio"] = 0.7
code, out = run("bad-ratio", bad)
if code == 0:
    failed += 1
    print(f"FAIL: a ratio that is not boxtree / peer_value passed --check:\n{out}")
print(f"test_bench_report: {'FAILED' if failed else 'ok'} ({failed} failures)")
sys.exit(1 if failed else 0)
