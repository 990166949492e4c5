// The writer of an .ot data section (ot_format.cpp), shared with the tiled map's streaming
// writer (tiled_map_writer.cpp). Private to the core.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "crc32.h"
#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {

constexpr uint32_t kSectionEndMagic = 0x444E4545u;  // after the nodes, before the CRC

// Collects the section in memory and hands it to the stream in large writes, with its running
// CRC: millions of small ostream::write calls cost more than the encoding.
class EvidentialOcTree::SectionWriter {
 public:
  explicit SectionWriter(std::ostream& s) : s_(s) { buffer_.reserve(kFlushBytes + 4096); }
  ~SectionWriter() { flush(); }
  void bytes(const void* data, size_t size) {
    const char* from = static_cast<const char*>(data);
    buffer_.insert(buffer_.end(), from, from + size);
    if (buffer_.size() >= kFlushBytes) flush();
  }
  template <typename T>
  void pod(const T& value) {
    bytes(&value, sizeof(T));
  }
  void string(const std::string& text) {
    pod(static_cast<uint32_t>(text.size()));
    bytes(text.data(), text.size());
  }
  uint32_t crc() {
    flush();
    return crc_;
  }
  void flush() {
    crc_ = crc32Update(crc_, buffer_.data(), buffer_.size());
    s_.write(buffer_.data(), static_cast<std::streamsize>(buffer_.size()));
    buffer_.clear();
  }

 private:
  static constexpr size_t kFlushBytes = 1 << 16;
  std::ostream& s_;
  std::vector<char> buffer_;
  uint32_t crc_ = 0;
};

}  // namespace evidential_octomap
