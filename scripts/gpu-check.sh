#!/usr/bin/env bash
# The GPU check (issue 4 part 5, docs/gpu.md): on a machine with an NVIDIA GPU, trace every
# scene of the scenes folder with closest hit for layouts pbrt, ptr, pbrt-q16 and sg-eq (then
# the kit's other layouts: the eight-wide ones, the case studies, bvh8-tri4) on the GPU,
# primary and secondary rays, each hit compared bit for bit with the CPU reference (the
# quantized layouts' is the reference traversal of their decoded boxes, in both modes: the kit
# names its boxes; sg-eq decodes with PTX's directed rounding, add.rm/mul.rm/sub.rp);
# then run the GPU tests of scion-cuda. Prints one summary table and exits 0 only when
# everything that ran passed and pbrt and ptr ran on every scene. Layout by layout, smallest
# scene first: a spent budget leaves out the last layouts' largest scenes (NOT RUN rows).
#
# Runs from the kit made by scripts/gpu-kit.sh (no Rust toolchain needed):
#   gpu-kit/gpu-check.sh                   # or: GPU_KIT=gpu-kit scripts/gpu-check.sh
# Environment:
#   SCION_SCENES       a folder of NAME.obj scenes (default: the kit's gzipped copies of the
#                      repository's scenes/, unpacked into a temporary folder)
#   GPU_CHECK_N        rays per run (default 1048576)
#   GPU_CHECK_RUNS     timed runs after the warm-up (default 9)
#   GPU_CHECK_MODE     scion (compile PTX in-process: needs libLLVM 22), kit (run the prebuilt
#                      PTX kits with scion-gpu), or auto (scion when it starts, else kit)
#   GPU_CHECK_TIMEOUT  seconds per run (default 60)
#   GPU_CHECK_BUDGET   seconds for all the traces (default 300): later ones are not started
#   GPU_CHECK_LAYOUTS  the layouts, in order (default: the kit's LAYOUTS, every library layout
#                      the GPU path runs, pbrt ptr pbrt-q16 sg-eq first); pbrt and ptr must
#                      run on every scene, the others as the budget allows (mode kit runs only
#                      those with a PTX kit, `scion layouts --kit`; the wide ones need mode
#                      scion)
#   GPU_CHECK_DEVICE   gpu (default), or gpu-emulated to check this script without a GPU:
#                      `scion trace --device gpu-emulated` (the GPU kernels compiled for the
#                      CPU, docs/gpu.md), no device probe, no test binaries (mode scion only)
#   OUT                where logs and summary.txt go (default: <kit>/results)
set -uo pipefail

here=$(cd "$(dirname "$0")" && pwd)
if [ -x "$here/bin/scion" ]; then KIT=$here; else KIT=${GPU_KIT:-$here/../gpu-kit}; fi
KIT=$(cd "$KIT" 2>/dev/null && pwd) || { echo "gpu-check: no kit at $KIT; run scripts/gpu-kit.sh first" >&2; exit 2; }
N=${GPU_CHECK_N:-1048576}
RUNS=${GPU_CHECK_RUNS:-9}
TIMEOUT=${GPU_CHECK_TIMEOUT:-60}
BUDGET=${GPU_CHECK_BUDGET:-300}
LAYOUTS=${GPU_CHECK_LAYOUTS:-$(cat "$KIT/LAYOUTS" 2>/dev/null || echo pbrt ptr pbrt-q16 sg-eq)}
LAYOUTS=$(echo $LAYOUTS)
DEVICE=${GPU_CHECK_DEVICE:-gpu}
case $DEVICE in
  gpu|gpu-emulated) ;;
  *) echo "gpu-check: GPU_CHECK_DEVICE must be gpu or gpu-emulated" >&2; exit 2;;
esac
RESULTS=${OUT:-$KIT/results}
mkdir -p "$RESULTS/logs"
SUMMARY=$RESULTS/summary.txt
: > "$SUMMARY"

say() { echo "$@" | tee -a "$SUMMARY"; }

scenes=${SCION_SCENES:-}
if [ -z "$scenes" ] && ls "$KIT"/scenes/*.obj.gz >/dev/null 2>&1; then
  scenes=$(mktemp -d "${TMPDIR:-/tmp}/scion-scenes.XXXXXX")
  trap 'rm -rf "$scenes"' EXIT
  for f in "$KIT"/scenes/*.obj.gz; do gzip -dc "$f" > "$scenes/$(basename "$f" .gz)"; done
fi
if [ -z "$scenes" ] || ! ls "$scenes"/*.obj >/dev/null 2>&1; then
  echo "gpu-check: no scenes found; set SCION_SCENES to the folder of the .obj files" >&2
  exit 2
fi

say "gpu-check: kit $KIT (commit $(cat "$KIT/COMMIT" 2>/dev/null || echo unknown))"
if command -v nvidia-smi >/dev/null 2>&1; then
  say "gpu-check: $(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 | head -1)"
else
  say "gpu-check: nvidia-smi not found"
fi

mode=${GPU_CHECK_MODE:-auto}
if [ "$mode" = auto ]; then
  if "$KIT/bin/scion" --version >/dev/null 2>&1; then mode=scion; else mode=kit; fi
fi
if [ "$DEVICE" = gpu-emulated ] && [ "$mode" != scion ]; then
  echo "gpu-check: GPU_CHECK_DEVICE=gpu-emulated needs mode scion (a kit's bin/scion that starts)" >&2
  exit 2
fi
case $mode in
  scion) if [ "$DEVICE" = gpu ]; then how="PTX compiled in-process by LLVM"; else how="the GPU kernels compiled for this CPU by LLVM"; fi
         say "gpu-check: mode scion (scion trace --device $DEVICE: $how)";;
  kit) say "gpu-check: mode kit (scion-gpu with the prebuilt PTX kits; scion does not start here: $("$KIT/bin/scion" --version 2>&1 | head -1))";;
  *) echo "gpu-check: GPU_CHECK_MODE must be scion, kit or auto" >&2; exit 2;;
esac
say "gpu-check: scenes $scenes, $N rays per run, $RUNS timed runs"
if [ "$DEVICE" = gpu-emulated ]; then
  info="emulated on the CPU (scion trace --device gpu-emulated; not a GPU)"
  say "gpu-check: $info"
  no_device=0
elif ! info=$("$KIT/bin/scion-gpu" --info 2>&1); then
  say "gpu-check: FAILED: the GPU cannot be opened: $info"
  say "gpu-check: (the tests below then only print skip lines)"
  no_device=1
else
  say "gpu-check: $info"
  no_device=0
fi
say ""

start=$(date +%s)
failures=0
not_run=0
identical=0
TSV=$RESULTS/traces.tsv
printf 'scene\tlayout\trays\ttriangles\tpack_s\tmrays\tcheck\n' > "$TSV"
table=$(printf '%-18s %-8s %-10s %10s %9s %12s  %s' scene layout rays triangles "pack s" "Mrays/s" check)
rows=()
# Smallest scenes first, so a spent budget leaves out the largest.
mapfile -t objs < <(ls -Sr "$scenes"/*.obj)
for layout in $LAYOUTS; do
  [ $no_device -eq 0 ] || break
  if [ ! -f "$KIT/ptx/$layout.ptx" ] && [ "$mode" != scion ]; then
    # A layout without a PTX kit (eight-wide, case studies, blocks: `scion layouts --kit`) runs
    # in mode scion only; pbrt and ptr always have one.
    case $layout in
      pbrt|ptr) say "gpu-check: no kit for $layout"; failures=$((failures + 1));;
      *) say "gpu-check: $layout has no PTX kit (mode scion runs it): not run"; not_run=$((not_run + 1));;
    esac
    continue
  fi
  for obj in "${objs[@]}"; do
    scene=$(basename "$obj" .obj)
    for rays in primary secondary; do
      log=$RESULTS/logs/$scene-$layout-$rays.log
      if [ $(( $(date +%s) - start )) -ge "$BUDGET" ]; then
        row=$(printf '%-18s %-8s %-10s %10s %9s %12s  %s' "$scene" "$layout" "$rays" - - - "NOT RUN (GPU_CHECK_BUDGET ${BUDGET}s spent)")
        rows+=("$row"); echo "$row"; not_run=$((not_run + 1))
        case $layout in pbrt|ptr) failures=$((failures + 1));; esac
        printf '%s\t%s\t%s\t-\t-\t-\tNOT RUN\n' "$scene" "$layout" "$rays" >> "$TSV"
        continue
      fi
      if [ "$mode" = scion ]; then
        cmd=("$KIT/bin/scion" trace --device "$DEVICE" --scene "$obj" --layout "$layout" --rays "$rays"
             --n "$N" --runs "$RUNS")
      else
        cmd=("$KIT/bin/scion-gpu" --ptx "$KIT/ptx/$layout.ptx" --scene "$obj" --rays "$rays"
             --n "$N" --runs "$RUNS")
      fi
      echo "\$ ${cmd[*]}" > "$log"
      timeout "$TIMEOUT" "${cmd[@]}" >> "$log" 2>&1
      rc=$?
      tris=$(awk '/^triangles/ {print $2} /^scene .*triangles\)/ {gsub(/[()]/,""); print $(NF-1)}' "$log" | head -1)
      mrays=$(awk '/^throughput/ {print $2}' "$log" | head -1)
      pack=$(awk '/^pack time/ {print $3}' "$log" | head -1)
      # The `check` line, not `checksum:` before it.
      check=$(sed -n 's/^check[[:space:]]\{1,\}//p' "$log" | head -1)
      if [ $rc -eq 0 ] && [[ "$check" == identical* ]]; then
        verdict="ok"; identical=$((identical + 1))
      elif [ $rc -eq 124 ]; then
        verdict="TIMEOUT after ${TIMEOUT}s"; failures=$((failures + 1))
      elif [ -n "$check" ]; then
        verdict="DIFFERS: $check"; failures=$((failures + 1))
      else
        verdict="ERROR (rc $rc): $(grep -m1 '^error' "$log" || tail -1 "$log")"; failures=$((failures + 1))
      fi
      row=$(printf '%-18s %-8s %-10s %10s %9s %12s  %s' "$scene" "$layout" "$rays" "${tris:--}" "${pack:--}" "${mrays:--}" "$verdict")
      rows+=("$row")
      echo "$row"
      printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$scene" "$layout" "$rays" "${tris:--}" "${pack:--}" "${mrays:--}" "$verdict" >> "$TSV"
    done
  done
done
trace_secs=$(( $(date +%s) - start ))

# The other query kinds through `scion run --device` (mode scion only: they are compiled on the
# spot), pbrt on the two smallest scenes: any hit over primary rays, closest point over points
# uniform in the box; every answer checked against the reference on the CPU.
kinds_failed=0
if [ "$mode" = scion ] && [ $no_device -eq 0 ]; then
  say ""
  say "== Other query kinds (scion run --device $DEVICE, pbrt) =="
  for obj in "${objs[@]:0:2}"; do
    scene=$(basename "$obj" .obj)
    for kind in any-hit closest-point; do
      log=$RESULTS/logs/run-$scene-$kind.log
      n=$([ "$kind" = closest-point ] && echo 16384 || echo 65536)
      cmd=("$KIT/bin/scion" run --device "$DEVICE" --algorithm "$kind" --scene "$obj" --layout pbrt
           --n "$n" --runs "$RUNS")
      echo "\$ ${cmd[*]}" > "$log"
      timeout "$TIMEOUT" "${cmd[@]}" >> "$log" 2>&1
      rc=$?
      check=$(sed -n 's/^check[[:space:]]\{1,\}//p' "$log" | head -1)
      speed=$(awk '/^throughput/ {print $2, $3}' "$log" | head -1)
      if [ $rc -eq 0 ] && [[ "$check" == identical* ]]; then v="ok: $check"
      else v="FAILED (rc $rc): ${check:-$(grep -m1 '^error' "$log" || tail -1 "$log")}"; kinds_failed=$((kinds_failed + 1)); fi
      say "$(printf '%-18s %-14s %8s  %-16s %s' "$scene" "$kind" "$n" "${speed:--}" "$v")"
    done
  done
fi

# A design-space sweep on the device (issue 17: `scion explore --devices`), the kit's layouts
# over the two smallest scenes, closest hit with primary rays, every answer checked: its CSV,
# Pareto plots and index under $RESULTS/explore (mode scion only). Not counted as a failure of
# the check: its warnings say what did not run.
if [ "$mode" = scion ] && [ $no_device -eq 0 ]; then
  say ""
  say "== scion explore --devices $DEVICE =="
  log=$RESULTS/logs/explore.log
  scenes_arg=$(IFS=,; echo "${objs[*]:0:2}")
  # The sweep measures layouts over triangles (bvh8-tri4's blocks are traced above only).
  over_triangles=$("$KIT/bin/scion" layouts --primitive Triangle --names)
  swept=$(for l in $LAYOUTS; do echo "$over_triangles" | grep -qx "$l" && echo "$l"; done | paste -sd, -)
  cmd=("$KIT/bin/scion" explore --devices "$DEVICE" --scenes "$scenes_arg"
       --layouts "$swept" --kinds closest-hit --rays primary
       --sizes "$N" --runs "$RUNS" -o "$RESULTS/explore/results.csv" --plots "$RESULTS/explore")
  mkdir -p "$RESULTS/explore"
  echo "\$ ${cmd[*]}" > "$log"
  timeout $((TIMEOUT * 4)) "${cmd[@]}" >> "$log" 2>&1
  say "explore: rc $?, $(grep -m1 '^results' "$log" || tail -1 "$log")"
fi

say ""
say "== GPU tests of scion-cuda =="
tests_failed=0
for t in "$KIT"/tests/*; do
  [ -x "$t" ] && [ "$DEVICE" = gpu ] || continue
  name=$(basename "$t")
  log=$RESULTS/logs/test-$name.log
  timeout "$TIMEOUT" "$t" --nocapture --test-threads=1 > "$log" 2>&1
  rc=$?
  result=$(grep -m1 '^test result' "$log" || echo "no result line")
  skips=$(grep -c 'skip:' "$log")
  if [ $rc -eq 0 ]; then v=ok; else v="FAILED (rc $rc)"; tests_failed=$((tests_failed + 1)); fi
  say "$(printf '%-22s %-14s %s; %s skip lines' "$name" "$v" "$result" "$skips")"
  if [ $rc -ne 0 ]; then grep -E "panicked|^---- |error" "$log" | head -8 | sed 's/^/    /' | tee -a "$SUMMARY"; fi
done

say ""
say "== GPU traces ($trace_secs s) =="
say "$table"
for r in "${rows[@]}"; do say "$r"; done
say ""
total=${#rows[@]}
ran=$((total - not_run))
say "gpu-check: $identical of $ran traces identical to the reference; $not_run not run (budget spent; a failure for pbrt and ptr); $tests_failed test binaries failed; $kinds_failed runs of other query kinds failed"
# The Mrays/s as the Markdown table of docs/benchmarks.md: one row per scene and ray kind, the
# kernel's throughput per layout, and each other layout as a ratio to pbrt in the same run.
awk -F'\t' -v device="$(printf '%s' "$info" | head -1)" -v layouts="$LAYOUTS" -v rays="$N" '
  NR == 1 { next }
  { key = $1 SUBSEP $2 SUBSEP $3; m[key] = $6; ok[key] = ($7 == "ok"); if ($4 != "-") tris[$1] = $4
    if (!($1 in seen)) { seen[$1] = 1; order[++n] = $1 } }
  function cell(s, l, r,   k) { k = s SUBSEP l SUBSEP r; return (k in m && m[k] != "-") ? m[k] (ok[k] ? "" : " (!)") : "-" }
  function ratio(s, l, r,   a, b) { a = m[s SUBSEP l SUBSEP r]; b = m[s SUBSEP "pbrt" SUBSEP r]
    return (a + 0 > 0 && b + 0 > 0) ? sprintf("%.2f", a / b) : "-" }
  END {
    nl = split(layouts, L, " ")
    print "GPU: " device ", closest hit, " (rays == 1048576 ? "2^20" : rays) " rays, kernel Mrays/s (trimmed mean of the timed runs); (!) = not identical to the reference"
    print ""
    head = "| scene | triangles | rays |"; rule = "|---|---:|---|"
    for (j = 1; j <= nl; j++) { head = head " " L[j] " |"; rule = rule "---:|" }
    for (j = 1; j <= nl; j++) if (L[j] != "pbrt") { head = head " " L[j] "/pbrt |"; rule = rule "---:|" }
    print head; print rule
    for (i = 1; i <= n; i++) for (k = 1; k <= 2; k++) { s = order[i]; r = (k == 1 ? "primary" : "secondary")
      line = "| " s " | " (s in tris ? tris[s] : "-") " | " r " |"
      for (j = 1; j <= nl; j++) line = line " " cell(s, L[j], r) " |"
      for (j = 1; j <= nl; j++) if (L[j] != "pbrt") line = line " " ratio(s, L[j], r) " |"
      print line }
  }' "$TSV" > "$RESULTS/benchmarks.md"
if [ "$total" -gt 0 ]; then
  say ""
  say "== For docs/benchmarks.md ($RESULTS/benchmarks.md) =="
  tee -a "$SUMMARY" < "$RESULTS/benchmarks.md"
fi
say ""
say "gpu-check: logs in $RESULTS/logs, traces.tsv and this summary in $RESULTS"
[ $no_device -eq 0 ] && [ $total -gt 0 ] && [ $failures -eq 0 ] && [ $tests_failed -eq 0 ] && [ $kinds_failed -eq 0 ]
