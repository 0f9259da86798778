#!/usr/bin/env python3
"""The summary table of scripts/bench-wide.sh: the eight-wide layouts against Embree and tinybvh.

  bench_wide_table.py ROWS.tsv N          prints the summary (markdown) of the peers benchmark's
                                          rows (bench/src/lib.rs `tsv_rows`) to standard output
  bench_wide_table.py --into DOC SUMMARY  replaces the text between `<!-- bench-wide:begin -->`
                                          and `<!-- bench-wide:end -->` in DOC with SUMMARY

Every ratio is a Scion layout's throughput (LLVM -O3) over the peer's, both measured in the same
run: above 1, Scion is faster. Issue 15's goal: the best eight-wide layout at or above Embree,
`bvh8` at or above tinybvh's BVH8_CPU.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_peers_table import header, into, read_runs  # noqa: E402

BEGIN = "<!-- bench-wide:begin -->"
END = "<!-- bench-wide:end -->"
WIDE = ["llvm-O3 bvh8", "llvm-O3 bvh8-q8-ci", "llvm-O3 bvh8-tri4"]


def summary(rows_path, n):
    runs, order = read_runs(rows_path)
    out = [header(n).replace("`scripts/bench-peers.sh`", "`scripts/bench-wide.sh`"), ""]
    out.append(
        "Throughput in Mrays/s of the eight-wide layouts (LLVM -O3, `closest_hit8`; "
        "`bvh8-tri4`: `bvh8` over blocks of four triangles, `closest_hit8_tri4`) and the "
        "ratios measured in the same run (above 1: Scion is faster). Best = the fastest of "
        "`bvh8`, `bvh8-q8-ci` and `bvh8-tri4`.\n")
    cols = ["scene", "rays", "threads", "bvh8", "bvh8-q8-ci", "bvh8-tri4", "best / Embree",
            "bvh8 / tinybvh bvh8_cpu", "pbrt / Embree"]
    out.append("| " + " | ".join(cols) + " |")
    out.append("|---|---|---:|" + "---:|" * (len(cols) - 3))
    below, below_tiny = [], []
    for key in order:
        r = runs[key]
        scene, rays, threads = key
        wide = [r.get(w) for w in WIDE]
        emb, tiny, pbrt = r.get("embree"), r.get("tinybvh bvh8_cpu"), r.get("llvm-O3 pbrt")
        best = max((w for w in wide if w), default=None)
        cells = [scene, rays, str(threads)] + ["%.3f" % w if w else "-" for w in wide]
        cells.append("%.2f" % (best / emb) if best and emb else "-")
        cells.append("%.2f" % (wide[0] / tiny) if wide[0] and tiny else "-")
        cells.append("%.2f" % (pbrt / emb) if pbrt and emb else "-")
        out.append("| " + " | ".join(cells) + " |")
        if best and emb and best < emb:
            below.append("%s %s: best/Embree %.2f" % (scene, rays, best / emb))
        if wide[0] and tiny and wide[0] < tiny:
            below_tiny.append("%s %s: bvh8/tinybvh %.2f" % (scene, rays, wide[0] / tiny))
    out.append("")
    out.append("Below issue 15's goal (best eight-wide at Embree): %d of %d runs.%s" % (
        len(below), len(order), " " + "; ".join(below) + "." if below else ""))
    out.append("")
    out.append("Below issue 15's goal (`bvh8` at tinybvh's BVH8_CPU): %d of %d runs.%s" % (
        len(below_tiny), len(order), " " + "; ".join(below_tiny) + "." if below_tiny else ""))
    return "\n".join(out) + "\n"


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "--into":
        into(sys.argv[2], sys.argv[3], BEGIN, END)
    elif len(sys.argv) == 3:
        sys.stdout.write(summary(sys.argv[1], int(sys.argv[2])))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
