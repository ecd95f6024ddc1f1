#!/usr/bin/env bash
# Installs the Debian packages Quadrix builds, tests and runs with, when any is missing.
# As root it runs apt-get; otherwise it prints the exact command and fails.
set -euo pipefail
packages=(
  build-essential cmake pkg-config ccache
  libeigen3-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev libtet1.5-dev libopenmesh-dev
  libtbb-dev libcli11-dev nlohmann-json3-dev libfmt-dev libpng-dev libjpeg62-turbo-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libnanoflann-dev zlib1g-dev gemmi-dev tao-pegtl-dev clang libclang-rt-14-dev libosmesa6-dev libegl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri libglfw3-dev xvfb xauth
  povray  # bench-only peer: `quadrix bench implicit` renders the same surfaces with POV-Ray
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
cmd="apt-get install -y --no-install-recommends ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "quadrix setup: missing Debian packages. Run as root:" >&2
  echo "  apt-get update && $cmd" >&2
  exit 1
fi
echo "quadrix setup: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
# shellcheck disable=SC2086
$cmd -qq
