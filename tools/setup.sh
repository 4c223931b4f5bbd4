#!/usr/bin/env bash
# Install what lahar needs from Debian's packages (only what is missing) and build it.
#   tools/setup.sh              release build in build/
#   LAHAR_BUILD_DIR=dir LAHAR_CMAKE_ARGS="-DLAHAR_SANITIZE=ON" tools/setup.sh
#   LAHAR_FUZZ=1 ...        also install clang and libFuzzer (tools/fuzz.sh)
#   LAHAR_SETUP_NO_BUILD=1 ...      only install the packages
set -euo pipefail
cd "$(dirname "$0")/.."
packages=(cmake make gcc pkg-config libglib2.0-dev liblcm-dev liblcm-bin libhdf5-dev hdf5-tools
          libyaml-dev libcjson-dev libsodium-dev libmatheval-dev liblammps-dev lammps nftables iproute2 python3 python3-h5py python3-matplotlib python3-yaml
          python3-numpy)
# libFuzzer: clang, its runtime libclang_rt.fuzzer (libclang-rt-14-dev) and clang's OpenMP (libomp-dev)
if [ "${LAHAR_FUZZ:-0}" = 1 ]; then
  packages+=(clang libclang-rt-14-dev libomp-dev)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "lahar setup: installing ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
[ "${LAHAR_SETUP_NO_BUILD:-0}" = 1 ] && exit 0
build=${LAHAR_BUILD_DIR:-build}
# shellcheck disable=SC2086
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release ${LAHAR_CMAKE_ARGS:-} >/dev/null
cmake --build "$build" -j"$(nproc)" >/dev/null
echo "lahar setup: built $build/bin/lahar, $build/bin/lahar-dem, $build/bin/lahar-sph" >&2
