#!/usr/bin/env python3
"""The summary table of scripts/bench-peers.sh.

  bench_peers_table.py ROWS.tsv N         prints the summary (markdown) of the peers benchmark's
                                          rows (bench/src/lib.rs `tsv_rows`) to standard output
  bench_peers_table.py --into DOC SUMMARY replaces the text between `<!-- bench-peers:begin -->`
                                          and `<!-- bench-peers:end -->` in DOC with SUMMARY

Every ratio is Scion's throughput (LLVM -O3, pbrt layout) over the peer's, both measured in the
same run: above 1, Scion is faster.
"""

import datetime
import os
import re
import subprocess
import sys

BEGIN = "<!-- bench-peers:begin -->"
END = "<!-- bench-peers:end -->"

SCION = "llvm-O3 pbrt"
# (row name, column title, goal of issue 12 as (primary, secondary) minimum ratio or None)
PEERS = [
    ("hand-written pbrt", "/ hand-written pbrt", (1.0, 1.0)),
    ("tinybvh bvh2", "/ tinybvh bvh2", (1.0, 1.0)),
    ("obvhs bvh2", "/ obvhs bvh2", (1.0, 1.0)),
    ("embree", "/ Embree", (0.6, 0.4)),
    ("tinybvh bvh8_cpu", "/ tinybvh bvh8_cpu", None),
    ("obvhs cwbvh", "/ obvhs cwbvh", None),
]


def run(cmd):
    try:
        return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return ""


def lock_version(name):
    try:
        text = open("Cargo.lock").read()
    except OSError:
        return "?"
    m = re.search(r'name = "%s"\nversion = "([^"]+)"' % re.escape(name), text)
    return m.group(1) if m else "?"


def machine():
    cpu = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return "%s, %d CPUs" % (cpu, os.cpu_count() or 1)


def header(n):
    commit = run(["git", "rev-parse", "--short", "HEAD"]) or "?"
    if run(["git", "status", "--porcelain", "--untracked-files=no"]):
        commit += " (with uncommitted changes)"
    embree = run(["dpkg-query", "-W", "-f=${Version}", "libembree3-3"]) or "?"
    llvm = run(["/usr/lib/llvm-22/bin/llvm-config", "--version"]) or "?"
    rustc = run(["rustc", "--version"]) or "?"
    today = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return (
        "Measured %s on %s; commit %s; %s, LLVM %s, Embree %s (Debian), tinybvh-rs %s, "
        "obvhs %s; %d rays per run (seed 1); Rust and C++ built for this CPU "
        "(`-C target-cpu=native`); `scripts/bench-peers.sh`.\n"
        % (today, machine(), commit, rustc, llvm, embree, lock_version("tinybvh-rs"),
           lock_version("obvhs"), n)
    )


def read_runs(rows_path):
    """The benchmark's rows by run: {(scene, rays, threads): {"triangles": n, row name: Mrays/s}}
    and the runs in the order they came."""
    runs = {}
    order = []
    for line in open(rows_path):
        f = line.rstrip("\n").split("\t")
        if len(f) < 12:
            continue
        key = (f[0], f[2], int(f[4]))
        if key not in runs:
            runs[key] = {"triangles": int(f[1])}
            order.append(key)
        runs[key][f[5]] = float(f[6])
    return runs, order


def summary(rows_path, n):
    runs, order = read_runs(rows_path)
    out = [header(n), ""]
    out.append(
        "Throughput of Scion's closest hit (LLVM -O3, pbrt layout) in Mrays/s, and its ratio to "
        "each peer measured in the same run (above 1: Scion is faster); the last column is "
        "Cranelift's throughput over LLVM's.\n"
    )
    cols = ["scene", "rays", "threads", SCION + " Mrays/s"] + [p[1] for p in PEERS]
    cols.append("Cranelift / LLVM")
    out.append("| " + " | ".join(cols) + " |")
    out.append("|---|---|---:|" + "---:|" * (len(cols) - 3))
    worst = {}
    misses = []
    for key in order:
        r = runs[key]
        scene, rays, threads = key
        s = r.get(SCION)
        cells = [scene, rays, str(threads), "%.3f" % s if s else "-"]
        for name, title, goal in PEERS:
            p = r.get(name)
            if s and p:
                ratio = s / p
                cells.append("%.2f" % ratio)
                w = worst.setdefault(title, (ratio, key))
                if ratio < w[0]:
                    worst[title] = (ratio, key)
                if goal and ratio < goal[0 if rays == "primary" else 1]:
                    misses.append("%s %s %s: %s %.2f" % (scene, rays, threads, title[2:], ratio))
            else:
                cells.append("-")
        c = r.get("cranelift pbrt")
        if s and c:
            ratio = c / s
            cells.append("%.2f" % ratio)
            w = worst.setdefault("Cranelift / LLVM", (ratio, key))
            if ratio < w[0]:
                worst["Cranelift / LLVM"] = (ratio, key)
            if ratio < 0.7:
                misses.append("%s %s %s: Cranelift / LLVM %.2f" % (scene, rays, threads, ratio))
        else:
            cells.append("-")
        out.append("| " + " | ".join(cells) + " |")
    out.append("")
    lows = ["%s %.2f (%s %s, %d thread(s))" % (t, w[0], w[1][0], w[1][1], w[1][2])
            for t, w in worst.items()]
    out.append("Lowest ratios: " + "; ".join(lows) + ".")
    out.append("")
    if misses:
        out.append("Below the goals of issue 12 (1.0 against the hand-written kernel, tinybvh's "
                   "BVH2 and obvhs's BVH2; 0.6 / 0.4 of Embree on primary / secondary rays; "
                   "Cranelift 0.7 of LLVM): " + "; ".join(misses) + ".")
    else:
        out.append("Every ratio meets the goals of issue 12 (1.0 against the hand-written kernel, "
                   "tinybvh's BVH2 and obvhs's BVH2; 0.6 / 0.4 of Embree on primary / secondary "
                   "rays; Cranelift 0.7 of LLVM).")
    return "\n".join(out) + "\n"


def into(doc, summary_path, begin=BEGIN, end=END):
    """Replaces the text between the markers `begin` and `end` in `doc` with the summary."""
    text = open(doc).read()
    new = open(summary_path).read()
    if begin not in text or end not in text:
        sys.exit("%s: no %s ... %s markers" % (doc, begin, end))
    head, rest = text.split(begin, 1)
    _, tail = rest.split(end, 1)
    tmp = doc + ".tmp"
    with open(tmp, "w") as f:
        f.write(head + begin + "\n" + new + end + tail)
    os.replace(tmp, doc)


def main(argv):
    if len(argv) == 4 and argv[1] == "--into":
        into(argv[2], argv[3])
    elif len(argv) == 3:
        sys.stdout.write(summary(argv[1], int(argv[2])))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv)
