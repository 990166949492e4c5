// libFuzzer entry point: the .ot reader (see fuzz_targets.h). Build and run: scripts/fuzz.sh.
#include <cstddef>
#include <cstdint>

#include "fuzz_targets.h"

extern "C" size_t LLVMFuzzerMutate(uint8_t* data, size_t size, size_t max_size);

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  evidential_octomap::fuzz::silenceDiagnostics();
  return 0;
}

// libFuzzer's own mutations, then (three times in four) the data section's CRC-32 recomputed,
// so that mutated files reach the parser and the invariant checks behind the checksum.
extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size,
                                          unsigned int seed) {
  size = LLVMFuzzerMutate(data, size, max_size);
  if (seed % 4 != 0) evidential_octomap::fuzz::resealOtChecksum(data, size);
  return size;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return evidential_octomap::fuzz::fuzzOtReader(data, size);
}
