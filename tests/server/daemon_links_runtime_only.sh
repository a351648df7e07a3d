#!/usr/bin/env bash
# Fails when code of the given libraries (the offline and research layers) reaches the daemon.
#   daemon_links_runtime_only.sh NM PROGRAM LIBRARY...
#
# Why symbols rather than the targets' link lists: what matters is the code in the binary, however
# it got there. A static library's member is linked only for a global symbol it defines, and a
# strong global definition (a non-inline function, a variable) exists once in a program. So the
# program holds code of a library exactly when it defines one of that library's strong global
# symbols: T, D, B, R and i (the CPU dispatchers) in nm's letters. Inline functions and template
# instances (W, V, u) are left out: every library that uses one has its own copy.
set -euo pipefail
nm_tool=$1 program=$2
shift 2

strong_symbols() {
  "$nm_tool" --defined-only --extern-only --format=posix "$@" | awk 'NF >= 2 && $2 ~ /^[TDBRi]$/ { print $1 }' | sort -u
}

forbidden=$(mktemp)
trap 'rm -f "$forbidden"' EXIT
strong_symbols "$@" > "$forbidden"
if [ ! -s "$forbidden" ]; then  # nothing to compare against would pass anything
  echo "no symbols defined in $*"
  exit 1
fi
found=$(strong_symbols "$program" | comm -12 - "$forbidden")
if [ -n "$found" ]; then
  echo "$program defines $(echo "$found" | wc -l) of the functions and variables of $*, e.g.:"
  echo "$found" | head -20 | c++filt
  exit 1
fi
echo "$program defines none of the $(wc -l < "$forbidden") functions and variables of $*"
