#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Merges the bench programs' rows into bench/results.json and their markdown fragments into the
generated blocks of bench/RESULTS.md (run by bench/run).

Every program writes <results>/<section>.json (a list of rows) and <section>.md. A row is
  {"section", "case", "metric", "boxtree_method", "boxtree", "peer", "peer_value", "ratio"}
with ratio = boxtree / peer_value (lower is better unless the metric name says otherwise).
Agreement: where boxtree must answer exactly like its reference, a row's metric says so and its
boxtree value counts the differences, which must be 0 (--check fails otherwise):
  pairs_disagree     mesh vs mesh: (source, pose) pair lists differing from the reference
  disagreeing_rays   rays: rays where this boxtree method differs from boxtree aabb
  missed_queries     box queries: boxes where a facet whose triangle meets the box was not reported
RESULTS.md keeps its hand-written text; only the parts between
  <!-- generated: NAME -->  and  <!-- end generated: NAME -->
are replaced (NAME: machine, headline, or a section name).
"""
import argparse
import datetime
import json
import math
import os
import platform
import re
import subprocess
import sys
from collections import defaultdict

SECTIONS = ["simulation", "mesh_vs_mesh", "rays", "box_queries", "build_memory"]
KEYS = ["section", "case", "metric", "boxtree_method", "boxtree", "peer", "peer_value", "ratio"]


def load_rows(results_dir):
    rows, missing = [], []
    for section in SECTIONS:
        path = os.path.join(results_dir, section + ".json")
        if not os.path.exists(path):
            missing.append(section)
            continue
        with open(path) as f:
            rows.extend(json.load(f))
    return rows, missing


def check_rows(rows):
    """Returns a list of problems: missing keys, unknown sections, ratios that are not boxtree / peer."""
    problems = []
    for i, row in enumerate(rows):
        absent = [k for k in KEYS if k not in row]
        if absent:
            problems.append(f"row {i}: missing {', '.join(absent)}: {row}")
            continue
        if row["section"] not in SECTIONS:
            problems.append(f"row {i}: unknown section {row['section']!r}")
        b, p, r = row["boxtree"], row["peer_value"], row["ratio"]
        if isinstance(b, (int, float)) and isinstance(p, (int, float)) and p and r is not None:
            if not math.isclose(r, b / p, rel_tol=1e-6, abs_tol=1e-12):
                problems.append(f"row {i}: ratio {r} != boxtree / peer_value = {b / p}")
    return problems


AGREEMENT_METRICS = ("pairs_disagree", "disagreeing_rays", "missed_queries")


def disagreements(rows):
    """The rows whose metric counts differences from an exact reference and whose boxtree count is
    not 0 (see the module's docstring)."""
    return [r for r in rows if r["metric"].startswith(AGREEMENT_METRICS) and r.get("boxtree")]


def geometric_mean(values):
    values = [v for v in values if v and v > 0]
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else None


def headline(rows):
    """Per section, metric and peer: the geometric mean of the ratios over the cases, for every
    boxtree method that ran on all of the group's cases (like with like: a method measured on fewer
    cases is not ranked; its mean is shown with its case count where it is aabb)."""
    groups = defaultdict(lambda: defaultdict(dict))
    for row in rows:
        if row.get("ratio") is None or "disagree" in row["metric"]:
            continue
        groups[(row["section"], row["metric"], row["peer"])][row["boxtree_method"]][row["case"]] = row["ratio"]
    lines = ["| section | metric | peer | best method over all cases: ratio (geometric mean) | aabb | cases |",
             "|---|---|---|---|---:|---:|"]
    for (section, metric, peer), by_method in sorted(groups.items(), key=lambda kv: (SECTIONS.index(kv[0][0])
                                                                                     if kv[0][0] in SECTIONS else 99,
                                                                                     kv[0][1], kv[0][2])):
        all_cases = set().union(*[set(c) for c in by_method.values()])
        means = {m: geometric_mean(list(c.values())) for m, c in by_method.items() if set(c) == all_cases}
        means = {m: v for m, v in means.items() if v is not None}
        higher_is_better = "higher is better" in metric or "per_second" in metric
        if not means:
            best = "none ran on every case"
        elif metric in ("contacts_per_step", "pairs", "contacts"):  # agreement: the ratio nearest 1
            m = min(means, key=lambda m: abs(math.log(means[m])))
            best = f"{m}: {means[m]:.3g}"
        else:
            m = (max if higher_is_better else min)(means, key=means.get)
            best = f"{m}: {means[m]:.3g}"
        aabb = ""
        if "aabb" in by_method:
            value = geometric_mean(list(by_method["aabb"].values()))
            if value is not None:
                partial = len(by_method["aabb"]) < len(all_cases)
                aabb = f"{value:.3g}" + (f" ({len(by_method['aabb'])} cases)" if partial else "")
        lines.append(f"| {section} | {metric} | {peer} | {best} | {aabb} | {len(all_cases)} |")
    return "\n".join(lines) + "\n"


def machine(seconds):
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    try:
        compiler = subprocess.run(["c++", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        compiler = "unknown"
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    text = (f"- Machine: {cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}\n"
            f"- Compiler: {compiler}; Release build (`-O3 -DNDEBUG`), single thread everywhere\n"
            f"- Run: {when}")
    if seconds is not None:
        text += f", {int(seconds) // 60} min {int(seconds) % 60} s for all sections"
    return text + "\n"


def rebase_links(markdown, prefix):
    """Prefixes the relative targets of markdown links and images with `prefix`."""
    if prefix in ("", "."):
        return markdown
    def fix(m):
        target = m.group(2)
        if re.match(r"^([a-z]+:|/|#)", target):
            return m.group(0)
        return m.group(1) + prefix.rstrip("/") + "/" + target + ")"
    return re.sub(r"(\]\()([^)\s]+)\)", fix, markdown)


def replace_block(document, name, content):
    pattern = re.compile(r"(<!-- generated: %s -->\n).*?(<!-- end generated: %s -->)" % (re.escape(name), re.escape(name)),
                         re.S)
    if not pattern.search(document):
        raise SystemExit(f"report.py: RESULTS.md has no block '{name}'")
    return pattern.sub(lambda m: m.group(1) + content + m.group(2), document)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--results", required=True, help="folder of <section>.json / .md")
    parser.add_argument("--json", required=True, help="merged rows go here")
    parser.add_argument("--markdown", help="RESULTS.md whose generated blocks are replaced")
    parser.add_argument("--seconds", type=float, help="wall time of the whole run, for the machine block")
    parser.add_argument("--check", action="store_true", help="fail if a section is missing or a row is malformed")
    args = parser.parse_args()

    rows, missing = load_rows(args.results)
    problems = check_rows(rows)
    if missing:
        problems.append("sections without results: " + ", ".join(missing))
    with open(args.json, "w") as f:
        json.dump(rows, f, indent=1)
        f.write("\n")
    print(f"report.py: {len(rows)} rows -> {args.json}")
    print(headline(rows))
    for r in disagreements(rows):
        message = f"disagreement: {r['section']} / {r['case']}: {r['metric']} = {r['boxtree']} ({r['boxtree_method']} vs {r['peer']})"
        print("report.py: " + message)
        problems.append(message)
    if args.markdown:
        with open(args.markdown) as f:
            document = f.read()
        document = replace_block(document, "machine", machine(args.seconds))
        document = replace_block(document, "headline", headline(rows))
        # A section's links are relative to its own .md (in the results folder): relative to the
        # markdown file once spliced into it.
        to_results = os.path.relpath(args.results, os.path.dirname(os.path.abspath(args.markdown)))
        for section in SECTIONS:
            path = os.path.join(args.results, section + ".md")
            if os.path.exists(path):
                with open(path) as f:
                    text = rebase_links(f.read(), to_results)
                document = replace_block(document, section, text.rstrip("\n") + "\n")
        with open(args.markdown, "w") as f:
            f.write(document)
        print(f"report.py: updated {args.markdown}")
    for p in problems:
        print("report.py: " + p, file=sys.stderr)
    if args.check and problems:
        sys.exit(1)


if __name__ == "__main__":
    main()
