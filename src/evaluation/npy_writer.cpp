// .npy writer (format 1.0): magic, version, a header dict padded to a multiple of 64 bytes, data.
#include <ostream>

#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/io.h"

namespace evidential_octomap {

namespace {

void writeNpyBytes(const std::string& path, const char* descr, const void* data, size_t rows,
                   size_t cols, size_t item) {
  std::string header = std::string("{'descr': '") + descr + "', 'fortran_order': False, " +
                       "'shape': (" + std::to_string(rows) + ", " + std::to_string(cols) + "), }";
  const size_t unpadded = 10 + header.size() + 1;  // magic + version + length, header, '\n'
  header.append((64 - unpadded % 64) % 64, ' ');
  header.push_back('\n');
  // Atomic like every file we write: a killed run leaves the previous file or the new one.
  writeFileAtomically(path, [&](std::ostream& out) {
    const uint16_t len = uint16_t(header.size());
    out.write("\x93NUMPY\x01\x00", 8);
    const char len_bytes[2] = {char(len & 0xFF), char(len >> 8)};
    out.write(len_bytes, 2);
    out.write(header.data(), std::streamsize(header.size()));
    out.write(static_cast<const char*>(data), std::streamsize(rows * cols * item));
    return out.good();
  });
}

}  // namespace

void writeNpy(const std::string& path, const float* values, size_t rows, size_t cols) {
  writeNpyBytes(path, "<f4", values, rows, cols, sizeof(float));
}

void writeNpy(const std::string& path, const int32_t* values, size_t rows, size_t cols) {
  writeNpyBytes(path, "<i4", values, rows, cols, sizeof(int32_t));
}

}  // namespace evidential_octomap
