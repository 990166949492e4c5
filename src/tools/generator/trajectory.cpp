#include "trajectory.h"

#include <cmath>
#include <stdexcept>

#include "noise.h"
#include "rng.h"
#include "terrain.h"

namespace evidential_octomap::generator {

RouteKind parseRoute(const std::string& name) {
  if (name == "loop") return RouteKind::kLoop;
  if (name == "out-and-back") return RouteKind::kOutAndBack;
  if (name == "line") return RouteKind::kLine;
  throw std::invalid_argument("unknown route '" + name + "' (loop, out-and-back, line)");
}

const char* routeName(RouteKind r) {
  switch (r) {
    case RouteKind::kLoop:
      return "loop";
    case RouteKind::kOutAndBack:
      return "out-and-back";
    case RouteKind::kLine:
      return "line";
  }
  return "?";
}

Route Route::make(RouteKind kind, double length, uint64_t seed) {
  Route r;
  r.kind = kind;
  const uint64_t key = hashOf(seed, kStreamTrajectory);
  if (kind == RouteKind::kLoop) {
    // r(phi) = R (1 + sum_k a_k cos(k phi + phase_k)): a convex-ish wobbly loop, scaled so that
    // its perimeter is `length`.
    double a[3], phase[3];
    for (int k = 0; k < 3; ++k) {
      a[k] = 0.05 + 0.08 * unitOf(hashOf(key, 1, k));
      phase[k] = 6.283185307179586 * unitOf(hashOf(key, 2, k));
    }
    const int n = 4096;
    std::vector<Eigen::Vector2d> dense(n + 1);
    for (int i = 0; i <= n; ++i) {
      const double phi = 6.283185307179586 * i / n;
      double rad = 1.0;
      for (int k = 0; k < 3; ++k) rad += a[k] * std::cos((k + 2) * phi + phase[k]);
      dense[i] = rad * Eigen::Vector2d(std::cos(phi), std::sin(phi));
    }
    double perimeter = 0.0;
    for (int i = 0; i < n; ++i) perimeter += (dense[i + 1] - dense[i]).norm();
    const double scale = length / perimeter;
    // Resample by arc length; the start (phi = 0) is at the origin's east.
    double acc = 0.0, next = 0.0;
    for (int i = 0; i < n && r.xy.size() < size_t(length / r.step); ++i) {
      const Eigen::Vector2d p = dense[i] * scale, q = dense[i + 1] * scale;
      const double seg = (q - p).norm();
      while (next <= acc + seg && r.xy.size() < size_t(length / r.step)) {
        r.xy.push_back(p + (q - p) * ((next - acc) / seg));
        next += r.step;
      }
      acc += seg;
    }
    r.length = double(r.xy.size()) * r.step;
  } else {
    // A heading that wanders smoothly (+-70 degrees over ~60 m), integrated.
    const size_t n = size_t(length / r.step) + 1;
    const double h0 = 6.283185307179586 * unitOf(hashOf(key, 3));
    Eigen::Vector2d p(0.0, 0.0);
    for (size_t i = 0; i < n; ++i) {
      r.xy.push_back(p);
      const double s = i * r.step;
      const double h = h0 + 1.2 * fbm2(hashOf(key, 4), s, 0.0, 60.0, 3);
      p += r.step * Eigen::Vector2d(std::cos(h), std::sin(h));
    }
    r.length = double(n - 1) * r.step;
  }
  return r;
}

Eigen::Vector2d Route::at(double s) const {
  const size_t n = xy.size();
  if (kind == RouteKind::kLoop) {
    s = std::fmod(s, length);
    if (s < 0) s += length;
  } else {
    s = std::clamp(s, 0.0, length);
  }
  const double f = s / step;
  const size_t i = std::min(size_t(f), n - 1);
  const size_t j = kind == RouteKind::kLoop ? (i + 1) % n : std::min(i + 1, n - 1);
  const double w = f - double(i);
  return xy[i] * (1.0 - w) + xy[j] * w;
}

Eigen::Vector2d Route::tangent(double s) const {
  // Over +-2 m, so the heading is smooth between samples.
  Eigen::Vector2d d = at(s + 2.0) - at(s - 2.0);
  if (kind != RouteKind::kLoop && (s < 2.0 || s > length - 2.0)) {
    d = at(std::min(s + 2.0, length)) - at(std::max(s - 2.0, 0.0));
  }
  const double n = d.norm();
  return n > 1e-9 ? Eigen::Vector2d(d / n) : Eigen::Vector2d(1.0, 0.0);
}

void Trajectory::planar(double t, Eigen::Vector2d* xy, double* heading) const {
  const double d = distanceDriven(t);
  auto headingAt = [&](double s, bool back) {
    const Eigen::Vector2d tg = route_.tangent(s) * (back ? -1.0 : 1.0);
    return std::atan2(tg.y(), tg.x());
  };
  if (route_.kind != RouteKind::kOutAndBack) {
    *xy = route_.at(d);
    *heading = headingAt(d, false);
    return;
  }
  // Out, turn in place, back, turn in place, ...: a period of 2 L / v + 2 pi / turn_rate.
  const double L = route_.length, v = motion_.speed;
  const double turn_time = 3.141592653589793 / motion_.turn_rate;
  const double period = 2.0 * (L / v + turn_time);
  double tau = std::fmod(std::max(t, 0.0), period);
  if (tau < L / v) {
    *xy = route_.at(tau * v);
    *heading = headingAt(tau * v, false);
  } else if ((tau -= L / v) < turn_time) {
    *xy = route_.at(L);
    *heading = headingAt(L, false) + motion_.turn_rate * tau;
  } else if ((tau -= turn_time) < L / v) {
    *xy = route_.at(L - tau * v);
    *heading = headingAt(L - tau * v, true);
  } else {
    tau -= L / v;
    *xy = route_.at(0.0);
    *heading = headingAt(0.0, true) + motion_.turn_rate * tau;
  }
}

double Trajectory::maxArcLength(double t) const {
  return std::min(distanceDriven(t), route_.length);
}

Eigen::Isometry3d Trajectory::pose(double t) const {
  Eigen::Vector2d p;
  double heading;
  planar(t, &p, &heading);
  const Eigen::Vector2d f(std::cos(heading), std::sin(heading)), l(-f.y(), f.x());
  // Roll and pitch of a 2.4 m x 1.8 m footprint resting on the terrain.
  auto ground = [&](const Eigen::Vector2d& q) {
    return Eigen::Vector3d(q.x(), q.y(), terrain_.groundHeight(q.x(), q.y()));
  };
  const Eigen::Vector3d front = ground(p + 1.2 * f), back = ground(p - 1.2 * f);
  const Eigen::Vector3d left = ground(p + 0.9 * l), right = ground(p - 0.9 * l);
  const Eigen::Vector3d x = (front - back).normalized();
  const Eigen::Vector3d z = x.cross((left - right).normalized()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  const Eigen::Vector3d centre = 0.25 * (front + back + left + right);
  T.translation() = centre + motion_.sensor_height * z;
  return T;
}

}  // namespace evidential_octomap::generator
