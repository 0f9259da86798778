#!/usr/bin/env bash
# Instructions per ray of one compiled closest hit, exactly, and where they go: the C++ example
# (examples/cpp) built for a layout and algorithm with `scionc -O3 --emit=asm`, run once under
# valgrind's callgrind with collection only inside the generated batch entry, so loading,
# building and packing do not count. With BLOCKS=1 it also prints the basic blocks of the entry
# that cost the most per ray (scripts/callgrind-blocks.py: each instruction's count from
# callgrind.out, summed per block of `objdump -d`). Deterministic, unlike timings on a shared
# machine: a compiler or library change is measured by running this before and after it.
#
# Usage: scripts/count-instructions.sh [LAYOUT_FILE [LAYOUT [ENTRY [TREE [SCENE [N]]]]]]
#   default: pbrt LinearBVH closest_hit BVH bunny 65536 (primary rays, one thread).
#   e.g.   scripts/count-instructions.sh bvh8 Bvh8 closest_hit8 BVH8 fzk_haus
#          scripts/count-instructions.sh bvh8_tri4 Bvh8Tri4 closest_hit8_tri4 BVH8T4 pine
#   Environment: CPU (scionc --cpu, default x86-64-v3: valgrind runs no AVX-512), BLOCKS=1,
#   BRANCHES=1 (also the blocks with the most mispredicted conditional branches per ray, as
#   valgrind's branch simulation predicts them),
#   ALGORITHM (a .scion file instead of library/algorithms/ENTRY.scion), RAYS (primary, or
#   secondary: `scion trace --rays secondary`'s), BACKEND=jit (Cranelift's code instead of
#   LLVM's: `scion trace --backend jit` under callgrind, its dumped code read back by address;
#   the blocks of every JIT'd function ranked together; CPU does not apply), KEEP=DIR (copy
#   the work folder there: the object or the dumped code, the profile, the run's output).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh >/dev/null
. scripts/bench-lib.sh
need_valgrind
layout_file=${1:-pbrt}
layout=${2:-LinearBVH}
entry=${3:-closest_hit}
tree=${4:-BVH}
scene=${5:-bunny}
n=${6:-65536}
cpu=${CPU:-x86-64-v3}
algorithm=${ALGORITHM:-library/algorithms/$entry.scion}
work=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] && cp -r "$work" "$KEEP"; rm -rf "$work"' EXIT
scene_path=$(scene_file "$scene" 2>/dev/null || echo "$scene")
branch_sim=no
[ "${BRANCHES:-0}" = 1 ] && branch_sim=yes
if [ "${BACKEND:-llvm}" = jit ]; then
  # Cranelift's code, JIT-compiled by `scion trace --backend jit`, which dumps each function's
  # bytes and address (SCION_CLIF_DUMP); every instruction inside them counts, the compiler and
  # the harness do not (one untimed trace: --runs 1).
  cargo build -q --release -p scion-cli
  mkdir "$work/clif"
  SCION_CLIF_DUMP="$work/clif" valgrind --tool=callgrind --dump-instr=yes --branch-sim=$branch_sim \
    --toggle-collect="*contract*Packed*trace*" --callgrind-out-file="$work/cg.out" \
    target/release/scion trace --scene "$scene_path" --n "$n" \
    --threads 1 --runs 1 --rays "${RAYS:-primary}" --backend jit \
    --layout "library/layouts/$layout_file.scion:$layout" --algorithm "$algorithm:$entry" \
    > "$work/run.out" 2> "$work/run.err" || { cat "$work/run.err" "$work/run.out" >&2; exit 1; }
  grep -qE "identical to the (eight-wide )?reference" "$work/run.out" || { cat "$work/run.out" >&2; echo "count-instructions: hits differ from the reference" >&2; exit 1; }
  report=$(python3 scripts/callgrind-blocks.py --jit "$work/clif" "$n" "$work/cg.out")
  echo "$report" | head -1 | awk -v what="$layout_file $entry $scene ($n ${RAYS:-primary} rays, Cranelift JIT)" \
    '{ printf "%s: %s instructions per ray\n", what, $(NF - 3) }'
  [ "${BLOCKS:-0}" = 1 ] && echo "$report"
  if [ "${BRANCHES:-0}" = 1 ]; then
    EVENT=Bcm python3 scripts/callgrind-blocks.py --jit "$work/clif" "$n" "$work/cg.out"
  fi
  exit 0
fi
cargo build -q --release -p scion-compiler -p scion-runtime-c
scionc=target/release/scionc
# Assembly through GNU as, not `--emit=obj`: assemblers encode a register-to-register `vmovq`
# from a high register in its store form (VEX 66 0F D6), a byte shorter, which valgrind 3.19
# cannot decode (SIGILL); the `{load}` pseudo-prefix asks GNU as for the load form (F3 0F 7E),
# the same instruction.
$scionc -O3 --emit=asm --cpu="$cpu" --layout "$layout" --entry "$entry" -o "$work/entry.s" \
  "$algorithm" "library/layouts/$layout_file.scion"
sed -i -E 's/^([[:space:]]*)vmovq([[:space:]]+%xmm[0-9]+, %xmm[0-9]+)$/\1{load} vmovq\2/' "$work/entry.s"
${CC:-gcc} -c "$work/entry.s" -o "$work/entry.o"
$scionc --emit=header --layout "$layout" --entry "$entry" -o "$work/scion_${entry}_$layout.h" \
  "$algorithm" "library/layouts/$layout_file.scion"
${CXX:-g++} -std=c++17 -O2 -I"$work" -Iruntime/capi/include -DSCION_LAYOUT="$layout" \
  -DSCION_ENTRY="$entry" -DSCION_TREE="$tree" "-DSCION_HEADER=\"scion_${entry}_$layout.h\"" \
  examples/cpp/main.cpp "$work/entry.o" -Ltarget/release -lscion_runtime -lpthread -ldl -lm \
  -o "$work/trace"
valgrind --tool=callgrind --dump-instr=yes --branch-sim=$branch_sim --toggle-collect="scion_${entry}_$layout" \
  --callgrind-out-file="$work/cg.out" "$work/trace" "$scene_path" "$n" 1 1 "${RAYS:-primary}" > "$work/run.out" \
  2> "$work/run.err" || { cat "$work/run.err" "$work/run.out" >&2; exit 1; }
grep -q "mismatches: 0" "$work/run.out" || { cat "$work/run.out" >&2; echo "count-instructions: hits differ from the reference" >&2; exit 1; }
total=$(sed -n 's/.*Collected : *\([0-9]*\).*/\1/p' "$work/run.err")
awk -v t="$total" -v n="$n" -v what="$layout_file $entry $scene ($n ${RAYS:-primary} rays, --cpu=$cpu)" \
  'BEGIN { printf "%s: %.1f instructions per ray\n", what, t / n }'
if [ "${BLOCKS:-0}" = 1 ]; then
  (cd "$work" && python3 "$OLDPWD/scripts/callgrind-blocks.py" ./trace "scion_${entry}_$layout" "$n")
fi
if [ "${BRANCHES:-0}" = 1 ]; then
  (cd "$work" && EVENT=Bcm python3 "$OLDPWD/scripts/callgrind-blocks.py" ./trace "scion_${entry}_$layout" "$n")
fi
