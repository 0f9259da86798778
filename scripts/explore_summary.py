#!/usr/bin/env python3
"""The summary of an explore results CSV for docs/benchmarks.md: per context (scene, kind,
queries, size, backend, threads), the fastest layout, the smallest, the Pareto-optimal layouts
(none both smaller and faster) and how often each layout is on a frontier or fastest."""
import csv
import sys
from collections import defaultdict

rows = list(csv.DictReader(open(sys.argv[1])))
ctx_fields = ["scene", "kind", "queries", "n", "backend", "threads", "builder"]
contexts = defaultdict(dict)
meta = rows[-1] if rows else {}
for r in rows:
    if r["check"] != "identical":
        continue
    contexts[tuple(r[f] for f in ctx_fields)][r["layout"]] = (
        float(r["bytes_per_triangle"]), float(r["ns_per_query"]))

def frontier(points):
    out = []
    for name, (b, t) in sorted(points.items(), key=lambda kv: (kv[1][0], kv[1][1])):
        if not out or t < out[-1][2]:
            out.append((name, b, t))
    return out

print(f"Measured with `scripts/explore-docs.sh` on {meta.get('machine', '?')}, {meta.get('cpus', '?')} CPUs; "
      f"commit {meta.get('commit', '?')}; {meta.get('toolchain', '?')}; {len(rows)} measurements in "
      f"`docs/explore/results.csv`; every figure and every context's table in "
      f"[docs/explore/index.md](explore/index.md).")
print()
print("| scene | queries | layouts | fastest (ns/query) | smallest (bytes/triangle) | Pareto frontier, smallest first |")
print("|---|---|---:|---|---|---|")
on_front = defaultdict(int)
fastest_count = defaultdict(int)
for ctx, points in sorted(contexts.items()):
    f = frontier(points)
    fastest = min(points.items(), key=lambda kv: kv[1][1])
    smallest = min(points.items(), key=lambda kv: kv[1][0])
    fastest_count[fastest[0]] += 1
    for name, _, _ in f:
        on_front[name] += 1
    scene, kind, queries, n = ctx[0], ctx[1], ctx[2], ctx[3]
    print(f"| {scene} | {kind}, {n} {queries} | {len(points)} | {fastest[0]} ({fastest[1][1]:.1f}) | "
          f"{smallest[0]} ({smallest[1][0]:.1f}) | {', '.join(name for name, _, _ in f)} |")
print()
total = len(contexts)
ranked = sorted(on_front.items(), key=lambda kv: -kv[1])
print(f"On the Pareto frontier, of {total} contexts: " +
      ", ".join(f"{k} {v}" for k, v in ranked) + ". Fastest: " +
      ", ".join(f"{k} {v}" for k, v in sorted(fastest_count.items(), key=lambda kv: -kv[1])) + ".")
