#include "dataset_writer.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "terrain.h"

namespace fs = std::filesystem;

namespace evidential_octomap::generator {

OutputSet OutputSet::parse(const std::string& list, const std::string& format) {
  OutputSet o;
  o.evidence = o.logits = o.probabilities = false;
  std::stringstream ss(list);
  for (std::string item; std::getline(ss, item, ',');) {
    if (item == "evidence")
      o.evidence = true;
    else if (item == "logits")
      o.logits = true;
    else if (item == "probabilities")
      o.probabilities = true;
    else if (item == "all")
      o.evidence = o.logits = o.probabilities = true;
    else
      throw std::invalid_argument("unknown output '" + item +
                                  "' (evidence, logits, probabilities, all)");
  }
  if (format != "bin" && format != "npy") {
    throw std::invalid_argument("unknown format '" + format + "' (bin, npy)");
  }
  o.npy = format == "npy";
  return o;
}

Eigen::Matrix4d kittiTr() {
  Eigen::Matrix4d Tr;
  Tr << -1.857739385241e-03, -9.999659513510e-01, -8.039975204516e-03, -4.784029760483e-03,
      -6.481465826011e-03, 8.051860151134e-03, -9.999466081774e-01, -7.337429464231e-02,
      9.999773098287e-01, -1.805528627661e-03, -6.496203536139e-03, -3.339968064433e-01, 0, 0, 0, 1;
  return Tr;
}

void writeFileBytes(const std::string& path, const void* data, size_t bytes,
                    const std::string& npy_header) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + tmp);
    out.write(npy_header.data(), std::streamsize(npy_header.size()));
    out.write(static_cast<const char*>(data), std::streamsize(bytes));
    if (!out) throw std::runtime_error("writing " + tmp + " failed");
  }
  fs::rename(tmp, path);
}

namespace {
std::string npyHeader(size_t rows, size_t cols) {
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" +
                       std::to_string(rows) + ", " + std::to_string(cols) + "), }";
  const size_t unpadded = 10 + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header.push_back('\n');
  const uint16_t len = uint16_t(header.size());
  return std::string("\x93NUMPY\x01\x00", 8) + char(len & 0xFF) + char(len >> 8) + header;
}
std::string stem(int scan) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%06d", scan);
  return buf;
}
}  // namespace

DatasetWriter::DatasetWriter(const std::string& dir, const OutputSet& outputs, int num_classes,
                             const std::vector<uint32_t>& raw_of_class, const KindClasses& classes)
    : dir_(dir),
      outputs_(outputs),
      C_(num_classes),
      raw_of_class_(raw_of_class),
      classes_(classes) {
  for (const char* d : {"velodyne", "labels", "predictions"}) fs::create_directories(dir + "/" + d);
  if (outputs.evidence) fs::create_directories(dir + "/evidence");
  if (outputs.logits) fs::create_directories(dir + "/logits");
  if (outputs.probabilities) fs::create_directories(dir + "/probabilities");
  movers_.open(dir + "/movers.csv", std::ios::trunc);
  if (!movers_) throw std::runtime_error("cannot write " + dir + "/movers.csv");
  movers_ << "scan,instance,class,x,y,z,yaw,length,width,height,points\n";
}

void DatasetWriter::writeScan(int scan, const std::vector<LidarPoint>& points,
                              const NetworkOutput& net) {
  const size_t n = points.size();
  const std::string s = stem(scan);
  std::vector<float> xyzr(4 * n);
  std::vector<uint32_t> labels(n), preds(n);
  for (size_t i = 0; i < n; ++i) {
    xyzr[4 * i] = points[i].p_S.x();
    xyzr[4 * i + 1] = points[i].p_S.y();
    xyzr[4 * i + 2] = points[i].p_S.z();
    xyzr[4 * i + 3] = points[i].remission;
    if (classes_.cls[int(points[i].kind)] < 0) {
      throw std::logic_error(std::string("generator: kind '") + kindInfo(points[i].kind).name +
                             "' has no class in the family's table");
    }
    labels[i] = kindInfo(points[i].kind).raw_id | (points[i].instance << 16);
    preds[i] = raw_of_class_[size_t(net.predicted[i])];
  }
  writeFileBytes(dir_ + "/velodyne/" + s + ".bin", xyzr.data(), xyzr.size() * 4);
  writeFileBytes(dir_ + "/labels/" + s + ".label", labels.data(), n * 4);
  writeFileBytes(dir_ + "/predictions/" + s + ".label", preds.data(), n * 4);
  const std::string ext = outputs_.npy ? ".npy" : ".bin";
  const std::string header = outputs_.npy ? npyHeader(n, size_t(C_)) : "";
  if (outputs_.evidence) {
    writeFileBytes(dir_ + "/evidence/" + s + ext, net.evidence.data(), n * C_ * 4, header);
  }
  if (outputs_.logits) {
    writeFileBytes(dir_ + "/logits/" + s + ext, net.logits.data(), n * C_ * 4, header);
  }
  if (outputs_.probabilities) {
    std::vector<float> p(n * C_);
    for (size_t i = 0; i < n; ++i) {
      const float* z = net.logits.data() + i * C_;
      float m = z[0];
      for (int c = 1; c < C_; ++c) m = std::max(m, z[c]);
      double sum = 0.0;
      for (int c = 0; c < C_; ++c) sum += std::exp(double(z[c] - m));
      for (int c = 0; c < C_; ++c) p[i * C_ + c] = float(std::exp(double(z[c] - m)) / sum);
    }
    writeFileBytes(dir_ + "/probabilities/" + s + ext, p.data(), n * C_ * 4, header);
  }
}

void DatasetWriter::addMoverRows(int scan, const std::vector<Mover>& movers, double t,
                                 const Terrain& terrain, const std::vector<LidarPoint>& points) {
  for (const Mover& m : movers) {
    if (!m.present(t)) continue;
    size_t hits = 0;
    for (const LidarPoint& p : points) hits += p.instance == m.instance;
    const Eigen::Vector3d c = m.centre(t, terrain);
    char buf[256];
    std::snprintf(buf, sizeof(buf), "%d,%u,%s,%.3f,%.3f,%.3f,%.4f,%.2f,%.2f,%.2f,%zu\n", scan,
                  m.instance, kindInfo(m.kind).name, c.x(), c.y(), c.z(), m.yaw(), m.size.x(),
                  m.size.y(), m.size.z(), hits);
    movers_ << buf;
  }
  movers_.flush();
}

void DatasetWriter::writePoses(const std::vector<Eigen::Isometry3d>& T_W_S) const {
  const Eigen::Matrix4d Tr = kittiTr(), Tr_inv = Tr.inverse();
  std::ostringstream poses;
  char buf[64];
  for (const Eigen::Isometry3d& T : T_W_S) {
    const Eigen::Matrix4d P = Tr * T.matrix() * Tr_inv;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        std::snprintf(buf, sizeof(buf), "%s%.12e", (r || c) ? " " : "", P(r, c));
        poses << buf;
      }
    }
    poses << "\n";
  }
  writeText("poses.txt", poses.str());
  std::ostringstream calib;
  // P0..P3 as KITTI's (rectified camera projections); the reader needs only Tr.
  calib << "P0: 7.070912e+02 0 6.018873e+02 0 0 7.070912e+02 1.831104e+02 0 0 0 1 0\n";
  calib << "Tr:";
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      std::snprintf(buf, sizeof(buf), " %.12e", Tr(r, c));
      calib << buf;
    }
  }
  calib << "\n";
  writeText("calib.txt", calib.str());
}

void DatasetWriter::writeText(const std::string& name, const std::string& text) const {
  writeFileBytes(dir_ + "/" + name, text.data(), text.size());
}

}  // namespace evidential_octomap::generator
