// The sequence generator (`evidential_octomap generate`), end to end: datasets written by the CLI
// are read back through Dataset (the reader every command uses) and checked against the world
// rebuilt from the same options, and against statistics computed here from the files.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <unordered_map>

#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/class_table.h"
#include "generator/kinds.h"
#include "generator/network_model.h"
#include "generator/world.h"
#include "test_helpers.h"

namespace fs = std::filesystem;
namespace g = evidential_octomap::generator;
using evidential_octomap::ClassTable;
using evidential_octomap::Dataset;
using evidential_octomap::Scan;
using namespace tools_test;

namespace {

int run(const std::string& args, std::string* output = nullptr) {
  const CliResult r = runCli(args);
  if (output) *output = r.output;
  return r.status;
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The tiny scene the tests share: a forest, 512 columns, 12 scans (1.2 s), 4 movers, a higher
// share of wrong cells than the preset (more of them to measure).
const char* kTinyArgs =
    "generate --scene forest --sensor os1-64 --columns 512 --movers 4 "
    "--wrong-rate 0.05 --outputs all -q";

g::WorldOptions tinyWorldOptions() {
  g::WorldOptions o;
  o.family = g::Family::kForest;
  o.sensor = "os1-64";
  o.columns = 512;
  o.scans = 12;
  o.seed = 7;
  o.movers = 4;
  return o;
}

// Generated once per test process; `extra` are further CLI options.
std::string dataset(const std::string& name, const std::string& extra) {
  static std::map<std::string, std::string> made;
  auto it = made.find(name);
  if (it != made.end()) return it->second;
  const std::string dir = freshDir("gen_" + name) + "/data";
  std::string out;
  const int rc = run(std::string(kTinyArgs) + " " + extra + " --out " + dir, &out);
  EXPECT_EQ(rc, 0) << out;
  made[name] = dir;
  return dir;
}
std::string tiny() { return dataset("tiny", "--seed 7 --scans 12 --threads 1"); }

struct Loaded {
  ClassTable classes;
  std::vector<Scan> scans;
  std::vector<std::vector<uint32_t>> raw_labels;
};

std::unique_ptr<Loaded> load(const std::string& dir) {
  auto l = std::make_unique<Loaded>();
  l->classes = ClassTable::load(dir + "/classes.yaml");
  const Dataset d = Dataset::open(dir, l->classes);
  EXPECT_TRUE(d.hasLabels());
  EXPECT_TRUE(d.hasPredictions());
  EXPECT_TRUE(d.hasEvidence());
  for (size_t i = 0; i < d.size(); ++i) {
    l->scans.push_back(d.load(i));
    l->raw_labels.push_back(
        evidential_octomap::readLabelFile(dir + "/labels/" + d.stems()[i] + ".label"));
    EXPECT_EQ(l->raw_labels.back().size(), l->scans.back().size());  // no all-zero points
  }
  return l;
}

int classNamed(const ClassTable& t, const std::string& name) {
  for (int c = 0; c < t.numClasses(); ++c)
    if (t.names[c] == name) return c;
  return -1;
}

struct Rate {
  size_t n = 0, wrong = 0;
  void add(bool is_wrong) { ++n, wrong += is_wrong; }
  double value() const { return n ? double(wrong) / n : 0.0; }
};

}  // namespace

TEST(Generator, SameSeedGivesByteIdenticalDatasetOnOneAndTwoThreads) {
  const std::string a = tiny(), b = dataset("tiny_2threads", "--seed 7 --scans 12 --threads 2");
  size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(a)) {
    if (!entry.is_regular_file()) continue;
    const fs::path rel = fs::relative(entry.path(), a);
    ASSERT_TRUE(fs::exists(fs::path(b) / rel)) << rel;
    std::string x = readAll(entry.path()), y = readAll((fs::path(b) / rel).string());
    if (rel == "README.md") {  // the command lines differ in --out only
      const size_t p = x.find(a), q = y.find(b);
      ASSERT_NE(p, std::string::npos);
      ASSERT_NE(q, std::string::npos);
      x.replace(p, a.size(), "DIR");
      y.replace(q, b.size(), "DIR");
    }
    EXPECT_TRUE(x == y) << rel << " differs";
    ++files;
  }
  // 12 scans x (velodyne, labels, predictions, evidence, logits, probabilities) + README,
  // calib, classes, movers, network_metrics, poses.
  EXPECT_EQ(files, 12u * 6u + 6u);
  EXPECT_NE(readAll(a + "/README.md").find("SYNTHETIC"), std::string::npos);
}

TEST(Generator, DifferentSeedGivesADifferentScene) {
  const std::string a = tiny(), c = dataset("seed8", "--seed 8 --scans 12");
  EXPECT_NE(readAll(a + "/velodyne/000000.bin"), readAll(c + "/velodyne/000000.bin"));
}

TEST(Generator, EveryFamilyWritesADatasetItsOwnClassTableReads) {
  for (const std::string family : {"forest", "grassland", "rocky", "farm"}) {
    const std::string dir = freshDir("gen_family_" + family) + "/data";
    std::string out;
    ASSERT_EQ(run("generate --scene " + family +
                      " --sensor hdl-64 --columns 256 --scans 2 --seed 1 -q --out " + dir,
                  &out),
              0)
        << out;
    const std::string config =
        std::string(EVIDENTIAL_TEST_CONFIG_DIR) + "/classes_offroad_" + family + ".yaml";
    EXPECT_EQ(readAll(dir + "/classes.yaml"), readAll(config)) << family;
    const ClassTable t = ClassTable::load(config);
    EXPECT_GE(t.numClasses(), 8) << family;
    EXPECT_LE(t.numClasses(), 13) << family;
    // Every raw label id written is in the table's learning map (Dataset::load throws if not),
    // and more than two classes are seen.
    const Dataset d = Dataset::open(dir, t);
    std::set<int> seen;
    for (size_t i = 0; i < d.size(); ++i) {
      const Scan s = d.load(i);
      seen.insert(s.gt.begin(), s.gt.end());
      EXPECT_EQ(s.evidence.size(), s.size() * size_t(t.numClasses()));
    }
    EXPECT_GT(seen.size(), 2u) << family;
  }
}

TEST(Generator, EveryKindAFamilyPlacesHasAClassInItsTable) {
  for (const std::string family : {"forest", "grassland", "rocky", "farm"}) {
    const ClassTable t = ClassTable::load(std::string(EVIDENTIAL_TEST_CONFIG_DIR) +
                                          "/classes_offroad_" + family + ".yaml");
    g::WorldOptions o;
    o.family = g::parseFamily(family);
    o.scans = 2000;  // 400 m: the whole loop, its puddles, fences and buildings
    o.seed = 3;
    const auto world = g::World::make(o, t);
    std::set<g::Kind> kinds;
    const g::Grid2& e = world->scene->extent;
    for (int j = 0; j < e.ny; j += 2)
      for (int i = 0; i < e.nx; i += 2)
        kinds.insert(world->scene->terrain.kindAt(e.cx(i), e.cy(j)));
    for (const g::Primitive& p : world->scene->objects) kinds.insert(p.kind);
    for (const g::Mover& m : world->movers) kinds.insert(m.kind);
    EXPECT_GE(kinds.size(), 5u) << family;
    for (g::Kind k : kinds) {
      EXPECT_GE(world->classes.cls[int(k)], 1) << family << ": " << g::kindInfo(k).name;
    }
  }
}

TEST(Generator, ClassTablesFollowRellis3dWhereItHasTheClass) {
  const ClassTable rellis = ClassTable::load(rellisClasses());
  std::map<std::string, uint32_t> rellis_raw;  // name -> raw id, from the RELLIS learning map
  for (const auto& [raw, cls] : rellis.learning_map) {
    if (cls != rellis.ignore_class) rellis_raw[rellis.names[cls]] = raw;
  }
  std::set<size_t> sizes;
  for (const std::string family : {"forest", "grassland", "rocky", "farm"}) {
    const ClassTable t = ClassTable::load(std::string(EVIDENTIAL_TEST_CONFIG_DIR) +
                                          "/classes_offroad_" + family + ".yaml");
    sizes.insert(size_t(t.numClasses()));
    EXPECT_EQ(t.ignore_class, 0);
    for (int c = 1; c < t.numClasses(); ++c) {
      const int r = classNamed(rellis, t.names[c]);
      if (r < 0) continue;
      EXPECT_EQ(t.colors[c], rellis.colors[r]) << family << " " << t.names[c];
      ASSERT_TRUE(rellis_raw.count(t.names[c])) << t.names[c];
      const auto it = t.learning_map.find(rellis_raw[t.names[c]]);
      ASSERT_NE(it, t.learning_map.end()) << family << " " << t.names[c];
      EXPECT_EQ(it->second, c) << family << " " << t.names[c];
    }
  }
  EXPECT_GT(sizes.size(), 1u);  // C differs between families
}

TEST(Generator, InstanceIdsAreOnMoverPointsOnlyAndInsideTheirMoversCsvBoxes) {
  const std::string dir = tiny();
  const auto l = load(dir);
  // movers.csv: scan,instance,class,x,y,z,yaw,length,width,height,points
  struct Row {
    std::string cls;
    double x, y, z, yaw, len, wid, hgt;
    size_t points;
  };
  std::map<std::pair<int, uint32_t>, Row> rows;
  std::ifstream csv(dir + "/movers.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "scan,instance,class,x,y,z,yaw,length,width,height,points");
  while (std::getline(csv, line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream in(line);
    int scan;
    uint32_t inst;
    Row r;
    in >> scan >> inst >> r.cls >> r.x >> r.y >> r.z >> r.yaw >> r.len >> r.wid >> r.hgt >>
        r.points;
    ASSERT_FALSE(in.fail()) << line;
    rows[{scan, inst}] = r;
  }
  ASSERT_FALSE(rows.empty());
  const int person = classNamed(l->classes, "person"), vehicle = classNamed(l->classes, "vehicle");
  size_t mover_points = 0;
  std::set<uint32_t> instances_seen;
  for (size_t s = 0; s < l->scans.size(); ++s) {
    const Scan& scan = l->scans[s];
    std::map<uint32_t, size_t> count;
    for (size_t i = 0; i < scan.size(); ++i) {
      const uint32_t inst = l->raw_labels[s][i] >> 16;
      const int cls = scan.gt[i];
      // The forest has no parked vehicles: person and vehicle points are movers, and only they.
      EXPECT_EQ(inst != 0, cls == person || cls == vehicle) << "scan " << s << " point " << i;
      if (inst == 0) continue;
      ++count[inst];
      const auto it = rows.find({int(s), inst});
      ASSERT_NE(it, rows.end()) << "scan " << s << " instance " << inst << " not in movers.csv";
      const Row& r = it->second;
      EXPECT_EQ(r.cls, l->classes.names[cls]);
      // The point (read through poses.txt and Tr) is on the box surface.
      const Eigen::Vector3f p = scan.pointW(i);
      const double dx = p.x() - r.x, dy = p.y() - r.y;
      const double lx = std::cos(r.yaw) * dx + std::sin(r.yaw) * dy;
      const double ly = -std::sin(r.yaw) * dx + std::cos(r.yaw) * dy;
      const double tol = 0.12;  // range noise
      EXPECT_LE(std::abs(lx), 0.5 * r.len + tol);
      EXPECT_LE(std::abs(ly), 0.5 * r.wid + tol);
      EXPECT_LE(std::abs(p.z() - r.z), 0.5 * r.hgt + tol);
    }
    for (const auto& [inst, n] : count) {
      EXPECT_EQ(rows[std::make_pair(int(s), inst)].points, n) << "scan " << s << " inst " << inst;
      mover_points += n;
      instances_seen.insert(inst);
    }
  }
  EXPECT_GT(mover_points, 50u);
  EXPECT_GE(instances_seen.size(), 2u);
}

TEST(Generator, GroundPointsLieOnTheTerrainThroughPosesAndANonIdentityTr) {
  const std::string dir = tiny();
  const Eigen::Matrix4d Tr = evidential_octomap::readKittiCalibTr(dir + "/calib.txt");
  EXPECT_GT((Tr.block<3, 3>(0, 0) - Eigen::Matrix3d::Identity()).norm(), 1.0);
  EXPECT_NEAR(
      (Tr.block<3, 3>(0, 0) * Tr.block<3, 3>(0, 0).transpose() - Eigen::Matrix3d::Identity())
          .norm(),
      0.0, 1e-6);
  const auto l = load(dir);
  const auto world = g::World::make(tinyWorldOptions(), l->classes);
  const int dirt = classNamed(l->classes, "dirt"), tree = classNamed(l->classes, "tree");
  size_t n = 0, close = 0;
  double sum = 0.0;
  for (const Scan& scan : l->scans) {
    for (size_t i = 0; i < scan.size(); ++i) {
      if (scan.gt[i] != dirt) continue;  // bare trail: no grass layer
      const Eigen::Vector3f p = scan.pointW(i);
      const double dz = p.z() - world->scene->terrain.groundHeight(p.x(), p.y());
      ++n;
      sum += dz;
      close += std::abs(dz) < 0.12;  // a few sigma of range noise at grazing incidence
    }
  }
  ASSERT_GT(n, 500u);
  EXPECT_GT(double(close) / n, 0.97);
  EXPECT_NEAR(sum / n, 0.0, 0.02);
  // And the sensor is where the trajectory says, 1.8 m above the ground.
  for (size_t s = 0; s < l->scans.size(); ++s) {
    const Eigen::Vector3d o = l->scans[s].originW();
    const Eigen::Isometry3d T = world->trajectory->pose(world->scanTime(int(s)));
    EXPECT_LT((o - T.translation()).norm(), 1e-6);
    EXPECT_NEAR(o.z() - world->scene->terrain.groundHeight(o.x(), o.y()), 1.8, 0.2);
  }
  // Trees stand: their points reach well above the ground.
  double top = 0.0;
  for (const Scan& scan : l->scans)
    for (size_t i = 0; i < scan.size(); ++i)
      if (scan.gt[i] == tree) {
        const Eigen::Vector3f p = scan.pointW(i);
        top = std::max(top, p.z() - world->scene->terrain.groundHeight(p.x(), p.y()));
      }
  EXPECT_GT(top, 5.0);
}

TEST(Generator, ConsistentlyWrongCellsAreWrongInEveryScanWithTheSameClass) {
  const std::string dir = tiny();
  const auto l = load(dir);
  g::NetworkParams p = g::NetworkParams::preset_named("good");
  p.wrong_rate = 0.05;  // as kTinyArgs
  const g::KindClasses kc = g::KindClasses::of(l->classes);
  const g::NetworkModel model(p, kc, l->classes.numClasses(), 0.0, 7);
  Rate inside, outside;
  const int C = l->classes.numClasses();
  double u_inside = 0.0, u_wrong_outside = 0.0;  // sums of the vacuity u = C / S
  // (cell, true class) -> predicted class -> count, and the scans it was seen in.
  std::map<std::tuple<int64_t, int64_t, int64_t, int>, std::map<int, size_t>> votes;
  std::map<std::tuple<int64_t, int64_t, int64_t, int>, std::set<size_t>> seen_in;
  for (size_t s = 0; s < l->scans.size(); ++s) {
    const Scan& scan = l->scans[s];
    for (size_t i = 0; i < scan.size(); ++i) {
      if (scan.gt[i] <= 0) continue;
      const Eigen::Vector3f q = scan.pointW(i);
      const bool wrong = scan.predicted[i] != scan.gt[i];
      double S = C;
      for (int c = 0; c < C; ++c) S += scan.evidence[i * C + c];
      if (!model.wrongCell(q.x(), q.y(), q.z())) {
        outside.add(wrong);
        if (wrong) u_wrong_outside += C / S;
        continue;
      }
      inside.add(wrong);
      u_inside += C / S;
      const auto key = std::make_tuple(int64_t(std::floor(q.x() / p.wrong_cell)),
                                       int64_t(std::floor(q.y() / p.wrong_cell)),
                                       int64_t(std::floor(q.z() / p.wrong_cell)), scan.gt[i]);
      ++votes[key][scan.predicted[i]];
      seen_in[key].insert(s);
    }
  }
  ASSERT_GT(inside.n, 2000u);
  EXPECT_GT(inside.value(), 0.9);
  EXPECT_LT(outside.value(), 0.3);
  // Confidently wrong: less vacuity than the network's other errors.
  EXPECT_LT(u_inside / inside.n, 0.7 * u_wrong_outside / outside.wrong);
  // Seen in several scans, a cell's points of one class get one and the same wrong class.
  size_t cells = 0, consistent = 0;
  for (const auto& [key, v] : votes) {
    if (seen_in[key].size() < 3) continue;
    size_t total = 0, best = 0;
    int best_class = -1;
    for (const auto& [cls, n] : v) {
      total += n;
      if (n > best) best = n, best_class = cls;
    }
    if (total < 20) continue;
    ++cells;
    consistent += best >= 0.95 * total && best_class != std::get<3>(key);
  }
  ASSERT_GT(cells, 10u);
  EXPECT_GT(double(consistent) / cells, 0.9);
}

TEST(Generator, ErrorRateRisesWithRange) {
  const auto l = load(tiny());
  Rate near, far;
  for (const Scan& scan : l->scans) {
    for (size_t i = 0; i < scan.size(); ++i) {
      if (scan.gt[i] <= 0) continue;
      const double r = scan.points_S[i].norm();
      const bool wrong = scan.predicted[i] != scan.gt[i];
      if (r < 20.0) near.add(wrong);
      if (r > 40.0) far.add(wrong);
    }
  }
  ASSERT_GT(far.n, 1000u);
  EXPECT_GT(far.value(), 1.5 * near.value()) << "near " << near.value() << " far " << far.value();
}

TEST(Generator, RareClassesAreWorseThanCommonOnes) {
  const auto l = load(tiny());
  std::set<int> rare, common;
  for (const char* n : {"person", "vehicle", "log"}) rare.insert(classNamed(l->classes, n));
  for (const char* n : {"grass", "tree", "dirt"}) common.insert(classNamed(l->classes, n));
  Rate r, c;
  for (const Scan& scan : l->scans) {
    for (size_t i = 0; i < scan.size(); ++i) {
      if (scan.points_S[i].norm() > 30.0) continue;  // the same ranges for both
      const bool wrong = scan.predicted[i] != scan.gt[i];
      if (rare.count(scan.gt[i])) r.add(wrong);
      if (common.count(scan.gt[i])) c.add(wrong);
    }
  }
  ASSERT_GT(r.n, 200u);
  EXPECT_GT(r.value(), 2.0 * c.value()) << "rare " << r.value() << " common " << c.value();
}

TEST(Generator, GroundPointsAtClassBordersAreConfusedMore) {
  const auto l = load(tiny());
  std::set<int> ground;
  for (const char* n : {"dirt", "grass", "mud"}) ground.insert(classNamed(l->classes, n));
  Rate border, inner;
  const double cell = 0.25;
  for (const Scan& scan : l->scans) {
    // xy hash grid of the scan's labelled world points.
    std::unordered_map<int64_t, std::vector<size_t>> grid;
    std::vector<Eigen::Vector3f> pw(scan.size());
    auto key = [&](int64_t i, int64_t j) { return i * 1000003 + j; };
    for (size_t i = 0; i < scan.size(); ++i) {
      pw[i] = scan.pointW(i);
      grid[key(int64_t(std::floor(pw[i].x() / cell)), int64_t(std::floor(pw[i].y() / cell)))]
          .push_back(i);
    }
    for (size_t i = 0; i < scan.size(); ++i) {
      if (!ground.count(scan.gt[i]) || scan.points_S[i].norm() > 20.0) continue;
      // Distance in xy to the nearest point of another class (up to 2 m).
      double best = 2.0;
      const int64_t ci = int64_t(std::floor(pw[i].x() / cell)),
                    cj = int64_t(std::floor(pw[i].y() / cell));
      for (int64_t dj = -8; dj <= 8; ++dj)
        for (int64_t di = -8; di <= 8; ++di) {
          const auto it = grid.find(key(ci + di, cj + dj));
          if (it == grid.end()) continue;
          for (size_t k : it->second) {
            if (scan.gt[k] == scan.gt[i] || scan.gt[k] <= 0) continue;
            best = std::min(best, double((pw[k] - pw[i]).head<2>().norm()));
          }
        }
      const bool wrong = scan.predicted[i] != scan.gt[i];
      if (best < 0.3) border.add(wrong);
      if (best >= 2.0) inner.add(wrong);
    }
  }
  ASSERT_GT(border.n, 300u);
  ASSERT_GT(inner.n, 300u);
  EXPECT_GT(border.value(), 1.5 * inner.value())
      << "border " << border.value() << " inner " << inner.value();
}

TEST(Generator, EvidenceScalesWithTheEvidenceScaleAndPredictionsDoNot) {
  const std::string a = tiny(), b = dataset("scale4", "--seed 7 --scans 12 --evidence-scale 4");
  const auto x = load(a), y = load(b);
  ASSERT_EQ(x->scans.size(), y->scans.size());
  for (size_t s = 0; s < x->scans.size(); ++s) {
    ASSERT_EQ(x->scans[s].evidence.size(), y->scans[s].evidence.size());
    EXPECT_EQ(x->scans[s].predicted, y->scans[s].predicted);
    for (size_t k = 0; k < x->scans[s].evidence.size(); k += 7) {
      EXPECT_NEAR(y->scans[s].evidence[k], 4.0f * x->scans[s].evidence[k],
                  1e-5f * y->scans[s].evidence[k] + 1e-30f);
    }
  }
}

TEST(Generator, ConfidenceFlagsErrorsImperfectly) {
  // AUROC of u = C / S for "prediction wrong", computed here from the evidence files.
  const auto l = load(tiny());
  const int C = l->classes.numClasses();
  std::vector<std::pair<double, bool>> v;
  for (const Scan& scan : l->scans) {
    for (size_t i = 0; i < scan.size(); ++i) {
      if (scan.gt[i] <= 0) continue;
      double S = C;
      for (int c = 0; c < C; ++c) S += scan.evidence[i * C + c];
      v.emplace_back(C / S, scan.predicted[i] != scan.gt[i]);
    }
  }
  std::sort(v.begin(), v.end());
  double rank_sum = 0.0;
  size_t pos = 0;
  for (size_t i = 0; i < v.size(); ++i)
    if (v[i].second) rank_sum += double(i + 1), ++pos;
  const double neg = double(v.size() - pos);
  const double auroc = (rank_sum - double(pos) * (pos + 1) / 2.0) / (double(pos) * neg);
  const double accuracy = 1.0 - double(pos) / v.size();
  EXPECT_GT(auroc, 0.6);
  EXPECT_LT(auroc, 0.95);  // real, but imperfect
  EXPECT_GT(accuracy, 0.6);
  EXPECT_LT(accuracy, 0.95);
}

TEST(Generator, MapReadsTheGeneratedEvidence) {
  const std::string dir = tiny();
  const std::string out = freshDir("gen_map");
  std::string log;
  ASSERT_EQ(run("map --data " + dir + " --classes " + dir + "/classes.yaml --evidence file " +
                    "--scans 3 --no-render -q --out " + out,
                &log),
            0)
      << log;
  EXPECT_TRUE(fs::exists(out + "/map.ot"));
  EXPECT_TRUE(fs::exists(out + "/metrics.json"));
}

TEST(Generator, MotionDistortedPointsAreStoredInTheEndOfSweepFrame) {
  // At 5 m/s a sweep moves the sensor 0.5 m: trunk points must still lie on their trunks when
  // read through the end-of-sweep pose, and differ from the undistorted sweep.
  const std::string args = "--seed 11 --scans 3 --speed 5 --threads 2";
  const std::string a = dataset("distorted", args + " --motion-distortion");
  const std::string b = dataset("undistorted", args);
  EXPECT_NE(readAll(a + "/velodyne/000002.bin"), readAll(b + "/velodyne/000002.bin"));
  const auto l = load(a);
  g::WorldOptions o = tinyWorldOptions();
  o.seed = 11;
  o.scans = 3;
  o.speed = 5.0;
  const auto world = g::World::make(o, l->classes);
  const int tree = classNamed(l->classes, "tree");
  std::vector<const g::Primitive*> trunks;
  for (const g::Primitive& p : world->scene->objects)
    if (p.kind == g::Kind::kTree && p.shape == g::Shape::kCylinderZ) trunks.push_back(&p);
  size_t n = 0, on = 0;
  for (const Scan& scan : l->scans) {
    for (size_t i = 0; i < scan.size(); ++i) {
      if (scan.gt[i] != tree || scan.points_S[i].norm() > 25.0) continue;
      const Eigen::Vector3f p = scan.pointW(i);
      if (p.z() - world->scene->terrain.groundHeight(p.x(), p.y()) > 1.0) continue;  // trunk
      double best = 1e9, radius = 0.0;
      for (const g::Primitive* t : trunks) {
        const double d = (p.head<2>() - t->centre.head<2>()).norm();
        if (d - t->half.x() < best - radius) best = d, radius = t->half.x();
      }
      ++n;
      on += std::abs(best - radius) < 0.1;
    }
  }
  ASSERT_GT(n, 200u);
  EXPECT_GT(double(on) / n, 0.95);
}

TEST(Generator, RewritesItsOwnDatasetWholeAndRefusesAnyOtherDirectory) {
  const std::string dir = freshDir("gen_rewrite") + "/data";
  std::string out;
  const std::string args = "generate --columns 128 --movers 1 -q --out " + dir;
  ASSERT_EQ(run(args + " --scans 4", &out), 0) << out;
  ASSERT_EQ(run(args + " --scans 2", &out), 0) << out;
  EXPECT_FALSE(fs::exists(dir + "/velodyne/000003.bin"));  // no scan of the longer run is left
  const ClassTable t = ClassTable::load(dir + "/classes.yaml");
  EXPECT_EQ(Dataset::open(dir, t).size(), 2u);
  const std::string other = freshDir("gen_other");
  writeBinary(other + "/keep.bin", std::vector<float>{1.0f});
  EXPECT_NE(run("generate --columns 128 --scans 1 -q --out " + other, &out), 0);
  EXPECT_NE(out.find("refusing"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(other + "/keep.bin"));
}
