#include "evidential_octomap/evidence/learned_evidence_c.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <string>

#include "evidential_octomap/evidence/learned_evidence.h"

namespace {
void setError(char* error, size_t size, const std::string& what) {
  if (error == nullptr || size == 0) return;
  const size_t n = std::min(size - 1, what.size());
  std::memcpy(error, what.data(), n);
  error[n] = '\0';
}
}  // namespace

extern "C" int evidential_octomap_learned_evidence(const char* model_path, const float* xyz,
                                                   const float* remission, const int32_t* predicted,
                                                   size_t n, int num_classes, float* evidence_out,
                                                   char* error, size_t error_size) {
  using evidential_octomap::LearnedEvidenceModel;
  try {
    const LearnedEvidenceModel model = LearnedEvidenceModel::load(model_path ? model_path : "");
    if (model.numClasses() != num_classes) {
      setError(error, error_size,
               std::string(model_path) + " has " + std::to_string(model.numClasses()) +
                   " classes, the caller " + std::to_string(num_classes));
      return 1;
    }
    static_assert(sizeof(int32_t) == sizeof(int), "predicted ids are read as int");
    const evidential_octomap::ScanInput scan{xyz, remission,
                                             reinterpret_cast<const int*>(predicted), n};
    const std::vector<float> e = model.evidence(scan);
    std::copy(e.begin(), e.end(), evidence_out);
    return 0;
  } catch (const std::exception& e) {
    setError(error, error_size, e.what());
    return 1;
  }
}
