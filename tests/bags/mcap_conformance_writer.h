// Test support: rebuilds an MCAP conformance file from its .json.
//
// Why: the conformance .mcap files in ../shared/data/mcap-conformance are Git
// LFS pointers (the MCAP repository stores them in LFS, and the copy we have
// holds only the pointers), while every .json is complete. The MCAP project
// generates each file deterministically from its records and the features
// in its name (foxglove/mcap, tests/conformance/scripts/generate-inputs.ts:
// ch chunked, mx message indexes, chx chunk index, pad three extra bytes
// 01 ff ff after each padded record's fields, rsh/rch schemas and channels
// repeated in the summary, st statistics, sum summary offsets, ax/mdx
// attachment and metadata indexes). This writer lays the records out the same
// way, written from the spec and that description (not from its code). The
// .json then checks the layout as well as the reader: chunk and summary
// offsets, lengths and the CRC-32s of chunk, data section and summary are in
// it, so a file that reads back to its .json has the reference layout.
#pragma once

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "bags/mcap.h"

namespace odotune::bags::mcap::testing {

// The feature suffixes of a conformance file name ("OneMessage-ch-mx-pad").
std::set<std::string> features_of(const std::string& stem);

// The file's bytes from its data records (Schema, Channel, Message,
// Attachment, Metadata, in order) and features.
std::vector<std::uint8_t> conformance_file(const std::set<std::string>& features,
                                           const std::vector<Record>& data_records);

}  // namespace odotune::bags::mcap::testing
