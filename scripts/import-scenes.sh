#!/usr/bin/env bash
# Makes scenes/NAME.obj.gz from a folder of the project's shared OBJ scenes and checks them.
#
#   scripts/import-scenes.sh [SOURCE_DIR]      (default: ../shared/scenes)
#
# Each file is compressed with `gzip -9n` (no file name or time stamp in the header, so the same
# OBJ always gives the same bytes) and then unpacked again and compared, by SHA-256, with the
# sum that scenes/README.md lists for it. With no SOURCE_DIR present it only checks the copies
# already in scenes/. Run from anywhere; writes only into the repository's scenes/ folder.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
src=${1:-$root/../shared/scenes}
dst=$root/scenes

# The file -> SHA-256 table of scenes/README.md (rows "| NAME.obj | `HEX` |").
sums=$(sed -n 's/^| \([a-z0-9_]*\.obj\) | `\([0-9a-f]\{64\}\)` |$/\1 \2/p' "$dst/README.md")
[ -n "$sums" ] || { echo "import-scenes: no SHA-256 table in $dst/README.md" >&2; exit 1; }

status=0
while read -r file sum; do
  if [ -f "$src/$file" ]; then
    tmp=$(mktemp "$dst/.$file.XXXXXX")
    gzip -9n -c "$src/$file" > "$tmp"
    mv "$tmp" "$dst/$file.gz"
  fi
  if [ ! -f "$dst/$file.gz" ]; then
    echo "import-scenes: $dst/$file.gz is missing" >&2; status=1; continue
  fi
  got=$(gzip -dc "$dst/$file.gz" | sha256sum | cut -d' ' -f1)
  if [ "$got" != "$sum" ]; then
    echo "import-scenes: $file.gz unpacks to SHA-256 $got, README.md lists $sum" >&2; status=1
  else
    echo "ok $file.gz"
  fi
done <<< "$sums"
exit $status
