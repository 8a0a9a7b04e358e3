#!/usr/bin/env bash
# Installs the Debian packages probelight builds and tests with, on Debian 12
# (bookworm) or 13 (trixie), skipping those already present. Uses sudo when
# not root.
set -euo pipefail

# The sanitizers' and libFuzzer's runtime ships with the distribution's
# default clang, whose major version the package's name carries.
codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
case "$codename" in
  bookworm) clang_runtime=libclang-rt-14-dev ;;
  trixie) clang_runtime=libclang-rt-19-dev ;;
  *) echo "probelight: Debian 12 (bookworm) or 13 (trixie) expected, this is '${codename:-unknown}'" >&2; exit 1 ;;
esac

packages=(
  # toolchain
  build-essential cmake pkg-config
  # a compiler cache: a second build of the same sources (CI's next run) is mostly hits;
  # Ninja: a new build folder's generator (scripts/compile-options.sh)
  ccache ninja-build
  # vision: marker detection, calibration, image files (libdeflate: the fast PNG writer for frames)
  libapriltag-dev libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-calib3d-dev libdeflate-dev
  # maths and data; glTF 2.0 models (tinygltf)
  libglm-dev nlohmann-json3-dev libtinygltf-dev
  # the command line's parser (header-only)
  libcli11-dev
  # GLES2 through EGL; Mesa's llvmpipe renders headless on machines without a GPU
  libegl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri
  # board backends (camera, KMS display, GPIO button, the systemd service's notifications)
  libcamera-dev libgbm-dev libdrm-dev libgpiod-dev libsystemd-dev
  # the desktop window (--display window), and its tests: a headless X
  # server, key presses sent to it, screenshots of it (xwd)
  libsdl2-dev xvfb xdotool x11-apps
  # tests and benchmarks (systemd-analyze checks the unit file; assimp-testmodels:
  # the assimp project's glTF 2.0 files, valid and broken, read where Debian puts them)
  libgtest-dev libbenchmark-dev systemd assimp-testmodels
  # Debian's package checker, run on the .deb by scripts/check-package.sh
  lintian
  # the sanitizer build and the libFuzzer targets (scripts/test-sanitizers.sh)
  clang "$clang_runtime"
)

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "probelight: all ${#packages[@]} packages already installed"
  exit 0
fi

sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "probelight: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
echo "probelight: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
