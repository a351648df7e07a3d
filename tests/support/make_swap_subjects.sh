#!/usr/bin/env bash
# Two subject files of one body for the clients' swap tests (a subject swapped at run time):
# the MakeHuman body fitted to two CMU takes of one performer (85_02 and 85_12), ~5 s each,
# built side by side. make_swap_subjects.sh SKINSTREAM OUT_DIR: OUT_DIR/first.sksubj, second.sksubj.
set -euo pipefail
skinstream=$1 out=$2
source_dir="$(cd "$(dirname "$0")/../.." && pwd)"
mesh="$source_dir/replay_data/makehuman/makehuman_hm08_body_only.obj"
mkdir -p "$out"
build() {  # build TAKE NAME: written whole before it is renamed into place
  "$skinstream" build-subject --capture "$source_dir/replay_data/cmu/$1.c3d" --mesh "$mesh" --out "$out/$2.tmp.sksubj" \
    >"$out/$2.log" 2>&1 || { cat "$out/$2.log" >&2; return 1; }
  mv "$out/$2.tmp.sksubj" "$out/$2.sksubj"
}
build 85_02 first &
first=$!
build 85_12 second
wait "$first"
