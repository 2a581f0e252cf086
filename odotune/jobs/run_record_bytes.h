// A finished run as bytes, for sending it from one MPI rank of a grid to the
// rank that writes the store (odotune/jobs/grid_mpi.h). Exact: every double travels as
// its 8 bytes (NaN payloads, infinities and -0 included), so a run computed on
// another rank is stored bit-identical to one computed in-process. Both ends
// are the same odotune binary on machines of the same byte order; the bytes
// are not a file format.
#pragma once

#include <vector>

#include <odotune/results/run_record.h>

namespace odotune::jobs {

std::vector<char> to_bytes(const results::RunRecord& r);

// Throws std::runtime_error when `bytes` are not exactly one record.
results::RunRecord run_record_from_bytes(const std::vector<char>& bytes);

}  // namespace odotune::jobs
