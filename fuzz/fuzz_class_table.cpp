// libFuzzer entry point: ClassTable::load on YAML (see fuzz_targets.h). Run: scripts/fuzz.sh.
#include <cstddef>
#include <cstdint>

#include "fuzz_targets.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  evidential_octomap::fuzz::silenceDiagnostics();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return evidential_octomap::fuzz::fuzzClassTable(data, size);
}
