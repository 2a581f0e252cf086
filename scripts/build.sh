#!/usr/bin/env bash
# Installs the dependencies (if missing), configures and builds odotune into
# build/ (Release; the CLI is build/odotune). Extra arguments go to CMake's
# configure step, e.g. `bash scripts/build.sh -DODOTUNE_NATIVE=ON`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j"$(nproc)"
