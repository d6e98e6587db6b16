#!/usr/bin/env bash
# Installs every build and test dependency of afterglow from Debian packages.
# Run as root (or with sudo available). Does nothing for packages already installed.
set -euo pipefail

packages=(
  build-essential cmake pkg-config ninja-build
  libembree-dev libopenimageio-dev openimageio-tools libopenmesh-dev libglm-dev
  libtinygltf-dev libstb-dev nlohmann-json3-dev libeigen3-dev
  libgtest-dev libgmock-dev libbenchmark-dev libopenexr-dev
  libcgal-dev
  clang libclang-rt-14-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
