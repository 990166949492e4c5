#include "bench_data.h"

#include <evidential_octomap/class_table.h>
#include <evidential_octomap/learned_evidence.h>
#include <evidential_octomap/subjective_logic.h>
#include <sys/resource.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>

namespace evbench {
namespace {

Mat4 identity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }

Mat4 fromRow12(const std::vector<double>& v) {
  Mat4 m = identity();
  std::copy(v.begin(), v.begin() + 12, m.begin());
  return m;
}

Mat4 multiply(const Mat4& a, const Mat4& b) {
  Mat4 c{};
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k)
      for (int col = 0; col < 4; ++col) c[r * 4 + col] += a[r * 4 + k] * b[k * 4 + col];
  return c;
}

// Inverse of a rigid (or near-rigid) 3x4 transform: [R t]^-1 = [R^T  -R^T t].
Mat4 inverseRigid(const Mat4& m) {
  Mat4 inv = identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) inv[r * 4 + c] = m[c * 4 + r];
  for (int r = 0; r < 3; ++r) {
    double t = 0.0;
    for (int c = 0; c < 3; ++c) t -= inv[r * 4 + c] * m[c * 4 + 3];
    inv[r * 4 + 3] = t;
  }
  return inv;
}

std::vector<double> parseNumbers(const std::string& line) {
  std::istringstream in(line);
  std::vector<double> out;
  double v;
  while (in >> v) out.push_back(v);
  return out;
}

template <typename T>
std::vector<T> readBinary(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw std::runtime_error("cannot open " + path);
  const std::streamsize bytes = in.tellg();
  if (bytes % static_cast<std::streamsize>(sizeof(T)) != 0) {
    throw std::runtime_error(path + ": size is not a multiple of " + std::to_string(sizeof(T)));
  }
  in.seekg(0);
  std::vector<T> data(static_cast<size_t>(bytes) / sizeof(T));
  if (!in.read(reinterpret_cast<char*>(data.data()), bytes)) {
    throw std::runtime_error("cannot read " + path);
  }
  return data;
}

std::string scanName(int i) {
  char name[16];
  std::snprintf(name, sizeof(name), "%06d", i);
  return name;
}

}  // namespace

KittiSequence::KittiSequence(const std::string& folder, const std::string& class_yaml)
    : folder_(folder),
      classes_(std::make_shared<const evidential_octomap::ClassTable>(
          evidential_octomap::ClassTable::load(class_yaml))) {
  Mat4 tr;
  bool have_tr = false;
  {
    std::ifstream calib(folder + "/calib.txt");
    if (!calib) throw std::runtime_error("cannot open " + folder + "/calib.txt");
    std::string line;
    while (std::getline(calib, line)) {
      if (line.rfind("Tr:", 0) == 0) {
        const auto v = parseNumbers(line.substr(3));
        if (v.size() != 12) throw std::runtime_error("calib.txt: Tr needs 12 numbers");
        tr = fromRow12(v);
        have_tr = true;
      }
    }
  }
  if (!have_tr) throw std::runtime_error(folder + "/calib.txt has no Tr line");
  const Mat4 tr_inv = inverseRigid(tr);
  std::ifstream poses(folder + "/poses.txt");
  if (!poses) throw std::runtime_error("cannot open " + folder + "/poses.txt");
  std::string line;
  while (std::getline(poses, line)) {
    const auto v = parseNumbers(line);
    if (v.empty()) continue;
    if (v.size() != 12)
      throw std::runtime_error("poses.txt line " + std::to_string(poses_.size() + 1));
    poses_.push_back(multiply(tr_inv, multiply(fromRow12(v), tr)));  // T_world_velo
  }
}

int KittiSequence::numClasses() const { return classes_->numClasses(); }

Scan KittiSequence::load(int i) const {
  if (i < 0 || size_t(i) >= poses_.size())
    throw std::runtime_error("poses.txt has no line for scan " + std::to_string(i));
  const Mat4& t = poses_[size_t(i)];
  const auto xyzi = readBinary<float>(folder_ + "/velodyne/" + scanName(i) + ".bin");
  const auto labels = readBinary<uint32_t>(folder_ + "/predictions/" + scanName(i) + ".label");
  if (xyzi.size() % 4 != 0 || labels.size() != xyzi.size() / 4) {
    throw std::runtime_error("scan " + scanName(i) + ": point and label counts differ");
  }
  Scan scan;
  const size_t n = labels.size();
  scan.points_W.reserve(n);
  scan.classes.resize(n);
  scan.xyz_S.resize(3 * n);
  scan.remission.resize(n);
  for (size_t j = 0; j < n; ++j) {
    const double x = xyzi[4 * j], y = xyzi[4 * j + 1], z = xyzi[4 * j + 2];
    std::copy(&xyzi[4 * j], &xyzi[4 * j + 3], &scan.xyz_S[3 * j]);
    scan.remission[j] = xyzi[4 * j + 3];
    scan.points_W.push_back(float(t[0] * x + t[1] * y + t[2] * z + t[3]),
                            float(t[4] * x + t[5] * y + t[6] * z + t[7]),
                            float(t[8] * x + t[9] * y + t[10] * z + t[11]));
    scan.classes[j] = classes_->classOfRaw(labels[j]);
  }
  scan.origin_W = octomap::point3d(float(t[3]), float(t[7]), float(t[11]));
  return scan;
}

std::vector<Scan> loadKittiScans(const std::string& folder, const std::string& class_yaml,
                                 int count, int* num_classes) {
  const KittiSequence sequence(folder, class_yaml);
  *num_classes = sequence.numClasses();
  if (size_t(count) > sequence.size())
    throw std::runtime_error("poses.txt has fewer lines than scans");
  std::vector<Scan> scans;
  for (int i = 0; i < count; ++i) scans.push_back(sequence.load(i));
  return scans;
}

std::vector<int> revisitOrder(int unique, int steps) {
  // 0..n-1, n-2..0, 1..n-1, n-2..0, ...: forth and back, never the same scan twice in a row.
  std::vector<int> order;
  int i = 0, direction = 1;
  while (int(order.size()) < steps) {
    order.push_back(i);
    if (unique < 2) continue;
    if (i + direction < 0 || i + direction >= unique) direction = -direction;
    i += direction;
  }
  return order;
}

std::vector<float> derivedEvidence(const std::vector<int>& classes, int num_classes,
                                   float magnitude) {
  std::vector<float> evidence(classes.size() * size_t(num_classes));
  for (size_t i = 0; i < classes.size(); ++i) {
    evidential_octomap::evidenceFromLabel(classes[i], num_classes, magnitude,
                                          &evidence[i * num_classes]);
  }
  return evidence;
}

std::vector<float> learnedEvidence(const Scan& scan, const std::string& model_path,
                                   int num_classes) {
  static std::string loaded_path;
  static evidential_octomap::LearnedEvidenceModel model;
  if (loaded_path != model_path) {
    model = evidential_octomap::LearnedEvidenceModel::load(model_path);
    loaded_path = model_path;
  }
  if (model.numClasses() != num_classes) {
    throw std::runtime_error(model_path + " has " + std::to_string(model.numClasses()) +
                             " classes, the class table " + std::to_string(num_classes));
  }
  evidential_octomap::ScanInput in;
  in.xyz = scan.xyz_S.data();
  in.remission = scan.remission.data();
  in.predicted = scan.classes.data();
  in.num_points = scan.classes.size();
  return model.evidence(in);
}

std::string defaultLearnedModel(const std::string& class_yaml) {
  const auto classes = evidential_octomap::ClassTable::load(class_yaml);
  const size_t slash = class_yaml.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : class_yaml.substr(0, slash);
  return dir + "/learned/" + classes.dataset + ".model";
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

double processCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double peakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // KiB on Linux
}

double currentRssMb() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  statm >> pages_total >> pages_resident;
  return pages_resident * 4096.0 / (1024.0 * 1024.0);
}

}  // namespace evbench
