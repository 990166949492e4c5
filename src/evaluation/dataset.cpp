#include "evidential_octomap/evaluation/dataset.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <Eigen/LU>

namespace fs = std::filesystem;

namespace evidential_octomap {

namespace {

std::runtime_error fileError(const std::string& file, const std::string& what) {
  return std::runtime_error(file + ": " + what);
}

std::vector<char> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw fileError(path, "cannot open file");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  std::vector<char> bytes(static_cast<size_t>(size));
  if (size > 0 && !in.read(bytes.data(), size)) throw fileError(path, "read failed");
  return bytes;
}

std::vector<std::string> sortedStems(const fs::path& dir, const std::string& ext) {
  std::vector<std::string> stems;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().extension() == ext) {
      stems.push_back(entry.path().stem().string());
    }
  }
  std::sort(stems.begin(), stems.end());
  return stems;
}

// Path of <dir>/<stem>.bin or .npy when one exists, else empty.
std::string findMatrixFile(const fs::path& dir, const std::string& stem) {
  for (const char* ext : {".bin", ".npy"}) {
    const fs::path p = dir / (stem + ext);
    if (fs::is_regular_file(p)) return p.string();
  }
  return {};
}

Eigen::Matrix4d rowMajor3x4(const std::vector<double>& v, const std::string& file) {
  if (v.size() != 12) throw fileError(file, "expected 12 values of a 3x4 matrix");
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) T(r, c) = v[r * 4 + c];
  return T;
}

}  // namespace

// --- Scan -----------------------------------------------------------------------------------

Eigen::Vector3f Scan::pointW(size_t i) const {
  const Eigen::Vector4d p(points_S[i].x(), points_S[i].y(), points_S[i].z(), 1.0);
  return (T_W_S * p).head<3>().cast<float>();
}

octomap::Pointcloud Scan::pointsW() const {
  octomap::Pointcloud cloud;
  cloud.reserve(points_S.size());
  for (size_t i = 0; i < points_S.size(); ++i) {
    const Eigen::Vector3f p = pointW(i);
    cloud.push_back(p.x(), p.y(), p.z());
  }
  return cloud;
}

// --- low-level readers ------------------------------------------------------------------------

std::vector<float> readVelodyneBin(const std::string& path) {
  const std::vector<char> bytes = readBytes(path);
  if (bytes.size() % (4 * sizeof(float)) != 0) {
    throw fileError(path, "size " + std::to_string(bytes.size()) +
                              " B is not a multiple of 16 B (float32 x, y, z, remission)");
  }
  std::vector<float> values(bytes.size() / sizeof(float));
  std::memcpy(values.data(), bytes.data(), bytes.size());
  return values;
}

std::vector<uint32_t> readLabelFile(const std::string& path) {
  const std::vector<char> bytes = readBytes(path);
  if (bytes.size() % sizeof(uint32_t) != 0) {
    throw fileError(path, "size " + std::to_string(bytes.size()) +
                              " B is not a multiple of 4 B (uint32 labels)");
  }
  std::vector<uint32_t> labels(bytes.size() / sizeof(uint32_t));
  std::memcpy(labels.data(), bytes.data(), bytes.size());
  return labels;
}

std::vector<float> readFloatMatrix(const std::string& path, size_t rows, size_t cols) {
  const std::vector<char> bytes = readBytes(path);
  size_t offset = 0;
  if (fs::path(path).extension() == ".npy") {
    // NPY v1/v2/v3: magic, version, header length, a Python dict literal, then raw data.
    if (bytes.size() < 10 || std::memcmp(bytes.data(), "\x93NUMPY", 6) != 0) {
      throw fileError(path, "not an .npy file (bad magic)");
    }
    const int major = static_cast<unsigned char>(bytes[6]);
    size_t header_len = 0;
    size_t header_start = 0;
    if (major == 1) {
      header_len = static_cast<unsigned char>(bytes[8]) |
                   (static_cast<size_t>(static_cast<unsigned char>(bytes[9])) << 8);
      header_start = 10;
    } else {
      if (bytes.size() < 12) throw fileError(path, "truncated .npy header");
      header_len = 0;
      for (int b = 0; b < 4; ++b) {
        header_len |= static_cast<size_t>(static_cast<unsigned char>(bytes[8 + b])) << (8 * b);
      }
      header_start = 12;
    }
    if (header_start + header_len > bytes.size()) throw fileError(path, "truncated .npy header");
    const std::string header(bytes.data() + header_start, header_len);
    if (header.find("'<f4'") == std::string::npos) {
      throw fileError(path, ".npy dtype must be little-endian float32 ('<f4'), header: " + header);
    }
    if (header.find("'fortran_order': True") != std::string::npos) {
      throw fileError(path, ".npy must be C-ordered (fortran_order False)");
    }
    offset = header_start + header_len;
  }
  const size_t expected = rows * cols * sizeof(float);
  if (bytes.size() - offset != expected) {
    throw fileError(path, "holds " + std::to_string((bytes.size() - offset) / sizeof(float)) +
                              " floats, expected " + std::to_string(rows) + " points x " +
                              std::to_string(cols) + " classes");
  }
  std::vector<float> values(rows * cols);
  std::memcpy(values.data(), bytes.data() + offset, expected);
  return values;
}

Eigen::Matrix4d readKittiCalibTr(const std::string& calib_path) {
  std::ifstream in(calib_path);
  if (!in) throw fileError(calib_path, "cannot open calibration file");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::string key;
    ss >> key;
    if (key != "Tr:") continue;
    std::vector<double> v;
    double x;
    while (ss >> x) v.push_back(x);
    return rowMajor3x4(v, calib_path);
  }
  throw fileError(calib_path, "no 'Tr:' line (Velodyne -> camera transform)");
}

std::vector<Eigen::Matrix4d> readKittiPoses(const std::string& poses_path) {
  std::ifstream in(poses_path);
  if (!in) throw fileError(poses_path, "cannot open poses file");
  std::vector<Eigen::Matrix4d> poses;
  std::string line;
  size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream ss(line);
    std::vector<double> v;
    double x;
    while (ss >> x) v.push_back(x);
    if (v.size() != 12) {
      throw fileError(poses_path, "line " + std::to_string(line_no) + " has " +
                                      std::to_string(v.size()) + " values, expected 12");
    }
    poses.push_back(rowMajor3x4(v, poses_path));
  }
  return poses;
}

Eigen::Matrix4d velodynePose(const Eigen::Matrix4d& P_cam, const Eigen::Matrix4d& Tr) {
  return Tr.inverse() * P_cam * Tr;
}

std::vector<int> classesOfLabels(const std::vector<uint32_t>& raw, const ClassTable& classes,
                                 const std::string& file) {
  std::vector<int> out(raw.size());
  for (size_t i = 0; i < raw.size(); ++i) {
    const uint32_t id = raw[i] & 0xFFFFu;
    const auto it = classes.learning_map.find(id);
    if (it == classes.learning_map.end()) {
      throw fileError(file, "unknown label id " + std::to_string(id) + " at point " +
                                std::to_string(i) + " (not in the learning map of class table '" +
                                classes.dataset + "')");
    }
    out[i] = it->second;
  }
  return out;
}

// --- Dataset ----------------------------------------------------------------------------------

namespace {

// What Dataset::open finds on disk, one entry per scan.
struct ScanFiles {
  Dataset::Layout layout = Dataset::Layout::kSemanticKitti;
  std::vector<std::string> stems, bins, labels, predictions, evidence;
  std::vector<Eigen::Matrix4d> poses_W_S;
  bool has_labels = false, has_predictions = false;
  std::string evidence_dir, evidence_kind;
};

// The first of evidence/, alpha/, logits/, probabilities/ under root.
void findEvidenceDir(const fs::path& root, ScanFiles* f) {
  for (const char* dir : {"evidence", "alpha", "logits", "probabilities"}) {
    if (fs::is_directory(root / dir)) {
      f->evidence_dir = (root / dir).string();
      f->evidence_kind = dir;
      return;
    }
  }
}

// Scan `stem`'s line in poses.txt (its number).
size_t poseIndex(const std::string& stem, const std::string& bin, size_t poses,
                 const fs::path& poses_path) {
  size_t index = 0;
  try {
    index = std::stoul(stem);
  } catch (const std::exception&) {
    throw std::runtime_error(bin +
                             ": scan name is not a number, cannot pick its line in poses.txt");
  }
  if (index >= poses) {
    throw std::runtime_error(poses_path.string() + ": no pose for scan " + stem + " (" +
                             std::to_string(poses) + " poses)");
  }
  return index;
}

// velodyne/*.bin with labels/, predictions/, an evidence directory, poses.txt and calib.txt.
ScanFiles semanticKittiFiles(const fs::path& root) {
  ScanFiles f;
  const fs::path velodyne = root / "velodyne", labels = root / "labels",
                 predictions = root / "predictions", poses_path = root / "poses.txt";
  f.stems = sortedStems(velodyne, ".bin");
  if (f.stems.empty()) throw std::runtime_error(velodyne.string() + ": no .bin scans");
  f.has_labels = fs::is_directory(labels);
  f.has_predictions = fs::is_directory(predictions);
  findEvidenceDir(root, &f);
  const auto P = readKittiPoses(poses_path.string());
  const Eigen::Matrix4d Tr = readKittiCalibTr((root / "calib.txt").string());
  for (const std::string& stem : f.stems) {
    f.bins.push_back((velodyne / (stem + ".bin")).string());
    f.labels.push_back(f.has_labels ? (labels / (stem + ".label")).string() : "");
    f.predictions.push_back(f.has_predictions ? (predictions / (stem + ".label")).string() : "");
    if (!f.evidence_dir.empty()) {
      const std::string file = findMatrixFile(f.evidence_dir, stem);
      if (file.empty())
        throw std::runtime_error(f.evidence_dir + ": no " + stem + ".bin or " + stem + ".npy");
      f.evidence.push_back(file);
    }
    const size_t index = poseIndex(stem, f.bins.back(), P.size(), poses_path);
    f.poses_W_S.push_back(velodynePose(P[index], Tr));
  }
  return f;
}

// A single pose-less scan: the .bin itself, or a directory holding exactly the scan files, each
// with its .label beside it when there is one.
ScanFiles singleScanFiles(const fs::path& root, const std::string& path) {
  ScanFiles f;
  f.layout = Dataset::Layout::kSingleScan;
  if (fs::is_regular_file(root)) {
    f.stems.push_back(root.stem().string());
    f.bins.push_back(root.string());
  } else {
    f.stems = sortedStems(root, ".bin");
    if (f.stems.empty()) {
      throw std::runtime_error(path +
                               ": neither a SemanticKITTI layout (velodyne/) nor a directory "
                               "holding a .bin scan");
    }
    for (const std::string& stem : f.stems) f.bins.push_back((root / (stem + ".bin")).string());
  }
  f.has_labels = true;
  for (const std::string& b : f.bins) {
    const fs::path l = fs::path(b).replace_extension(".label");
    if (!fs::is_regular_file(l)) f.has_labels = false;
    f.labels.push_back(l.string());
    f.predictions.push_back("");
    f.poses_W_S.push_back(Eigen::Matrix4d::Identity());
  }
  return f;
}

}  // namespace

Dataset Dataset::open(const std::string& path, const ClassTable& classes,
                      const InputConversion& conversion) {
  const fs::path root(path);
  if (!fs::exists(root)) throw std::runtime_error(path + ": no such file or directory");
  ScanFiles f = fs::is_directory(root / "velodyne") ? semanticKittiFiles(root)
                                                     : singleScanFiles(root, path);
  Dataset d;
  d.path_ = path;
  d.conversion_ = conversion;
  d.classes_ = &classes;
  d.layout_ = f.layout;
  d.stems_ = std::move(f.stems);
  d.bin_files_ = std::move(f.bins);
  d.label_files_ = std::move(f.labels);
  d.prediction_files_ = std::move(f.predictions);
  d.evidence_files_ = std::move(f.evidence);
  d.poses_W_S_ = std::move(f.poses_W_S);
  d.has_labels_ = f.has_labels;
  d.has_predictions_ = f.has_predictions;
  d.evidence_dir_ = std::move(f.evidence_dir);
  d.evidence_kind_ = std::move(f.evidence_kind);
  return d;
}

std::string Dataset::describeEvidenceFiles() const {
  if (evidence_kind_ == "logits") {
    const std::string t = logitTransformName(conversion_.logit_transform);
    return "logits/ files, " + t +
           (conversion_.logit_transform == LogitTransform::kSoftmax
                ? " then confidence-scaled evidence, E=" + std::to_string(int(conversion_.probability_magnitude))
                : " evidence (EDL)");
  }
  if (evidence_kind_ == "probabilities") {
    return "probabilities/ files, confidence-scaled evidence, E=" +
           std::to_string(int(conversion_.probability_magnitude));
  }
  return evidence_kind_.empty() ? "" : evidence_kind_ + "/ files";
}

std::vector<float> Dataset::readEvidence(const std::string& file, size_t n, size_t C) const {
  std::vector<float> raw = readFloatMatrix(file, n, C);
  std::vector<float> ev(raw.size());
  for (size_t k = 0; k < n; ++k) {
    const float* in = raw.data() + k * C;
    float* out = ev.data() + k * C;
    std::string bad;
    if (evidence_kind_ == "logits") {
      bad = evidenceFromLogits(in, int(C), conversion_.logit_transform,
                               conversion_.probability_magnitude, out);
    } else if (evidence_kind_ == "probabilities") {
      bad = evidenceFromProbabilities(in, int(C), conversion_.probability_magnitude, out);
    } else {
      const bool alpha = evidence_kind_ == "alpha";
      for (size_t c = 0; c < C && bad.empty(); ++c) {
        out[c] = alpha ? in[c] - 1.0f : in[c];
        if (!std::isfinite(out[c]) || out[c] < 0.0f) {
          bad = "invalid " + evidence_kind_ + " " + std::to_string(in[c]) + " of class " +
                std::to_string(c) + (alpha ? " (alpha must be >= 1)" : " (must be >= 0)");
        }
      }
    }
    if (!bad.empty()) throw fileError(file, "point " + std::to_string(k) + ": " + bad);
  }
  return ev;
}

Scan Dataset::load(size_t i) const {
  if (i >= stems_.size()) throw std::out_of_range("Dataset::load: scan index out of range");
  Scan scan;
  scan.name = stems_[i];
  scan.T_W_S = poses_W_S_[i];
  const std::vector<float> xyzr = readVelodyneBin(bin_files_[i]);
  const size_t n = xyzr.size() / 4;

  auto readClasses = [&](const std::string& file) {
    const std::vector<uint32_t> raw = readLabelFile(file);
    if (raw.size() != n) {
      throw fileError(file, "holds " + std::to_string(raw.size()) + " labels but " +
                                bin_files_[i] + " holds " + std::to_string(n) + " points");
    }
    return classesOfLabels(raw, *classes_, file);
  };
  std::vector<int> gt, pred;
  if (has_labels_) gt = readClasses(label_files_[i]);
  if (has_predictions_) pred = readClasses(prediction_files_[i]);
  std::vector<float> ev;
  const int C = classes_->numClasses();
  if (hasEvidence()) ev = readEvidence(evidence_files_[i], n, size_t(C));

  scan.points_S.reserve(n);
  scan.remission.reserve(n);
  for (size_t k = 0; k < n; ++k) {
    const float x = xyzr[4 * k], y = xyzr[4 * k + 1], z = xyzr[4 * k + 2];
    if (x == 0.0f && y == 0.0f && z == 0.0f) {
      ++scan.dropped_no_return;
      continue;
    }
    scan.points_S.emplace_back(x, y, z);
    scan.remission.push_back(xyzr[4 * k + 3]);
    if (!gt.empty()) scan.gt.push_back(gt[k]);
    if (!pred.empty()) scan.predicted.push_back(pred[k]);
    if (!ev.empty()) scan.evidence.insert(scan.evidence.end(), ev.begin() + k * C,
                                          ev.begin() + (k + 1) * C);
  }
  return scan;
}

}  // namespace evidential_octomap
