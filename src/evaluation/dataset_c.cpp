#include "evidential_octomap/evaluation/dataset_c.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <memory>
#include <optional>
#include <string>

#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evaluation/dataset.h"

struct evidential_octomap_dataset {
  evidential_octomap::ClassTable classes;  // the dataset keeps a pointer to it
  std::optional<evidential_octomap::Dataset> dataset;
  evidential_octomap::Scan scan;
  std::vector<int> scan_classes;
};

namespace {
void copyText(char* out, size_t size, const std::string& text) {
  if (out == nullptr || size == 0) return;
  const size_t n = std::min(size - 1, text.size());
  std::memcpy(out, text.data(), n);
  out[n] = '\0';
}
}  // namespace

extern "C" evidential_octomap_dataset* evidential_octomap_dataset_open(const char* path,
                                                                       const char* class_table,
                                                                       char* error,
                                                                       size_t error_size) {
  try {
    auto handle = std::make_unique<evidential_octomap_dataset>();
    handle->classes = evidential_octomap::ClassTable::load(class_table ? class_table : "");
    handle->dataset.emplace(evidential_octomap::Dataset::open(path ? path : "", handle->classes));
    return handle.release();
  } catch (const std::exception& e) {
    copyText(error, error_size, e.what());
    return nullptr;
  }
}

extern "C" void evidential_octomap_dataset_close(evidential_octomap_dataset* dataset) {
  delete dataset;
}

extern "C" size_t evidential_octomap_dataset_size(const evidential_octomap_dataset* dataset) {
  return dataset->dataset->size();
}

extern "C" long long evidential_octomap_dataset_load(evidential_octomap_dataset* dataset, size_t i,
                                                     const char* classes_from, char* error,
                                                     size_t error_size) {
  try {
    const std::string from = classes_from ? classes_from : "";
    if (from != "predictions" && from != "labels") {
      throw std::invalid_argument("classes come from \"predictions\" or \"labels\", not \"" +
                                  from + "\"");
    }
    const evidential_octomap::Dataset& d = *dataset->dataset;
    if (from == "predictions" ? !d.hasPredictions() : !d.hasLabels()) {
      throw std::runtime_error(d.path() + " has no " + from + "/ files");
    }
    if (i >= d.size()) {
      throw std::out_of_range(d.path() + " has " + std::to_string(d.size()) + " scans, no scan " +
                              std::to_string(i));
    }
    dataset->scan = d.load(i);
    dataset->scan_classes = from == "predictions" ? dataset->scan.predicted : dataset->scan.gt;
    return static_cast<long long>(dataset->scan.size());
  } catch (const std::exception& e) {
    copyText(error, error_size, e.what());
    return -1;
  }
}

extern "C" void evidential_octomap_dataset_scan(const evidential_octomap_dataset* dataset,
                                                float* xyz, float* remission, int32_t* classes,
                                                double* pose, char* name, size_t name_size) {
  const evidential_octomap::Scan& scan = dataset->scan;
  for (size_t i = 0; i < scan.size(); ++i) {
    if (xyz) std::copy_n(scan.points_S[i].data(), 3, xyz + 3 * i);
    if (remission) remission[i] = i < scan.remission.size() ? scan.remission[i] : 0.0f;
    if (classes) classes[i] = static_cast<int32_t>(dataset->scan_classes[i]);
  }
  if (pose) {
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) pose[4 * r + c] = scan.T_W_S(r, c);
  }
  copyText(name, name_size, scan.name);
}
