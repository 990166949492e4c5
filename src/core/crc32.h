// CRC-32 (IEEE 802.3 polynomial, as zlib and PNG use) of the .ot semantic section. Private to
// the core (not installed); the fuzz harness reseals mutated files with it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace evidential_octomap {

// Continues `crc` (0 for the first block) over `size` bytes; crc32Update(0, "123456789", 9)
// is 0xCBF43926.
uint32_t crc32Update(uint32_t crc, const void* data, size_t size);

}  // namespace evidential_octomap
