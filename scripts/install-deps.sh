#!/usr/bin/env bash
# Installs the Debian 12 packages skinstream needs to build, test and run.
# As root it runs apt-get itself; otherwise it prints the exact command and fails.
# --build-only: only what building the programs and the web page needs (the Dockerfile's builder
# stage): no test tools, Chromium, Blender, Python or clang.
set -euo pipefail

build_only=0
case "${1:-}" in
  "") ;;
  --build-only) build_only=1 ;;
  *) echo "usage: install-deps.sh [--build-only]" >&2; exit 2 ;;
esac
# Checked already by the script that called this one (scripts/test.sh, for its build and fuzz steps).
[ "${SKINSTREAM_DEPS_CHECKED:-}" = 1 ] && exit 0

# What building skinstreamd, the CLI and the web page needs (--build-only installs these alone).
packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libboost-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libmeshoptimizer-dev libcli11-dev zlib1g-dev libexpat1-dev
  libssl-dev  # OpenSSL's libcrypto: SHA-256 for the multicast datagrams' HMAC (protocol/subscriber/datagram_authentication.cpp)
)
# The web viewer's build (npm) and its browser test (node + playwright-core + chromium). A
# machine with Node.js from elsewhere (e.g. NodeSource, which bundles npm) keeps it.
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  packages+=(nodejs npm)
fi
# The tests, the benchmarks, the fuzz targets and the other clients.
[ "$build_only" -eq 1 ] || packages+=(
  ccache libboost-system-dev libopenmesh-dev libgtest-dev libgmock-dev libbenchmark-dev
  chromium
  clang libclang-rt-14-dev  # scripts/fuzz.sh: libFuzzer and clang's sanitizer runtimes
  clang-format  # scripts/format-check.sh
  # The Python package (clients/python): Debian's python3 and numpy; pip, venv, setuptools and
  # wheel for its offline `pip install` test; libmeshoptimizer2d (the .so.2d it decodes the
  # compressed encoding with, also pulled in by libmeshoptimizer-dev).
  python3 python3-numpy python3-pip python3-venv python3-setuptools python3-wheel libmeshoptimizer2d
  # The Blender add-on's headless test (clients/blender): Blender 3.4, about a minute to install.
  blender
  # skinstream-bench --link-mbit: a network namespace and tc's shaper (ip, tc); the multicast
  # test between network namespaces on a bridge (ip), one receiver's datagrams dropped by nft.
  iproute2 nftables
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: missing: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: not root; run this, then try again:" >&2
  echo "  sudo apt-get update && sudo apt-get install -y --no-install-recommends ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
