# Helpers shared by the benchmark and measurement scripts (sourced, not run):
#   scene_file NAME      the file of scene NAME in $scenes (NAME.obj, else NAME.obj.gz); fails,
#                        naming the folder, when neither exists. $scenes: set it before the
#                        call (default $SCION_SCENES or the repository's scenes/).
#   LIBRARY_SCENES       the library's ten scenes, smallest first.
#   peers_bench          builds the peers benchmark (cargo bench -p scion-bench --bench peers)
#                        with the caller's CARGO_TARGET_DIR and RUSTFLAGS, prints its path.
#   need_valgrind        installs valgrind (Debian package) when it is missing.

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
