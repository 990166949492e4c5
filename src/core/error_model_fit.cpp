// fitErrorModel (error_model.h): penalised logistic regression by Newton's method, the penalty
// chosen on held-out folds of spatial blocks.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "evidential_octomap/error_model.h"

namespace evidential_octomap {

// The design matrix of a term list over rows, standardised, and the Newton fit on it.
class ErrorModelFit {
 public:
  ErrorModelFit(const std::vector<ErrorRow>& rows, const std::vector<ErrorModel::Term>& terms)
      : rows_(rows), terms_(terms), n_(rows.size()), d_(terms.size()) {
    x_.resize(n_ * d_);
    mean_.assign(d_, 0.0);
    scale_.assign(d_, 1.0);
    for (size_t i = 0; i < n_; ++i)
      for (size_t j = 0; j < d_; ++j)
        x_[i * d_ + j] = ErrorModel::value(terms_[j], rows[i].x, rows[i].label);
    // Features and hinges are standardised so that one penalty fits all; label offsets stay
    // 0/1, so that the penalty shrinks a rare label's offset (standardised, a label seen on a
    // few voxels would barely be penalised and take an extreme weight from them).
    for (size_t j = 1; j < d_; ++j)
      if (terms_[j].kind != ErrorModel::Term::kLabel) standardise(j);
  }

  // Weights (standardised terms) minimising the log loss over the rows where `use` is true plus
  // penalty / 2 * |w without intercept|^2.
  std::vector<double> fit(const std::vector<char>& use, double penalty) const {
    std::vector<double> w(d_, 0.0);
    double wrong = 0.0, count = 0.0;
    for (size_t i = 0; i < n_; ++i)
      if (use[i]) wrong += rows_[i].wrong, count += 1.0;
    w[0] = std::log((wrong + 0.5) / (count - wrong + 0.5));
    double loss = objective(use, penalty, w);
    for (int iteration = 0; iteration < 50; ++iteration) {
      const std::vector<double> step = newtonStep(use, penalty, w);
      // Damped: a full Newton step can overshoot on separable hinges; halve until it descends.
      std::vector<double> next(d_);
      double next_loss = INFINITY, t = 1.0;
      for (int halving = 0; halving < 30; ++halving, t *= 0.5) {
        for (size_t j = 0; j < d_; ++j) next[j] = w[j] - t * step[j];
        next_loss = objective(use, penalty, next);
        if (next_loss <= loss) break;
      }
      if (!(next_loss <= loss)) break;
      const bool converged = loss - next_loss < 1e-10 * std::max(1.0, loss);
      w = next;
      loss = next_loss;
      if (converged) break;
    }
    return w;
  }

  double probability(const std::vector<double>& w, size_t i) const {
    double z = 0.0;
    for (size_t j = 0; j < d_; ++j) z += w[j] * x_[i * d_ + j];
    return z >= 0 ? 1.0 / (1.0 + std::exp(-z)) : std::exp(z) / (1.0 + std::exp(z));
  }

  // The same model on raw term values.
  ErrorModel unstandardised(const std::vector<double>& w) const {
    ErrorModel m;
    m.terms_ = terms_;
    m.weights_.assign(d_, 0.0);
    m.weights_[0] = w[0];
    for (size_t j = 1; j < d_; ++j) {
      m.weights_[j] = w[j] / scale_[j];
      m.weights_[0] -= w[j] * mean_[j] / scale_[j];
    }
    return m;
  }

 private:
  void standardise(size_t j) {
    double sum = 0.0, squares = 0.0;
    for (size_t i = 0; i < n_; ++i) sum += x_[i * d_ + j];
    mean_[j] = sum / double(n_);
    for (size_t i = 0; i < n_; ++i) squares += std::pow(x_[i * d_ + j] - mean_[j], 2);
    const double sd = std::sqrt(squares / double(n_));
    scale_[j] = sd > 1e-12 ? sd : 1.0;  // a constant term: its weight stays at the penalty's 0
    for (size_t i = 0; i < n_; ++i) x_[i * d_ + j] = (x_[i * d_ + j] - mean_[j]) / scale_[j];
  }

  // The penalised log loss at w over the rows where `use` is true.
  double objective(const std::vector<char>& use, double penalty,
                   const std::vector<double>& w) const {
    double loss = 0.0;
    for (size_t i = 0; i < n_; ++i) {
      if (!use[i]) continue;
      double z = 0.0;
      for (size_t j = 0; j < d_; ++j) z += w[j] * x_[i * d_ + j];
      // log(1 + e^z) - y z, stable for either sign of z
      loss += (z > 0 ? z + std::log1p(std::exp(-z)) : std::log1p(std::exp(z))) -
              (rows_[i].wrong ? z : 0.0);
    }
    for (size_t j = 1; j < d_; ++j) loss += 0.5 * penalty * w[j] * w[j];
    return loss;
  }

  // H^-1 g of the penalised log loss at w (Cholesky; H is positive definite for penalty > 0).
  std::vector<double> newtonStep(const std::vector<char>& use, double penalty,
                                 const std::vector<double>& w) const {
    std::vector<double> g(d_, 0.0), h(d_ * d_, 0.0);
    for (size_t i = 0; i < n_; ++i) {
      if (!use[i]) continue;
      const double p = probability(w, i), r = p - double(rows_[i].wrong), s = p * (1.0 - p);
      const double* xi = &x_[i * d_];
      for (size_t a = 0; a < d_; ++a) {
        g[a] += r * xi[a];
        const double sa = s * xi[a];
        for (size_t b = 0; b <= a; ++b) h[a * d_ + b] += sa * xi[b];
      }
    }
    for (size_t a = 1; a < d_; ++a) g[a] += penalty * w[a], h[a * d_ + a] += penalty;
    h[0] += 1e-9;
    return choleskySolve(h, g);
  }

  std::vector<double> choleskySolve(std::vector<double> h, std::vector<double> g) const {
    for (size_t a = 0; a < d_; ++a) {  // lower triangle in place
      for (size_t b = 0; b <= a; ++b) {
        double v = h[a * d_ + b];
        for (size_t k = 0; k < b; ++k) v -= h[a * d_ + k] * h[b * d_ + k];
        h[a * d_ + b] = a == b ? std::sqrt(std::max(v, 1e-12)) : v / h[b * d_ + b];
      }
    }
    for (size_t a = 0; a < d_; ++a) {
      for (size_t k = 0; k < a; ++k) g[a] -= h[a * d_ + k] * g[k];
      g[a] /= h[a * d_ + a];
    }
    for (size_t a = d_; a-- > 0;) {
      for (size_t k = a + 1; k < d_; ++k) g[a] -= h[k * d_ + a] * g[k];
      g[a] /= h[a * d_ + a];
    }
    return g;
  }

  const std::vector<ErrorRow>& rows_;
  std::vector<ErrorModel::Term> terms_;
  size_t n_, d_;
  std::vector<double> x_, mean_, scale_;
};

namespace {

// The intercept, each feature, its hinges at the quartiles and one offset per label seen.
std::vector<ErrorModel::Term> termsFor(const std::vector<ErrorRow>& rows, int num_classes) {
  using Term = ErrorModel::Term;
  std::vector<Term> terms{Term{}};
  for (int f = 0; f < ErrorModel::kNumFeatures; ++f) {
    terms.push_back({Term::kFeature, f, 0.0});
    std::vector<double> values(rows.size());
    for (size_t i = 0; i < rows.size(); ++i) values[i] = rows[i].x[f];
    std::sort(values.begin(), values.end());
    double last = values.front();
    for (double q : {0.25, 0.5, 0.75}) {
      const double knot = values[size_t(q * double(values.size() - 1))];
      if (knot > last && knot < values.back()) terms.push_back({Term::kHinge, f, knot});
      last = std::max(last, knot);
    }
  }
  std::vector<size_t> per_label(num_classes, 0);
  for (const ErrorRow& r : rows)
    if (r.label >= 0 && r.label < num_classes) ++per_label[r.label];
  for (int c = 0; c < num_classes; ++c)
    if (per_label[c] > 0) terms.push_back({Term::kLabel, c, 0.0});
  return terms;
}

double logLoss(double p, bool wrong) {
  return -std::log(std::clamp(wrong ? p : 1.0 - p, 1e-12, 1.0));
}

}  // namespace

ErrorModelFitResult fitErrorModel(const std::vector<ErrorRow>& all_rows, int num_classes,
                                  int folds, size_t max_rows) {
  const size_t stride = (all_rows.size() + max_rows - 1) / std::max<size_t>(max_rows, 1);
  std::vector<ErrorRow> rows;
  for (size_t i = 0; i < all_rows.size(); i += std::max<size_t>(stride, 1))
    rows.push_back(all_rows[i]);
  size_t wrong = 0;
  for (const ErrorRow& r : rows) wrong += r.wrong;
  if (wrong == 0 || wrong == rows.size()) {
    throw std::runtime_error("the error model needs labelled voxels both right and wrong (" +
                             std::to_string(wrong) + " of " + std::to_string(rows.size()) +
                             " wrong)");
  }
  const ErrorModelFit fit(rows, termsFor(rows, num_classes));
  ErrorModelFitResult result;
  double best_loss = INFINITY;
  for (double per_row : {1e-5, 1e-4, 1e-3, 1e-2, 1e-1}) {
    const double penalty = per_row * double(rows.size());
    std::vector<double> out_of_fold(all_rows.size());
    for (int k = 0; k < folds; ++k) {
      std::vector<char> use(rows.size());
      for (size_t i = 0; i < rows.size(); ++i) use[i] = int(rows[i].fold % folds) != k;
      const ErrorModel model = fit.unstandardised(fit.fit(use, penalty));
      for (size_t i = 0; i < all_rows.size(); ++i)
        if (int(all_rows[i].fold % folds) == k)
          out_of_fold[i] = model.probability(all_rows[i].x, all_rows[i].label);
    }
    double loss = 0.0;
    for (size_t i = 0; i < all_rows.size(); ++i) loss += logLoss(out_of_fold[i], all_rows[i].wrong);
    if (loss < best_loss) {
      best_loss = loss;
      result.out_of_fold = std::move(out_of_fold);
      result.penalty = penalty;
    }
  }
  result.model = fit.unstandardised(fit.fit(std::vector<char>(rows.size(), 1), result.penalty));
  return result;
}

}  // namespace evidential_octomap
