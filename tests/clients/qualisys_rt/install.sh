#!/usr/bin/env bash
# Installs the pinned npm packages of the QTM RT client test (qualisys-rt and its dependencies,
# package-lock.json) when node_modules is missing or older than the lock.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
command -v npm >/dev/null || { echo "install.sh: npm not found (Debian: apt-get install nodejs npm)" >&2; exit 1; }
installed="$here/node_modules/.package-lock.json"
if [ ! -f "$installed" ] || [ "$here/package-lock.json" -nt "$installed" ]; then
  (cd "$here" && npm ci --no-audit --no-fund)
fi
echo "qualisys-rt installed"
