#!/usr/bin/env bash
# Installs the Debian packages rigidtouch needs to build, test and plot (docs/architecture.md).
# Skips apt entirely when everything is already installed.
set -euo pipefail
packages=(
  build-essential cmake pkg-config git clang-format clang libclang-rt-14-dev
  libeigen3-dev libmujoco-dev libqhull-dev libbullet-dev libcli11-dev nlohmann-json3-dev libfftw3-dev
  libsodium-dev
  libboost-dev libgtest-dev libgmock-dev googletest libbenchmark-dev
  python3 python3-matplotlib python3-numpy
  pybind11-dev python3-pybind11 python3-dev python3-pytest python3-distributed python3-pandas
  libglfw3-dev libimgui-dev libstb-dev libgl-dev xvfb xauth libgl1-mesa-dri
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "installing: ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -q
$sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
