#!/usr/bin/env bash
# Installs odotune's build dependencies from Debian 12 packages.
# Noninteractive and idempotent: packages already present are skipped, and
# apt-get is not touched at all when nothing is missing.
set -euo pipefail

PACKAGES=(
  build-essential cmake git pkg-config
  libeigen3-dev          # fixed-size linear algebra for the filters
  libnlopt-cxx-dev       # derivative-free solvers (odotune/tuner/nlopt_solver.h)
  libceres-dev           # robust least squares (diagnose/, batch calibration)
  libfmt-dev             # formatting of tables and messages
  libgtest-dev libgmock-dev
  libbenchmark-dev       # bench/
  libcli11-dev           # the odotune command line
  libyaml-cpp-dev        # scenarios, experiment and config files
  nlohmann-json3-dev     # --json outputs
  libsqlite3-dev         # results store
  gnuplot-nox            # figures
  # bags/ and `odotune import rosbag`:
  libzstd-dev liblz4-dev zlib1g-dev  # MCAP chunk compression and CRC-32
  libgeographiclib-dev   # GNSS fixes to a local east-north frame
  # ROS 1 bags, read with librosbag_storage; its header rosbag/bag.h needs
  # pluginlib's, which need these ROS 2 helpers (without them odotune still
  # builds, and `import rosbag` says it cannot read ROS 1 bags).
  librosbag-storage-dev libroscpp-core-dev pluginlib-dev libclass-loader-dev librcpputils-dev librcutils-dev
  libament-index-cpp-dev
)
if [[ "${ODOTUNE_WITH_MPI:-0}" == "1" ]]; then
  PACKAGES+=(libopenmpi-dev openmpi-bin)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [[ "$(id -u)" != "0" ]]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
