#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The `boxtree` command line's contract: subcommands, options, JSON keys, error behaviour.
Usage: test_cli.py BOXTREE_BINARY SHARED_MESH_DIR SCRATCH_DIR
Prints 'N passed, N failed' and exits non-zero on any failure."""
import json
import os
import subprocess
import sys

binary, mesh_dir, scratch = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(scratch, exist_ok=True)
passed, failed = 0, 0


def run(*args, stdin=None):
    p = subprocess.run([binary, *args], input=stdin, capture_output=True, text=True, timeout=300)
    return p.returncode, p.stdout, p.stderr


def check(name, condition, detail=""):
    global passed, failed
    if condition:
        passed += 1
    else:
        failed += 1
        print(f"FAIL {name}: {detail}")


def write(name, text):
    path = os.path.join(scratch, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def expect_error(name, args, must_mention, stdin=None):
    code, out, err = run(*args, stdin=stdin)
    lines = [l for l in err.splitlines() if l.strip()]
    check(name + " exits non-zero", code != 0, f"exit {code}")
    check(name + " prints one line", len(lines) == 1, repr(err))
    for word in must_mention:
        check(f"{name} mentions {word!r}", word in err, repr(err))


# Two triangles covering the unit square in z = 0, and a unit cube (closed).
square = write("square.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n")
cube = write("cube.obj", "\n".join([
    "v 0 0 0", "v 1 0 0", "v 1 1 0", "v 0 1 0", "v 0 0 1", "v 1 0 1", "v 1 1 1", "v 0 1 1",
    "f 1 3 2", "f 1 4 3", "f 5 6 7", "f 5 7 8", "f 1 2 6", "f 1 6 5",
    "f 2 3 7", "f 2 7 6", "f 3 4 8", "f 3 8 7", "f 4 1 5", "f 4 5 8"]) + "\n")

# generate + info --json
terrain = os.path.join(scratch, "terrain.obj")
code, out, err = run("generate", "terrain", "--size", "32", "--seed", "3", "--out", terrain)
check("generate terrain", code == 0 and os.path.exists(terrain), err)
code, out, err = run("info", terrain, "--json")
check("info exit 0", code == 0, err)
info = json.loads(out)
for key in ["facets", "height", "nodes", "memory_bytes", "levels", "plane_cost"]:
    check(f"info has {key}", key in info)
check("info facets", info["facets"] == 2 * 32 * 32, info["facets"])
check("info nodes = 2n-1", info["nodes"] == 2 * info["facets"] - 1)
check("info levels cover all nodes", sum(l["nodes"] for l in info["levels"]) == info["nodes"])
check("info level keys", all(set(l) >= {"level", "nodes", "avg_area", "avg_volume"} for l in info["levels"]))
check("info level 0 are leaves", info["levels"][0]["level"] == 0 and info["levels"][0]["nodes"] == info["facets"])
check("info height", info["height"] == len(info["levels"]) - 1 and info["height"] <= 11 + 4, info["height"])
check("info plane_cost >= 1", info["plane_cost"] >= 1)
code, out2, err = run("info", terrain, "--json", "--method", "aabb", "--cost", "volume")
check("info --cost volume", code == 0 and json.loads(out2)["nodes"] == info["nodes"], err)
code, out, err = run("info", terrain)
check("info human-readable", code == 0 and "height" in out and "plane cost" in out, out)

# The real meshes are skipped when absent, except in CI (CI=true), where they are required.
bunny = os.path.join(mesh_dir, "stanford_bunny_res4.obj")
if os.path.exists(bunny):
    code, out, err = run("info", bunny, "--json")
    check("info bunny facets", code == 0 and json.loads(out)["facets"] == 948, out + err)
elif os.environ.get("CI") == "true":
    check("real meshes present (CI=true: they are required)", False, f"{bunny} not found")
else:
    print(f"note: {bunny} absent, real-mesh CLI check skipped")

# collide
code, out, err = run("collide", cube, cube, "--json")
res = json.loads(out) if code == 0 else {}
for key in ["pairs", "bv_tests", "leaf_tests", "seconds"]:
    check(f"collide has {key}", key in res, out + err)
# Cube against itself: each facet touches every facet sharing a vertex with it (and itself).
shared = 0
faces = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4), (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
for f in faces:
    for g in faces:
        shared += bool(set(f) & set(g))
check("collide cube self pairs (touching counts)", res.get("pairs") == shared, f"{res.get('pairs')} vs {shared}")
far = "1 0 0 5  0 1 0 0  0 0 1 0"
code, out, err = run("collide", cube, cube, "--transform", far, "--json")
check("collide far apart = 0 pairs", code == 0 and json.loads(out)["pairs"] == 0, out + err)
touch = "1 0 0 1  0 1 0 0  0 0 1 0"  # shifted by exactly one: the faces x=1 and x=0 coincide
code, out, err = run("collide", cube, cube, "--transform", touch, "--json")
check("collide touching faces intersect", code == 0 and json.loads(out)["pairs"] > 0, out + err)
rot = "0 -1 0 0.5  1 0 0 0.5  0 0 1 0.5"  # 90 degrees about z
code, out, err = run("collide", cube, cube, "--transform", rot, "--json")
check("collide rotated", code == 0 and json.loads(out)["pairs"] > 0, out + err)
code, out, err = run("collide", cube, cube, "--transform", "0.5 0 0 0.25  0 0.5 0 0.25  0 0 0.5 0.25", "--json")
check("collide non-rigid: small cube strictly inside = 0 pairs", code == 0 and json.loads(out)["pairs"] == 0, out + err)
code, out, err = run("collide", cube, cube, "--first", "--json")
check("collide --first", code == 0 and json.loads(out)["pairs"] == 1, out + err)
expect_error("collide bad transform count", ["collide", cube, cube, "--transform", "1 0 0"], ["--transform", "12"])
expect_error("collide bad transform token", ["collide", cube, cube, "--transform", "1 0 0 0 0 1 0 0 0 0 1 x"], ["--transform", "'x'"])
expect_error("collide nan transform", ["collide", cube, cube, "--transform", "1 0 0 0 0 1 0 0 0 0 1 nan"], ["--transform"])

# ray
rays = write("rays.txt", "# origin direction\n0.25 0.75 1  0 0 -2\n\n5 5 1 0 0 -1\n0.5 0.5 -1 0 0 1\n0.9 0.1 1 0 0 1\n")
code, out, err = run("ray", square, "--rays", rays, "--json")
lines = [json.loads(l) for l in out.splitlines()]
check("ray one line per ray", code == 0 and len(lines) == 4, out + err)
if len(lines) == 4:
    for l in lines:
        check("ray keys", {"hit", "facet", "t", "nodes_visited"} <= set(l), l)
    check("ray 1 hits facet 1 at t=0.5 (direction not normalized)", lines[0]["hit"] and lines[0]["facet"] == 1 and lines[0]["t"] == 0.5, lines[0])
    check("ray 2 misses", lines[1]["hit"] is False, lines[1])
    check("ray 3 hits the shared diagonal from below", lines[2]["hit"] and lines[2]["facet"] in (0, 1) and lines[2]["t"] == 1.0, lines[2])
    check("ray 4 points away: t >= 0 only", lines[3]["hit"] is False, lines[3])
code, out, err = run("ray", cube, "--rays", "-", "--json", stdin="0.5 0.5 0.5 1 1 1\n")
check("ray from stdin, inside the cube, through a corner", code == 0 and json.loads(out)["hit"] and abs(json.loads(out)["t"] - 0.5) < 1e-15, out + err)
bad_rays = write("bad_rays.txt", "0 0 1 0 0 -1\n\n0 0 1 0 0\n")
expect_error("ray short line", ["ray", square, "--rays", bad_rays], ["bad_rays.txt:3", "6 numbers"])
expect_error("ray zero direction", ["ray", square, "--rays", write("zero.txt", "0 0 1 0 0 0\n")], ["zero.txt:1", "zero"])
expect_error("ray missing file", ["ray", square, "--rays", os.path.join(scratch, "nope.txt")], ["nope.txt"])

# every method gives the same answers (the exact tests decide; the volumes only prune)
methods = ["aabb", "obb-all", "obb-max", "obb-min", "pie-max", "pie-min", "pie-max-general", "pie-min-general",
           "pie-min+aabb@2", "obb-min+aabb@3"]
bumpy = os.path.join(scratch, "bumpy.obj")
run("generate", "bumpy-sphere", "--size", "10", "--seed", "4", "--out", bumpy)
sphere_rays = write("sphere_rays.txt", "".join(f"{0.1 * i - 1} {0.05 * i} 3  0.01 {-0.02 * i} -1\n" for i in range(20)))
reference = None
for m in methods:
    code, info_out, err = run("info", bumpy, "--method", m, "--json")
    check(f"info --method {m}", code == 0 and json.loads(info_out)["nodes"] == 2 * json.loads(info_out)["facets"] - 1, err)
    code, col_out, err = run("collide", bumpy, bumpy, "--method", m, "--transform", rot, "--json")
    code2, ray_out, err2 = run("ray", bumpy, "--rays", sphere_rays, "--method", m, "--json")
    if code != 0 or code2 != 0:
        check(f"collide/ray --method {m}", False, err + err2)
        continue
    answer = (json.loads(col_out)["pairs"], [(r["facet"], r["t"]) for r in map(json.loads, ray_out.splitlines())])
    if reference is None:
        reference = answer
        check("the method check has intersecting pairs", answer[0] > 0, answer[0])
    check(f"--method {m} gives aabb's answers", answer == reference, f"{answer[0]} pairs vs {reference[0]}")

# errors common to all subcommands
for sub in (["info", square], ["collide", square, square], ["ray", square, "--rays", rays]):
    expect_error(f"{sub[0]} unknown method", [*sub, "--method", "octree"], ["octree", "aabb", "pie-min", "obb-all"])
    expect_error(f"{sub[0]} bad hybrid level", [*sub, "--method", "pie-min+aabb@0"], ["pie-min+aabb@0"])
expect_error("missing mesh", ["info", os.path.join(scratch, "missing.obj")], ["missing.obj"])
expect_error("bad index", ["info", write("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")], ["bad_index.obj"])
expect_error("unknown subcommand", ["explode"], ["explode"])
code, out, err = run("--help")
check("--help exits 0", code == 0 and "info" in out and "collide" in out and "ray" in out, out + err)
# --version: the project's version (boxtree/version.h, from CMake's project(VERSION)) on stdout.
code, out, err = run("--version")
check("--version exits 0 and prints 'boxtree X.Y.Z'", code == 0 and __import__("re").fullmatch(r"boxtree \d+\.\d+\.\d+\n", out) is not None,
      repr(out) + err)

# bad input (issue 9): every case exits non-zero with one line on stderr naming the file and the problem
def write_bytes(name, data):
    path = os.path.join(scratch, name)
    with open(path, "wb") as f:
        f.write(data)
    return path


import random
import struct
noise = random.Random(9)
garbage = bytes(noise.randrange(256) for _ in range(2000))
tri_stl = b"truncated".ljust(80, b" ") + struct.pack("<I", 4) + struct.pack("<12fH", *([0.0] * 12), 0) * 2
bad_inputs = [
    ("empty.obj", b"", ["empty.obj", "empty file"]),
    ("garbage.obj", garbage, ["garbage.obj", "binary data"]),
    ("garbage.stl", garbage, ["garbage.stl", "STL"]),
    ("garbage.ply", garbage, ["garbage.ply", "PLY"]),
    ("garbage.off", garbage, ["garbage.off", "OFF"]),
    ("truncated.stl", tri_stl, ["truncated.stl", "truncated binary STL"]),
    ("nan.obj", b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", ["nan.obj", "non-finite"]),
    ("inf.obj", b"v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n", ["inf.obj", "non-finite"]),
    ("beyond_1e50.obj", b"v 0 0 0\nv 1e60 0 0\nv 0 1 0\nf 1 2 3\n", ["beyond +-1e50"]),
    ("no_faces.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", ["no_faces.obj", "no facets"]),
    ("index_zero.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ["index_zero.obj", "index 0"]),
    ("index_negative.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", ["index_negative.obj", "-4"]),
    ("mesh.xyz", b"v 0 0 0\n", ["mesh.xyz", "unknown mesh file extension"]),
]
for name, data, words in bad_inputs:
    path = write_bytes(name, data)
    expect_error(f"info {name}", ["info", path], words)
    expect_error(f"collide with {name}", ["collide", square, path], words)
    expect_error(f"ray on {name}", ["ray", path, "--rays", rays], words)
os.makedirs(os.path.join(scratch, "a_directory.obj"), exist_ok=True)
expect_error("mesh is a directory", ["info", os.path.join(scratch, "a_directory.obj")], ["directory"])
expect_error("ray with NaN", ["ray", square, "--rays", write("nan_rays.txt", "0 0 1 nan 0 -1\n")], ["nan_rays.txt:1", "not finite"])
expect_error("generate --size 0", ["generate", "terrain", "--size", "0", "--out", os.path.join(scratch, "x.obj")], ["--size"])

# odd but valid meshes: they load, build and answer
huge = write("huge_1e30.obj", "v 1e30 0 0\nv 0 1e30 0\nv 0 0 1e30\nv -1e30 -1e30 -1e30\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n")
code, out, err = run("info", huge, "--json")
check("info on 1e30 coordinates", code == 0 and json.loads(out)["facets"] == 4, out + err)
degenerate = write("degenerate_only.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\nf 1 1 1\n")
code, out, err = run("info", degenerate, "--json")
check("info on degenerate facets only", code == 0 and json.loads(out)["nodes"] == 3, out + err)
# A tetrahedron 1e6 from the origin against itself: every facet touches every other (they share
# vertices), so all 16 pairs intersect, for every method.
far = write("far_1e6.obj", "v 1000000 1000000 1000000\nv 1000000.001 1000000 1000000\nv 1000000 1000000.001 1000000\n"
            "v 1000000 1000000 1000000.001\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n")
for m in ["aabb", "obb-min", "pie-max", "pie-min+aabb@1"]:
    code, out, err = run("collide", far, far, "--method", m, "--json")
    check(f"collide 1e6 offset, touching facets ({m})", code == 0 and json.loads(out)["pairs"] == 16, out + err)

print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed else 0)
