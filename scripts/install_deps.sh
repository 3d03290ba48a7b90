#!/usr/bin/env bash
# Installs every package this project needs, from Debian 12's apt only.
# Idempotent: prints nothing and exits 0 when everything is already present.
# Usage: scripts/install_deps.sh [--build-only | --containers] [--print]
#   --build-only  only what compiling needs (no experiment tools; docker/Dockerfile's builder)
#   --containers  also podman and what scripts/containers.sh needs (root only)
#   --print       list the packages and exit
set -euo pipefail

BUILD_PACKAGES=(
  # toolchain
  cmake g++ ccache pkg-config git
  # middleware (Fast DDS 2.9 + code generator + CLI tools; fastcdr/fastrtps CMake configs need libssl-dev)
  libfastrtps-dev libfastcdr-dev fastddsgen fastdds-tools libssl-dev
  # maths, vision, point clouds, optimisation
  libeigen3-dev libopencv-dev libpcl-dev libceres-dev
  # configuration, command line, logging
  libyaml-cpp-dev libcli11-dev libspdlog-dev libfmt-dev libabsl-dev
  # nearest neighbours (header-only): the cloud's localisation
  libnanoflann-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
)
# experiment scripts
EXPERIMENT_PACKAGES=(iproute2 nftables tshark python3 python3-numpy python3-matplotlib python3-yaml)
PACKAGES=("${BUILD_PACKAGES[@]}" "${EXPERIMENT_PACKAGES[@]}")

# scripts/containers.sh: podman as root with runc (containers.md), netavark networks, an offline
# Debian base image (debootstrap) and the compose file (docker-compose on podman's Docker API).
CONTAINER_PACKAGES=(podman runc netavark aardvark-dns iptables debootstrap docker-compose curl)

print=0
for arg in "$@"; do
  case $arg in
    --print) print=1 ;;
    --build-only) PACKAGES=("${BUILD_PACKAGES[@]}") ;;
    --containers) PACKAGES+=("${CONTAINER_PACKAGES[@]}") ;;
    *) echo "install_deps.sh: unknown argument '$arg' (--build-only, --containers, --print)" >&2; exit 2 ;;
  esac
done
if [[ $print == 1 ]]; then
  printf '%s\n' "${PACKAGES[@]}"
  exit 0
fi

missing=()
for p in "${PACKAGES[@]}"; do
  # "install ok installed" is the only state that means the package is usable.
  if [[ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null)" != "install ok installed" ]]; then
    missing+=("$p")
  fi
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

if ! command -v apt-get >/dev/null 2>&1; then
  echo "install_deps.sh: apt-get not found; this project supports Debian 12 (bookworm) only." >&2
  echo "  missing packages: ${missing[*]}" >&2
  exit 1
fi

SUDO=()
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    SUDO=(sudo -n)
  else
    echo "install_deps.sh: ${#missing[@]} package(s) missing and cannot install them:" >&2
    echo "  not root, and passwordless sudo is not available." >&2
    echo "  Fix: run as root, or ask an administrator to run:" >&2
    echo "    apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
fi

echo "install_deps.sh: installing ${#missing[@]} package(s): ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
# tshark asks whether non-root users may capture; answer non-interactively.
echo "wireshark-common wireshark-common/install-setuid boolean false" | "${SUDO[@]}" debconf-set-selections 2>/dev/null || true
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! "${SUDO[@]}" apt-get update -qq >"$log" 2>&1; then
  echo "install_deps.sh: 'apt-get update' failed:" >&2; tail -n 20 "$log" >&2; exit 1
fi
if ! "${SUDO[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >"$log" 2>&1; then
  echo "install_deps.sh: 'apt-get install' failed:" >&2; tail -n 30 "$log" >&2; exit 1
fi
echo "install_deps.sh: done"
