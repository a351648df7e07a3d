#!/usr/bin/env bash
# Builds the browser live preview into OUT_DIR (default: clients/web/dist/), the folder
# skinstreamd serves with --web-root. Installs the pinned npm packages first when node_modules
# is missing or older than package-lock.json.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
out_dir="${1:-$here/dist}"

command -v node >/dev/null || { echo "build.sh: node not found (Debian: apt-get install nodejs npm)" >&2; exit 1; }
command -v npm >/dev/null || { echo "build.sh: npm not found (Debian: apt-get install npm)" >&2; exit 1; }

# npm writes node_modules/.package-lock.json after every install: older than the lock = stale.
installed="$here/node_modules/.package-lock.json"
if [ ! -f "$installed" ] || [ "$here/package-lock.json" -nt "$installed" ]; then
  (cd "$here" && npm ci --no-audit --no-fund)
fi

node "$here/build.mjs" "$out_dir"
