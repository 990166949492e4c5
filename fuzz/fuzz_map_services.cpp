// libFuzzer entry point: the core calls behind the node's services (see fuzz_targets.h,
// fuzzMapServices). Build and run: scripts/fuzz.sh services.
#include <cstddef>
#include <cstdint>

#include "fuzz_targets.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  evidential_octomap::fuzz::silenceDiagnostics();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return evidential_octomap::fuzz::fuzzMapServices(data, size);
}
