#!/usr/bin/env bash
# Installs every Debian package that multicue's build, tests and benchmarks need, then the npm
# packages of the report viewer (web/, `npm ci` from web/package-lock.json).
# Idempotent and non-interactive; runs `apt-get update` once, `npm ci` only when the lock changed.
#   scripts/setup.sh            library, CLI, Python module, tests, benchmarks, the PCL/Open3D peers
#                               and ROS 1 (.bag files, multicue_node)
#   scripts/setup.sh --minimal  library, CLI, Python module and tests only (no PCL/Open3D, no ROS)
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
    libembree-dev libassimp-dev libopencv-dev libsvm-dev libsqlite3-dev
    libyaml-cpp-dev
    # Mesh textures.
    libpng-dev libjpeg-dev
    # ROS 2 bags: zstd and lz4 compressed MCAP chunks.
    libzstd-dev liblz4-dev
    # URDF models (kitchen models and kitchen maps); check_urdf for the export tests.
    liburdfdom-dev liburdfdom-tools
    # Occupancy maps (search module) of the registration's multi-view maps.
    liboctomap-dev
    libgtest-dev libgmock-dev libbenchmark-dev
    # The Python module (python/) and its tests.
    pybind11-dev python3-dev python3-numpy python3-pytest
    clang-format
    # libFuzzer targets of fuzz/ (scripts/fuzz.sh, -DMULTICUE_BUILD_FUZZERS=ON).
    clang-14 libclang-rt-14-dev
    # The report page's viewer is bundled from npm; its browser test drives Debian's Chromium.
    nodejs chromium chromium-driver
)
if [[ $minimal -eq 0 ]]; then
    # Peers for oracle tests and side-by-side benchmarks; never linked into the library.
    packages+=(libpcl-dev libopen3d-dev)
    # ROS 1 (Debian's packages): .bag files, multicue_node (ros/), its service generator, and
    # roscore, rosbag, rostopic, rosservice for its tests; pcl_conversions for the PointCloud2
    # interoperability test.
    packages+=(libroscpp-dev librosbag-dev libsensor-msgs-dev libstd-msgs-dev
               libvisualization-msgs-dev python3-gencpp python3-genmsg ros-core rosbash
               libpcl-conversions-dev)
fi

missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Debian ships npm as its own package; other Node.js builds bring it along.
if ! command -v npm >/dev/null 2>&1; then missing+=(npm); fi

if [[ ${#missing[@]} -eq 0 ]]; then
    echo "setup.sh: all ${#packages[@]} packages already installed"
else
    SUDO=""
    if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
    export DEBIAN_FRONTEND=noninteractive
    echo "setup.sh: installing ${#missing[@]} packages: ${missing[*]}"
    $SUDO apt-get update -qq
    $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The report viewer's npm packages (three.js, esbuild, playwright-core for the browser test),
# exactly as web/package-lock.json pins them. The build bundles them offline; nothing else is
# downloaded at build or run time. Skipped while node_modules matches the lock file.
web="$(cd "$(dirname "$0")/.." && pwd)/web"
stamp="$web/node_modules/.multicue-lock-sha256"
lock_sum="$(sha256sum "$web/package-lock.json" | cut -d' ' -f1)"
if [[ -f "$stamp" && "$(cat "$stamp")" == "$lock_sum" ]]; then
    echo "setup.sh: web/node_modules is up to date"
else
    echo "setup.sh: npm ci in web/"
    (cd "$web" && npm ci --no-audit --no-fund --prefer-offline --loglevel=error)
    echo "$lock_sum" > "$stamp"
fi
echo "setup.sh: done"
