#!/usr/bin/env bash
# Installs the dependencies (if missing), configures and builds odotune into
# build/ (Release; the CLI is build/odotune).
#   bash scripts/build.sh [-DOPTION=VALUE …] [TARGET …]
# Arguments that start with '-' go to CMake's configure step, e.g.
# `bash scripts/build.sh -DODOTUNE_NATIVE=ON`; the others are the targets to
# build (default: the CLI and the tests), e.g. `bash scripts/build.sh odotune`
# builds only the CLI and the libraries it links, `bash scripts/build.sh
# benchmarks` the benchmarks (build/bench_*, not in the default build).
# ODOTUNE_WITH_MPI=1 also installs Open MPI and builds with MPI (README, "MPI");
# without it build/ is configured without MPI.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
mpi=OFF
if [[ "${ODOTUNE_WITH_MPI:-0}" == "1" ]]; then mpi=ON; fi
# ccache, when the machine has it (it is not a dependency), makes rebuilds and
# builds of other clones fast; paths are hashed relative to the clone.
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
fi
configure=()
targets=()
for a in "$@"; do
  if [[ "$a" == -* ]]; then configure+=("$a"); else targets+=(--target "$a"); fi
done
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DODOTUNE_WITH_MPI="$mpi" "${launcher[@]}" "${configure[@]}" >/dev/null
cmake --build build -j"$(nproc)" "${targets[@]}"
