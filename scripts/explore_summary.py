#!/usr/bin/env python3
"""The summary of an explore results CSV for docs/benchmarks.md: per context (scene, kind,
queries, size, backend, threads), the fastest layout, the smallest, the Pareto-optimal layouts
(none both smaller and faster) and how often each layout is on a frontier or fastest; with a
peers file (second argument, `scion explore --peers`'s), the fastest peer, its time placed as the
plots place it (its ratio to its anchor layout in its own run, times the anchor's time here).

Usage: explore_summary.py RESULTS.csv [PEERS.csv]"""
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

peers = defaultdict(dict)
if len(sys.argv) > 2:
    for p in csv.DictReader(open(sys.argv[2])):
        scene = p["scene"].removesuffix(".gz").removesuffix(".obj")
        backend, _, layout = p["anchor"].partition(" ")
        key = (scene, p["kind"], p["queries"], p["n"], backend, p["threads"])
        peers[key][p["peer"]] = (layout, float(p["ns_per_query"]), float(p["anchor_ns_per_query"]))

def fastest_peer(ctx, points):
    best = None
    for name, (layout, t, at) in peers.get(ctx[:6], {}).items():
        if layout in points and at > 0:
            scaled = points[layout][1] * t / at
            if best is None or scaled < best[1]:
                best = (name, scaled)
    return f"{best[0]} ({best[1]:.1f})" if best else "-"

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
print("| scene | queries | layouts | fastest (ns/query) | fastest peer (ns/query) | smallest (bytes/triangle) | Pareto frontier, smallest first |")
print("|---|---|---:|---|---|---|---|")
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
          f"{fastest_peer(ctx, points)} | "
          f"{smallest[0]} ({smallest[1][0]:.1f}) | {', '.join(name for name, _, _ in f)} |")
print()
total = len(contexts)
ranked = sorted(on_front.items(), key=lambda kv: -kv[1])
print(f"On the Pareto frontier, of {total} contexts: " +
      ", ".join(f"{k} {v}" for k, v in ranked) + ". Fastest: " +
      ", ".join(f"{k} {v}" for k, v in sorted(fastest_count.items(), key=lambda kv: -kv[1])) + ".")
