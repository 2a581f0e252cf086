// The two wire encodings of ROS messages, read field by field:
//   ros1: ROS 1 serialisation (roscpp_serialization): little-endian, packed
//         (no alignment), string = uint32 length + bytes, variable array =
//         uint32 count + elements, fixed array = elements, time = uint32 sec
//         + uint32 nsec, std_msgs/Header = uint32 seq + time + string.
//   cdr:  ROS 2's OMG CDR (XCDR1, as rmw_fastrtps/rosbag2 write it): a
//         4-byte encapsulation header (00 01: little-endian, 00 00: big),
//         then each primitive aligned to its size, counted from the byte
//         after the header; string = uint32 length including the NUL + bytes
//         + NUL; sequence = uint32 count + elements; builtin_interfaces/Time
//         = int32 sec + uint32 nanosec; std_msgs/Header = time + string.
//
// Why our own reader: Debian packages no ROS 2 serialisation library, and
// the messages odotune reads (odotune/bags/ros_messages.h) need a dozen primitive
// reads. Big-endian CDR is read too (byte-swapped), though rosbag2 writes
// little-endian. Every read is bounds-checked (ByteReader::Short).
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include <odotune/bags/byte_reader.h>

namespace odotune::bags {

enum class WireEncoding { ros1, cdr };

class WireReader {
 public:
  // For cdr, reads and checks the encapsulation header (throws
  // ByteReader::Short, or std::runtime_error for an encapsulation other than
  // plain CDR).
  WireReader(std::span<const std::uint8_t> data, WireEncoding encoding);

  double f64(const char* field);
  float f32(const char* field);
  std::uint32_t u32(const char* field);
  std::int32_t i32(const char* field);
  std::uint16_t u16(const char* field);
  std::uint8_t u8(const char* field);
  std::int8_t i8(const char* field);
  std::string string(const char* field);
  // A variable-length array's element count, checked against the bytes
  // left (each element takes at least `min_element_bytes`).
  std::uint32_t count(const char* field, std::size_t min_element_bytes);
  // A stamp [ns since the epoch] (ROS 1 time or builtin_interfaces/Time).
  std::int64_t time_ns(const char* field);

  WireEncoding encoding() const { return encoding_; }
  std::size_t left() const { return r_.left(); }

 private:
  void align(std::size_t n);
  template <class T>
  T prim(const char* field);

  ByteReader r_;
  WireEncoding encoding_;
  bool big_endian_ = false;
  std::size_t origin_ = 0;  // cdr: offset of the byte after the encapsulation header
};

}  // namespace odotune::bags
