#!/usr/bin/env bash
# Fails when a C++ line changed since .clang-format came to the project is not laid out as
# clang-format lays it out, and prints what it would change. Lines older than that are left as
# they are: the check covers what a change touches. Usage: scripts/format-check.sh [BASE]
# (BASE: a commit to compare with instead; the working tree's uncommitted changes count too).
set -euo pipefail
cd "$(dirname "$0")/.."
base=${1:-$(git log -1 --format=%H -- .clang-format)}
if [ -z "$base" ] || ! git cat-file -e "$base^{commit}" 2>/dev/null; then
  # A shallow clone holds no older commit: there is nothing to compare with, and it says so.
  echo "format-check: no commit to compare with (a shallow clone?): nothing checked" >&2
  exit 0
fi
# clang-format runs once a file, one file after another (about 250 files, 15 s of CPU): the files
# are cut into one contiguous share per processor, checked side by side, and their answers
# printed in file order.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
git diff -U0 --no-color "$base" -- '*.cpp' '*.h' > "$work/all.diff"
files=$(grep -c '^diff --git ' "$work/all.diff" || true)
shares=$(nproc)
awk -v per=$(( (files + shares - 1) / (shares > 0 ? shares : 1) )) -v dir="$work" \
  '/^diff --git /{ share = int(file / per); file += 1 } { print > (dir "/share" share ".diff") }' "$work/all.diff"
for share in "$work"/share*.diff; do
  [ -e "$share" ] || continue
  (clang-format-diff -p1 < "$share" > "$share.out" || true) &
done
wait
changes=$(for share in $(ls "$work"/share*.diff.out 2>/dev/null | sort -V); do cat "$share"; done)
if [ -n "$changes" ]; then
  echo "$changes"
  echo "format-check: lines changed since ${base:0:7} are not as clang-format lays them out (above); run: git diff -U0 $base -- '*.cpp' '*.h' | clang-format-diff -p1 -i" >&2
  exit 1
fi
echo "format-check: every C++ line changed since ${base:0:7} is formatted"
