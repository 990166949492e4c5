#include "evidential_octomap/evidence/learned_evidence.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace evidential_octomap {

namespace {

float activate(EvidentialMlp::Activation a, float z) {
  if (a == EvidentialMlp::Activation::kRelu) return z > 0.0f ? z : 0.0f;
  return z > 20.0f ? z : std::log1p(std::exp(z));  // softplus, exact to float beyond 20
}

// Token reader that names the file and the item on every error.
class Reader {
 public:
  explicit Reader(const std::string& path) : path_(path), in_(path) {
    if (!in_) fail("cannot open model file");
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(path_ + ": " + what);
  }
  std::string word(const char* what) {
    std::string w;
    if (!(in_ >> w)) fail(std::string("truncated: expected ") + what);
    return w;
  }
  void expect(const std::string& keyword) {
    const std::string w = word(keyword.c_str());
    if (w != keyword) fail("expected '" + keyword + "', found '" + w + "'");
  }
  long integer(const char* what, long lo, long hi) {
    const std::string w = word(what);
    char* end = nullptr;
    const long v = std::strtol(w.c_str(), &end, 10);
    if (*end != '\0' || v < lo || v > hi) {
      fail(std::string("bad ") + what + " '" + w + "' (expected an integer in [" +
           std::to_string(lo) + ", " + std::to_string(hi) + "])");
    }
    return v;
  }
  std::vector<float> floats(size_t n, const char* what) {
    std::vector<float> v(n);
    for (size_t i = 0; i < n; ++i) {
      const std::string w = word(what);
      char* end = nullptr;
      v[i] = std::strtof(w.c_str(), &end);
      if (*end != '\0' || !std::isfinite(v[i]))
        fail(std::string("bad value in ") + what + ": '" + w + "'");
    }
    return v;
  }
  std::string restOfLine() {
    std::string s;
    std::getline(in_, s);
    const size_t b = s.find_first_not_of(" \t");
    return b == std::string::npos ? "" : s.substr(b);
  }

 private:
  std::string path_;
  std::ifstream in_;
};

uint64_t parseFingerprint(Reader& r) {
  const std::string w = r.word("fingerprint");
  char* end = nullptr;
  const uint64_t v = std::strtoull(w.c_str(), &end, 16);
  if (w.size() != 16 || *end != '\0') r.fail("bad scan fingerprint '" + w + "' (16 hex digits)");
  return v;
}

EvidentialMlp::Dense readDense(Reader& r, int in_expected) {
  r.expect("dense");
  EvidentialMlp::Dense d;
  d.in = int(r.integer("layer inputs", 1, 1 << 16));
  d.out = int(r.integer("layer outputs", 1, 1 << 16));
  if (d.in != in_expected) {
    r.fail("layer has " + std::to_string(d.in) + " inputs, the previous one gives " +
           std::to_string(in_expected));
  }
  const std::string act = r.word("activation");
  if (act == "relu") {
    d.activation = EvidentialMlp::Activation::kRelu;
  } else if (act == "softplus") {
    d.activation = EvidentialMlp::Activation::kSoftplus;
  } else {
    r.fail("unknown activation '" + act + "' (relu, softplus)");
  }
  d.weight = r.floats(size_t(d.in) * size_t(d.out), "weights");
  d.bias = r.floats(size_t(d.out), "biases");
  return d;
}

}  // namespace

std::vector<float> EvidentialMlp::forward(const FeatureMatrix& x) const {
  if (x.cols != inputs()) {
    throw std::invalid_argument("EvidentialMlp: " + std::to_string(x.cols) +
                                " features given, the model takes " + std::to_string(inputs()));
  }
  const int out_dim = outputs();
  int widest = inputs();
  for (const Dense& d : layers) widest = std::max(widest, d.out);
  std::vector<float> y(x.rows * size_t(out_dim));
#pragma omp parallel
  {
    std::vector<float> a(static_cast<size_t>(widest)), b(static_cast<size_t>(widest));
#pragma omp for schedule(static)
    for (size_t i = 0; i < x.rows; ++i) {
      const float* row = x.row(i);
      for (int k = 0; k < inputs(); ++k)
        a[size_t(k)] = (row[k] - mean[size_t(k)]) / stddev[size_t(k)];
      for (const Dense& d : layers) {
        for (int o = 0; o < d.out; ++o) {
          const float* w = d.weight.data() + size_t(o) * size_t(d.in);
          float z = d.bias[size_t(o)];
          for (int k = 0; k < d.in; ++k) z += w[k] * a[size_t(k)];
          b[size_t(o)] = activate(d.activation, z);
        }
        std::swap(a, b);
      }
      std::copy(a.begin(), a.begin() + out_dim, y.begin() + i * size_t(out_dim));
    }
  }
  return y;
}

LearnedEvidenceModel LearnedEvidenceModel::load(const std::string& path) {
  Reader r(path);
  LearnedEvidenceModel m;
  m.path_ = path;
  if (r.word("header") != "evidential_octomap_learned_evidence") {
    r.fail("not a learned-evidence model (first word must be evidential_octomap_learned_evidence)");
  }
  if (r.integer("format version", 0, 1 << 20) != 1) r.fail("unsupported format version");
  r.expect("classes");
  m.num_classes_ = int(r.integer("number of classes", 1, 4096));
  r.expect("features");
  const int F = int(r.integer("number of features", 1, 1 << 16));
  std::vector<std::string> names;
  for (int k = 0; k < F; ++k) names.push_back(r.word("feature name"));
  if (names != pointFeatureNames(m.num_classes_)) {
    r.fail(
        "its features are not this build's point features (trained with another version of "
        "point_features.cpp?); retrain with docs/experiments/drivers/learned_evidence/train.py");
  }
  r.expect("description");
  m.description_ = r.restOfLine();
  r.expect("folds");
  const long K = r.integer("number of folds", 1, 64);
  for (long f = 0; f < K; ++f) {
    Fold fold;
    r.expect("fold");
    fold.name = r.word("fold name");
    r.expect("trained_on");
    const long n = r.integer("number of training scans", 0, 1 << 20);
    for (long s = 0; s < n; ++s) fold.trained_on.push_back(parseFingerprint(r));
    r.expect("normalise");
    fold.mlp.mean = r.floats(size_t(F), "feature means");
    fold.mlp.stddev = r.floats(size_t(F), "feature deviations");
    for (float s : fold.mlp.stddev) {
      if (!(s > 0.0f)) r.fail("fold " + fold.name + ": a feature deviation is not > 0");
    }
    r.expect("layers");
    const long L = r.integer("number of layers", 1, 64);
    int in = F;
    for (long l = 0; l < L; ++l) {
      fold.mlp.layers.push_back(readDense(r, in));
      in = fold.mlp.layers.back().out;
    }
    if (in != m.num_classes_) {
      r.fail("fold " + fold.name + " outputs " + std::to_string(in) +
             " values, not C = " + std::to_string(m.num_classes_));
    }
    if (fold.mlp.layers.back().activation != EvidentialMlp::Activation::kSoftplus) {
      r.fail("fold " + fold.name + ": the last layer must be softplus (evidence >= 0)");
    }
    m.folds_.push_back(std::move(fold));
  }
  r.expect("end");
  return m;
}

std::vector<size_t> LearnedEvidenceModel::heldOutFolds(uint64_t fingerprint) const {
  std::vector<size_t> out;
  for (size_t f = 0; f < folds_.size(); ++f) {
    const auto& t = folds_[f].trained_on;
    if (std::find(t.begin(), t.end(), fingerprint) == t.end()) out.push_back(f);
  }
  return out;
}

std::vector<float> LearnedEvidenceModel::evidence(const ScanInput& scan,
                                                  std::vector<size_t>* folds_used) const {
  const uint64_t id = scanFingerprint(scan);
  const std::vector<size_t> folds = heldOutFolds(id);
  if (folds.empty()) {
    throw std::runtime_error("every fold of " + path_ + " was trained on scan " +
                             fingerprintHex(id) +
                             " (it saw its labels), so its evidence would not be held out");
  }
  if (folds_used) *folds_used = folds;
  const FeatureMatrix x = computePointFeatures(scan, num_classes_);
  std::vector<float> e(x.rows * size_t(num_classes_), 0.0f);
  for (size_t f : folds) {
    const std::vector<float> y = folds_[f].mlp.forward(x);
    for (size_t k = 0; k < e.size(); ++k) e[k] += y[k] / float(folds.size());
  }
  for (size_t i = 0; i < scan.num_points; ++i) {
    const float* p = scan.xyz + 3 * i;
    if (p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f) {
      std::fill_n(e.begin() + i * size_t(num_classes_), num_classes_, 0.0f);
    }
  }
  return e;
}

}  // namespace evidential_octomap
