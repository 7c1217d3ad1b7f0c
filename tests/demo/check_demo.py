#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Checks boxtree-demo headless runs (standard library only: PNGs are decoded with zlib).

  check_demo.py frames      DEMO ENGINE MIDPHASE DIR   one small run: frames written, not blank,
                                                       moving, bodies above the terrain at the end
  check_demo.py determinism DEMO ENGINE MIDPHASE DIR   two runs, same seed: identical frames and
                                                       final positions
  check_demo.py overlay     DEMO DIR                   the hierarchy overlay image is not blank
"""
import json
import os
import shutil
import struct
import subprocess
import sys
import zlib

# Small enough for a few seconds per run, also under ASan (llvmpipe renders in software).
SMALL = ["--bodies", "40", "--terrain-size", "32", "--steps", "90", "--every", "45",
         "--width", "160", "--height", "120", "--seed", "7"]
WIDTH, HEIGHT = 160, 120


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def read_png(path):
    """Returns (width, height, rows), rows = list of bytes objects of RGB triples."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail(f"{path}: not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, colour_type, _, _, interlace = header
    if depth != 8 or colour_type not in (2, 6) or interlace != 0:
        fail(f"{path}: expected 8-bit RGB(A), non-interlaced (got depth {depth}, colour type {colour_type})")
    channels = 3 if colour_type == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for y in range(height):
        filter_type = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            left = line[i - channels] if i >= channels else 0
            up = previous[i]
            up_left = previous[i - channels] if i >= channels else 0
            if filter_type == 1:
                line[i] = (line[i] + left) & 255
            elif filter_type == 2:
                line[i] = (line[i] + up) & 255
            elif filter_type == 3:
                line[i] = (line[i] + (left + up) // 2) & 255
            elif filter_type == 4:
                p = left + up - up_left
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - up_left)
                predictor = left if pa <= pb and pa <= pc else (up if pb <= pc else up_left)
                line[i] = (line[i] + predictor) & 255
        previous = line
        rgb = line if channels == 3 else bytearray(b for i, b in enumerate(line) if i % 4 != 3)
        rows.append(bytes(rgb))
    return width, height, rows


def region_stats(rows, x0, x1, y0, y1):
    """Mean colour and number of distinct colours of a pixel rectangle."""
    total, count, colours = [0, 0, 0], 0, set()
    for y in range(y0, y1):
        row = rows[y]
        for x in range(x0, x1):
            pixel = row[3 * x:3 * x + 3]
            colours.add(pixel)
            for k in range(3):
                total[k] += pixel[k]
            count += 1
    return [t / count for t in total], len(colours)


def check_not_blank(path, min_colours=40):
    width, height, rows = read_png(path)
    if (width, height) != (WIDTH, HEIGHT):
        fail(f"{path}: size {width}x{height}, expected {WIDTH}x{HEIGHT}")
    # The top rows are sky (background); the middle holds terrain and bodies.
    sky_mean, _ = region_stats(rows, 0, width, 0, 4)
    mid_mean, mid_colours = region_stats(rows, width // 4, 3 * width // 4, height // 3, 2 * height // 3)
    difference = max(abs(a - b) for a, b in zip(sky_mean, mid_mean))
    if difference < 25:
        fail(f"{path}: the middle looks like the background (mean colours {mid_mean} vs {sky_mean})")
    if mid_colours < min_colours:
        fail(f"{path}: only {mid_colours} distinct colours in the middle: nothing shaded was drawn")
    return rows


def run_demo(demo, engine, midphase, out_dir):
    shutil.rmtree(out_dir, ignore_errors=True)
    summary_path = out_dir + ".json"
    command = [demo, "--engine", engine, "--midphase", midphase, "--out", out_dir, "--json", summary_path] + SMALL
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        fail(f"{' '.join(command)} exited with {result.returncode}:\n{result.stdout}{result.stderr}")
    with open(summary_path) as f:
        return json.load(f)


def check_frames(demo, engine, midphase, out_dir):
    summary = run_demo(demo, engine, midphase, out_dir)
    images = summary["images"]
    if len(images) != 3:  # steps 0, 45, 90
        fail(f"expected 3 frames, got {images}")
    for path in images:
        if not os.path.isfile(path):
            fail(f"{path} was not written")
    first = check_not_blank(images[0])
    last = check_not_blank(images[-1])
    changed = sum(a != b for r0, r1 in zip(first, last) for a, b in zip(r0, r1))
    if changed < 300:
        fail(f"the first and last frames differ in only {changed} bytes: did anything move?")
    if summary["bodies"] != 40 or len(summary["final_bodies"]) != 40:
        fail("expected 40 bodies in the summary")
    # above_terrain: the body's bottom (its lowest point, and every corner or vertex) is no deeper
    # in the terrain under it than the demo's allowance (demos/src/main.cpp).
    below = [b for b in summary["final_bodies"] if b["above_terrain"] is False]
    off = [b for b in summary["final_bodies"] if b["above_terrain"] is None]
    if below or off:
        fail(f"{len(below)} bodies ended below the terrain and {len(off)} off it: {below + off}")
    if summary["bodies_above_terrain"] != 40:
        fail(f"bodies_above_terrain is {summary['bodies_above_terrain']}, expected 40")
    if summary["contacts_per_step"] <= 0:
        fail("no contacts were reported")
    deepest = max(summary["final_bodies"], key=lambda b: b["depth"])
    # The demo's allowance (5 cm) is for every scene; on this one the deepest measured was 1.3 cm
    # (Bullet's builtin midphase; boxtree 0.5 cm in Bullet, 1.1 cm in ODE, gcc build).
    if deepest["depth"] > 0.025:
        fail(f"a {deepest['shape']} ended {100 * deepest['depth']:.1f} cm in the terrain (allowed: 2.5 cm)")
    print(f"ok: {engine}/{midphase}: {len(images)} frames, all {summary['bodies']} bodies above the terrain "
          f"(deepest: a {deepest['shape']} {100 * deepest['depth']:.1f} cm in), "
          f"{summary['contacts_per_step']:.0f} contacts per step")


def check_determinism(demo, engine, midphase, out_dir):
    a = run_demo(demo, engine, midphase, out_dir + "-a")
    b = run_demo(demo, engine, midphase, out_dir + "-b")
    for path_a, path_b in zip(a["images"], b["images"]):
        with open(path_a, "rb") as fa, open(path_b, "rb") as fb:
            if fa.read() != fb.read():
                fail(f"{path_a} and {path_b} differ: the same seed must give the same frames")
    positions_a = [body["position"] for body in a["final_bodies"]]
    positions_b = [body["position"] for body in b["final_bodies"]]
    if positions_a != positions_b:
        fail("the final body positions differ between two runs with the same seed")
    print(f"ok: {engine}/{midphase}: two runs gave identical frames ({len(a['images'])}) and positions")


def check_overlay(demo, out_dir):
    shutil.rmtree(out_dir, ignore_errors=True)
    command = [demo, "--overlay-level", "6", "--method", "obb-all", "--terrain-size", "16", "--width", str(WIDTH),
               "--height", str(HEIGHT), "--out", out_dir, "--json", out_dir + ".json"]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        fail(f"{' '.join(command)} exited with {result.returncode}:\n{result.stdout}{result.stderr}")
    with open(out_dir + ".json") as f:
        summary = json.load(f)
    if summary["volumes"] < 2:
        fail(f"expected several volumes at level 6, got {summary['volumes']}")
    check_not_blank(summary["image"], min_colours=20)
    print(f"ok: overlay with {summary['volumes']} volumes in {summary['image']}")


def main():
    if len(sys.argv) == 6 and sys.argv[1] == "frames":
        check_frames(*sys.argv[2:])
    elif len(sys.argv) == 6 and sys.argv[1] == "determinism":
        check_determinism(*sys.argv[2:])
    elif len(sys.argv) == 4 and sys.argv[1] == "overlay":
        check_overlay(*sys.argv[2:])
    else:
        print(__doc__)
        sys.exit(2)


if __name__ == "__main__":
    main()
