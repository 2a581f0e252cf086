// The one error type of bags/: what is wrong with which bag, where.
//
// Every reader of this module reports a malformed, truncated or unsupported
// input as a BagError whose what() is one line: "FILE: WHERE: what is wrong
// (what was expected)". WHERE is a byte offset ("byte 1234"), a record
// ("message 17 of /imu/data") or empty when the whole file is meant. No reader
// crashes, hangs or allocates more than the input declares and can back up.
#pragma once

#include <stdexcept>
#include <string>

namespace odotune::bags {

struct BagError : std::runtime_error {
  BagError(const std::string& file_name, const std::string& at, const std::string& why)
      : std::runtime_error(file_name + ": " + (at.empty() ? "" : at + ": ") + why),
        file(file_name),
        where(at),
        reason(why) {}
  std::string file, where, reason;
};

}  // namespace odotune::bags
