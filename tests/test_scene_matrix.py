#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""scene_matrix --repeats (bench/sim/scene_matrix.cpp): a quick scene run twice per midphase
reports each measure's median, their ratio, and the two paired ratios; --repeats 0 is refused.
Usage: test_scene_matrix.py SCENE_MATRIX SCRATCH_DIR"""
import json
import math
import os
import subprocess
import sys

binary, scratch = sys.argv[1], sys.argv[2]
os.makedirs(scratch, exist_ok=True)
out_json = os.path.join(scratch, "scene_matrix.json")
out_md = os.path.join(scratch, "scene_matrix.md")
failed = 0


def check(ok, what):
    global failed
    if not ok:
        print("FAILED:", what)
        failed += 1


subprocess.run([binary, "--quick", "--repeats", "2", "--only", "sphere, rough", "--engines", "ode", "--json", out_json,
                "--markdown", out_md], check=True, stdout=subprocess.DEVNULL)
rows = json.load(open(out_json))
collision = [r for r in rows if r["metric"] == "collision_ms_per_step"]
check(len(collision) == 2, "one collision row per phase, got %d" % len(collision))
for r in collision:
    check(r["repeats"] == 2, "%s: repeats %r" % (r["case"], r["repeats"]))
    paired = r.get("paired_ratios", [])
    check(len(paired) == 2 and all(math.isfinite(p) and p > 0 for p in paired),
          "%s: two positive paired ratios, got %r" % (r["case"], paired))
    ours, theirs = r.get("boxtree_runs", []), r.get("peer_runs", [])
    check(len(ours) == 2 and len(theirs) == 2, "%s: both runs of each midphase" % r["case"])
    if len(ours) == 2 and len(theirs) == 2:
        check(r["boxtree"] == (ours[0] + ours[1]) / 2 and r["peer_value"] == (theirs[0] + theirs[1]) / 2,
              "%s: the medians of the runs" % r["case"])
        check(all(abs(paired[i] - ours[i] / theirs[i]) <= 1e-12 * paired[i] for i in range(len(paired))),
              "%s: each paired ratio is its pair's" % r["case"])
    check(abs(r["ratio"] - r["boxtree"] / r["peer_value"]) <= 1e-12 * r["ratio"],
          "%s: the ratio is the medians' ratio" % r["case"])
md = open(out_md).read()
check("2 runs each" in md, "the markdown says how many runs")
check("–" in md.split("| scene (bodies")[1], "the markdown gives the paired ratios' range")

refused = subprocess.run([binary, "--quick", "--repeats", "0", "--only", "sphere, rough"], capture_output=True,
                         text=True)
check(refused.returncode != 0 and "repeats" in refused.stderr, "--repeats 0 is refused with a message")
print("test_scene_matrix: %s" % ("FAILED" if failed else "passed"))
sys.exit(1 if failed else 0)
