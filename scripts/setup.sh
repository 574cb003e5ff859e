#!/usr/bin/env bash
# Installs every Debian package that multicue's build, tests and benchmarks need.
# Idempotent and non-interactive; runs `apt-get update` once.
#   scripts/setup.sh            library, CLI, tests, benchmarks and the PCL/Open3D peers
#   scripts/setup.sh --minimal  library, CLI and tests only (no PCL/Open3D)
set -euo pipefail

minimal=0
for arg in "$@"; do
    case "$arg" in
        --minimal) minimal=1 ;;
        -h|--help) sed -n '2,5p' "$0"; exit 0 ;;
        *) echo "setup.sh: unknown option '$arg'" >&2; exit 2 ;;
    esac
done

packages=(
    build-essential cmake ninja-build ccache pkg-config git
    libeigen3-dev liblzf-dev libtbb-dev
    libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
    libembree-dev libassimp-dev libopencv-dev libsvm-dev libsqlite3-dev liboctomap-dev
    libyaml-cpp-dev
    libgtest-dev libgmock-dev libbenchmark-dev
    clang-format
    # The report page's viewer is bundled from npm; its browser test drives Debian's Chromium.
    nodejs chromium chromium-driver
)
if [[ $minimal -eq 0 ]]; then
    # Peers for oracle tests and side-by-side benchmarks; never linked into the library.
    packages+=(libpcl-dev libopen3d-dev)
fi

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Debian ships npm as its own package; other Node.js builds bring it along.
if ! command -v npm >/dev/null 2>&1; then missing+=(npm); fi

if [[ ${#missing[@]} -eq 0 ]]; then
    echo "setup.sh: all ${#packages[@]} packages already installed"
    exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
echo "setup.sh: installing ${#missing[@]} packages: ${missing[*]}"
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup.sh: done"
