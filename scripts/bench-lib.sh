# Helpers shared by the benchmark and measurement scripts (sourced, not run):
#   scene_file NAME      the file of scene NAME in $scenes (NAME.obj, else NAME.obj.gz); fails,
#                        naming the folder, when neither exists. $scenes: set it before the
#                        call (default $SCION_SCENES or the repository's scenes/).
#   LIBRARY_SCENES       the library's ten scenes, smallest first.
#   peers_bench          builds the peers benchmark (cargo bench -p scion-bench --bench peers)
#                        with the caller's CARGO_TARGET_DIR and RUSTFLAGS, prints its path.
#   need_valgrind        installs valgrind (Debian package) when it is missing.
#   doc_table FILE NAME  puts FILE's text into docs/benchmarks.md between `<!-- NAME:begin -->`
#                        and `<!-- NAME:end -->` (nothing when BENCH_NO_DOC=1).

scenes=${scenes:-${SCION_SCENES:-scenes}}

scene_file() {
  local f
  for f in "$scenes/$1.obj" "$scenes/$1.obj.gz"; do [ -f "$f" ] && { echo "$f"; return 0; }; done
  echo "$(basename "$0"): no scene $1 in $scenes (NAME.obj or NAME.obj.gz)" >&2
  return 1
}

LIBRARY_SCENES=(teapot pine suzanne balloon fzk_haus sponza_dabrovic bunny engine cruiser_cg57
  dragon)

peers_bench() {
  local bench
  bench=$(cargo bench -p scion-bench --bench peers --no-run 2>&1 |
    sed -n 's/.*Executable .*(\(.*\)).*/\1/p' | tail -n 1)
  [ -x "$bench" ] || { echo "$(basename "$0"): the peers benchmark did not build" >&2; return 1; }
  echo "$bench"
}

need_valgrind() {
  command -v valgrind >/dev/null && return 0
  echo "$(basename "$0"): installing valgrind (Debian package)" >&2
  local sudo=""
  [ "$(id -u)" -eq 0 ] || sudo=sudo
  $sudo apt-get update -q >/dev/null
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q valgrind >/dev/null
}

doc_table() {
  [ "${BENCH_NO_DOC:-0}" != 1 ] || return 0
  python3 - "$1" "$2" <<'PY'
import re, sys
table, name = open(sys.argv[1]).read(), sys.argv[2]
p = "docs/benchmarks.md"
s = open(p).read()
begin, end = f"<!-- {name}:begin -->", f"<!-- {name}:end -->"
if begin not in s or end not in s:
    sys.exit(f"docs/benchmarks.md has no {begin} ... {end}")
s = re.sub(re.escape(begin) + ".*?" + re.escape(end), lambda m: begin + "\n" + table + end, s, flags=re.S)
open(p, "w").write(s)
PY
}
