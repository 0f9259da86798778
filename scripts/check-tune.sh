#!/usr/bin/env bash
# Checks `scion tune` against the full sweep (issue 17): on each library scene, closest hit with
# primary (and, with RAYS=secondary, secondary) rays, `scion tune` measures every candidate
# afresh (its own results file) and picks the fastest; the script then looks its choice up in
# docs/explore/results.csv (scripts/explore-docs.sh's sweep) and prints the choice's time there
# over the best time there, and, since those are two runs of a shared machine, the same ratio
# measured head to head: the choice and the sweep's best timed together in one `scion explore`
# run (27 interleaved rounds, the middle ones averaged). Within 1.05 is issue 17's goal.
#
# Usage: scripts/check-tune.sh [SCENE_NAME...]   (default: the ten library scenes)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/bench-lib.sh
cargo build --release -q -p scion-cli
sweep=docs/explore/results.csv
[ -f "$sweep" ] || { echo "$0: no $sweep: run scripts/explore-docs.sh first" >&2; exit 1; }
if [ $# -gt 0 ]; then names=("$@"); else names=("${LIBRARY_SCENES[@]}"); fi
layouts=$(target/release/scion layouts --names --primitive Triangle | grep -v '^hair-bvh$' | paste -sd, -)
rays=${RAYS:-primary}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
worst=0
echo "| scene | rays | tune's choice | the sweep's best | choice / best in the sweep | choice / best head to head |"
echo "|---|---|---|---|---:|---:|"
for name in "${names[@]}"; do
  choice=$(target/release/scion tune --scene "$name" --algorithm closest-hit --rays "$rays" \
    --layouts "$layouts" --results "$tmp/$name.csv" 2>/dev/null | awk '$1 == "choice" { print $2 }')
  read -r best ratio < <(python3 - "$sweep" "$name" "$rays" "$choice" <<'PY'
import csv, sys
sweep, scene, rays, choice = sys.argv[1:]
rows = [r for r in csv.DictReader(open(sweep))
        if r["scene"] == scene and r["kind"] == "closest-hit" and r["queries"] == rays
        and r["n"] == "65536" and r["threads"] == "1" and r["check"] == "identical"]
best = min(rows, key=lambda r: float(r["ns_per_query"]))
mine = [r for r in rows if r["layout"] == choice]
ratio = float(mine[0]["ns_per_query"]) / float(best["ns_per_query"]) if mine else float("nan")
print(best["layout"], f"{ratio:.3f}")
PY
)
  head="1.000"
  if [ "$choice" != "$best" ]; then
    target/release/scion explore --scenes "$name" --layouts "$choice,$best" --rays "$rays" \
      --devices cpu --runs 27 --threads 1 -o "$tmp/$name-head.csv" > /dev/null 2>&1
    head=$(python3 - "$tmp/$name-head.csv" "$choice" "$best" <<'PY'
import csv, sys
rows = {r["layout"]: float(r["ns_per_query"]) for r in csv.DictReader(open(sys.argv[1]))}
print(f"{rows[sys.argv[2]] / rows[sys.argv[3]]:.3f}")
PY
)
  fi
  echo "| $name | $rays | $choice | $best | $ratio | $head |"
done
