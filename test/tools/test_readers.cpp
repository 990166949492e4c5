#include <gtest/gtest.h>

#include <Eigen/LU>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <vector>

#include "evidential_octomap/evaluation/dataset.h"
#include "evidential_octomap/evaluation/dataset_c.h"
#include "test_helpers.h"

namespace fs = std::filesystem;
using evidential_octomap::ClassTable;
using evidential_octomap::LogitTransform;
using evidential_octomap::Dataset;
using evidential_octomap::InputConversion;
using evidential_octomap::readFloatMatrix;
using evidential_octomap::writeNpy;
using namespace tools_test;

namespace {
// Independent of the reader: the 12 numbers of a line, padded to 4 x 4.
Eigen::Matrix4d matrixFromNumbers(std::istringstream& in) {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) in >> T(r, c);
  return T;
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no exception)";
}
}  // namespace

TEST(KittiReader, ScanCountsMatchTheFiles) {
  const ClassTable classes = ClassTable::load(kittiClasses());
  const Dataset d = Dataset::open(kittiDir(), classes);
  ASSERT_EQ(d.size(), 10u);
  EXPECT_EQ(d.layout(), Dataset::Layout::kSemanticKitti);
  EXPECT_TRUE(d.hasLabels());
  EXPECT_TRUE(d.hasPredictions());
  EXPECT_FALSE(d.hasEvidence());
  for (size_t i : {size_t(0), size_t(9)}) {
    const auto scan = d.load(i);
    const size_t expected = fs::file_size(kittiDir() + "/velodyne/" + scan.name + ".bin") / 16;
    EXPECT_EQ(scan.size() + scan.dropped_no_return, expected);
    EXPECT_EQ(scan.dropped_no_return, 0u);  // KITTI has no zero points
    EXPECT_EQ(scan.gt.size(), scan.size());
    EXPECT_EQ(scan.predicted.size(), scan.size());
    EXPECT_GT(scan.size(), 120000u);
    EXPECT_LT(scan.size(), 126000u);
  }
  EXPECT_EQ(d.load(0).size(), 123389u);  // 000000.bin is 1,974,224 bytes
}

TEST(KittiReader, PoseOfScan0IsInvTrTimesPTimesTr) {
  // Hand computation from the text files, without the reader's parsing code.
  std::ifstream calib(kittiDir() + "/calib.txt");
  std::string line;
  Eigen::Matrix4d Tr = Eigen::Matrix4d::Zero();
  while (std::getline(calib, line)) {
    if (line.rfind("Tr:", 0) == 0) {
      std::istringstream in(line.substr(3));
      Tr = matrixFromNumbers(in);
    }
  }
  std::ifstream poses(kittiDir() + "/poses.txt");
  std::getline(poses, line);
  std::istringstream in0(line);
  const Eigen::Matrix4d P0 = matrixFromNumbers(in0);
  const Eigen::Matrix4d expected = Tr.inverse() * P0 * Tr;

  const ClassTable classes = ClassTable::load(kittiClasses());
  const Dataset d = Dataset::open(kittiDir(), classes);
  EXPECT_TRUE(d.pose(0).isApprox(expected, 1e-12)) << d.pose(0) << "\nvs\n" << expected;
  // P0 is (numerically) the identity, so the Velodyne pose of scan 0 is too.
  EXPECT_LT((d.pose(0) - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-6);
  // About 0.7 m per scan forward, in the Velodyne x direction.
  const Eigen::Vector3d t1 = d.pose(1).block<3, 1>(0, 3);
  EXPECT_GT(t1.norm(), 0.5);
  EXPECT_LT(t1.norm(), 1.0);
  EXPECT_GT(t1.x(), 0.5);
}

TEST(RellisReader, SinglePoselessScanDropsNoReturnPoints) {
  const ClassTable classes = ClassTable::load(rellisClasses());
  const Dataset d = Dataset::open(rellisDir(), classes);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d.layout(), Dataset::Layout::kSingleScan);
  EXPECT_TRUE(d.pose(0).isIdentity());
  const auto scan = d.load(0);
  EXPECT_EQ(scan.size(), 77708u);             // README: 77 708 valid
  EXPECT_EQ(scan.dropped_no_return, 53364u);  // README: 53 364 zero points
  EXPECT_TRUE(scan.predicted.empty());
  // README label counts (every zero point is void, so the others keep their counts).
  std::vector<size_t> count(classes.numClasses(), 0);
  for (int c : scan.gt) ++count[c];
  EXPECT_EQ(count[1], 18040u);  // grass
  EXPECT_EQ(count[2], 17872u);  // tree
  EXPECT_EQ(count[7], 1310u);   // person
  EXPECT_EQ(count[13], 100u);   // mud
}

TEST(RellisReader, AcceptsTheBinPathItself) {
  const ClassTable classes = ClassTable::load(rellisClasses());
  const Dataset d = Dataset::open(rellisDir() + "/000104.bin", classes);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d.load(0).size(), 77708u);
}

// --- error paths ------------------------------------------------------------------------------

class BrokenKitti : public ::testing::Test {
 protected:
  void SetUp() override {
    classes = ClassTable::load(kittiClasses());
    dir = freshDir("broken_kitti");
    fs::create_directories(dir + "/velodyne");
    fs::create_directories(dir + "/labels");
    writeBinary(dir + "/velodyne/000000.bin", std::vector<float>(4 * 10, 1.0f));
    fs::copy_file(kittiDir() + "/calib.txt", dir + "/calib.txt");
    std::ofstream(dir + "/poses.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  }
  ClassTable classes;
  std::string dir;
};

TEST(ReaderErrors, MissingDirectoryNamesThePath) {
  const ClassTable classes = ClassTable::load(kittiClasses());
  const std::string msg = messageOf([&] { Dataset::open("/nonexistent/seq", classes); });
  EXPECT_NE(msg.find("/nonexistent/seq"), std::string::npos) << msg;
}

TEST_F(BrokenKitti, LabelCountMismatchNamesTheLabelFile) {
  writeBinary(dir + "/labels/000000.label", std::vector<uint32_t>(9, 40));
  const Dataset d = Dataset::open(dir, classes);
  const std::string msg = messageOf([&] { d.load(0); });
  EXPECT_NE(msg.find("labels/000000.label"), std::string::npos) << msg;
  EXPECT_NE(msg.find("9 labels"), std::string::npos) << msg;
}

TEST_F(BrokenKitti, UnknownLabelIdNamesFileAndId) {
  std::vector<uint32_t> labels(10, 40);
  labels[3] = 7777;
  writeBinary(dir + "/labels/000000.label", labels);
  const Dataset d = Dataset::open(dir, classes);
  const std::string msg = messageOf([&] { d.load(0); });
  EXPECT_NE(msg.find("000000.label"), std::string::npos) << msg;
  EXPECT_NE(msg.find("7777"), std::string::npos) << msg;
}

TEST_F(BrokenKitti, TruncatedBinNamesTheBinFile) {
  writeBinary(dir + "/labels/000000.label", std::vector<uint32_t>(10, 40));
  writeBinary(dir + "/velodyne/000000.bin", std::vector<float>(4 * 10 - 1, 1.0f));
  const Dataset d = Dataset::open(dir, classes);
  const std::string msg = messageOf([&] { d.load(0); });
  EXPECT_NE(msg.find("velodyne/000000.bin"), std::string::npos) << msg;
}

TEST_F(BrokenKitti, MissingPosesNamesTheFile) {
  fs::remove(dir + "/poses.txt");
  const std::string msg = messageOf([&] { Dataset::open(dir, classes); });
  EXPECT_NE(msg.find("poses.txt"), std::string::npos) << msg;
}

TEST_F(BrokenKitti, EvidenceFileOfWrongSizeNamesTheFile) {
  writeBinary(dir + "/labels/000000.label", std::vector<uint32_t>(10, 40));
  fs::create_directories(dir + "/evidence");
  writeBinary(dir + "/evidence/000000.bin", std::vector<float>(10 * 19, 1.0f));  // C is 20
  const Dataset d = Dataset::open(dir, classes);
  ASSERT_TRUE(d.hasEvidence());
  const std::string msg = messageOf([&] { d.load(0); });
  EXPECT_NE(msg.find("evidence/000000.bin"), std::string::npos) << msg;
}

TEST_F(BrokenKitti, AlphaFilesBecomeEvidence) {
  writeBinary(dir + "/labels/000000.label", std::vector<uint32_t>(10, 40));
  fs::create_directories(dir + "/alpha");
  std::vector<float> alpha(10 * 20, 1.0f);
  alpha[3 * 20 + 9] = 6.0f;  // point 3: alpha 6 for road -> evidence 5
  writeBinary(dir + "/alpha/000000.bin", alpha);
  const auto scan = Dataset::open(dir, classes).load(0);
  ASSERT_EQ(scan.evidence.size(), 200u);
  EXPECT_FLOAT_EQ(scan.evidence[3 * 20 + 9], 5.0f);
  EXPECT_FLOAT_EQ(scan.evidence[0], 0.0f);
}

TEST_F(BrokenKitti, LogitsFilesBecomeEvidenceByTheChosenTransform) {
  writeBinary(dir + "/labels/000000.label", std::vector<uint32_t>(10, 40));
  fs::create_directories(dir + "/logits");
  std::vector<float> z(10 * 20, 0.0f);
  z[3 * 20 + 9] = 2.0f;
  writeBinary(dir + "/logits/000000.bin", z);
  InputConversion edl;
  edl.logit_transform = LogitTransform::kExp;
  const Dataset d = Dataset::open(dir, classes, edl);
  EXPECT_EQ(d.evidenceKind(), "logits");
  EXPECT_NE(d.describeEvidenceFiles().find("exp"), std::string::npos);
  const auto scan = d.load(0);
  EXPECT_NEAR(scan.evidence[3 * 20 + 9], std::exp(2.0f), 1e-5);
  EXPECT_NEAR(scan.evidence[3 * 20 + 8], 1.0f, 1e-6);  // exp(0)
  // softmax (default): uniform logits of point 0 give no evidence at all (u = 1).
  const auto soft = Dataset::open(dir, classes).load(0);
  for (int c = 0; c < 20; ++c) EXPECT_NEAR(soft.evidence[c], 0.0f, 1e-6);
}

TEST_F(BrokenKitti, BadProbabilityFileNamesFileAndPoint) {
  writeBinary(dir + "/labels/000000.label", std::vector<uint32_t>(10, 40));
  fs::create_directories(dir + "/probabilities");
  std::vector<float> p(10 * 20, 0.05f);
  p[4 * 20 + 2] = -1.0f;
  writeBinary(dir + "/probabilities/000000.bin", p);
  const std::string msg = messageOf([&] { Dataset::open(dir, classes).load(0); });
  EXPECT_NE(msg.find("probabilities/000000.bin"), std::string::npos) << msg;
  EXPECT_NE(msg.find("point 4"), std::string::npos) << msg;
}

TEST(FloatMatrixReader, ReadsNpyVersion1) {
  const std::string dir = freshDir("npy");
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }";
  while ((10 + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::ofstream out(dir + "/e.npy", std::ios::binary);
  out.write("\x93NUMPY\x01\x00", 8);
  const uint16_t len = uint16_t(header.size());
  out.put(char(len & 0xFF));
  out.put(char(len >> 8));
  out << header;
  const float v[6] = {0, 1, 2, 3, 4, 5};
  out.write(reinterpret_cast<const char*>(v), sizeof v);
  out.close();
  const auto m = readFloatMatrix(dir + "/e.npy", 2, 3);
  ASSERT_EQ(m.size(), 6u);
  EXPECT_FLOAT_EQ(m[5], 5.0f);
  EXPECT_THROW(readFloatMatrix(dir + "/e.npy", 3, 3), std::runtime_error);
}

// Issue 16 item 9 (every writer atomic): kill -9 at random moments of a `features` .npy write
// leaves the previous file whole (written in place, a kill mid-write left a torn file).
TEST(NpyWriter, KilledAtAnyMomentLeavesTheOldFileWhole) {
  const std::string path = freshDir("npy_kill") + "/f.npy";
  const size_t rows = 1 << 18, cols = 4;
  const std::vector<float> old_values(rows * cols, 1.0f), new_values(rows * cols, 2.0f);
  const auto t0 = std::chrono::steady_clock::now();
  writeNpy(path, old_values.data(), rows, cols);
  const double write_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> delay(0.0, 2.0 * write_ms);
  for (int trial = 0; trial < 8; ++trial) {
    ASSERT_TRUE(killedAfter(delay(rng), [&] {
      for (;;) writeNpy(path, new_values.data(), rows, cols);
    }));
    const std::vector<float> read = readFloatMatrix(path, rows, cols);  // throws when torn
    ASSERT_EQ(read.size(), rows * cols) << "trial " << trial;
    EXPECT_TRUE(read == old_values || read == new_values) << "trial " << trial << ": mixed file";
  }
}

// The C entry points (dataset_c.h, what the ROS player calls through ctypes) give what the C++
// reader gives: the same points, classes of the chosen files and pose, and clear errors.
TEST(DatasetCApi, ScanEqualsTheCppReadersScan) {
  const ClassTable classes = ClassTable::load(kittiClasses());
  const Dataset d = Dataset::open(kittiDir(), classes);
  const evidential_octomap::Scan expected = d.load(3);
  char error[512] = "";
  evidential_octomap_dataset* c =
      evidential_octomap_dataset_open(kittiDir().c_str(), kittiClasses().c_str(), error, 512);
  ASSERT_NE(c, nullptr) << error;
  EXPECT_EQ(evidential_octomap_dataset_size(c), d.size());
  for (const char* from : {"predictions", "labels"}) {
    const long long n = evidential_octomap_dataset_load(c, 3, from, error, sizeof(error));
    ASSERT_EQ(n, static_cast<long long>(expected.size())) << error;
    std::vector<float> xyz(3 * n), remission(n);
    std::vector<int32_t> ids(n);
    double pose[16];
    char name[32];
    evidential_octomap_dataset_scan(c, xyz.data(), remission.data(), ids.data(), pose, name, 32);
    EXPECT_STREQ(name, expected.name.c_str());
    const std::vector<int>& want = std::string(from) == "labels" ? expected.gt : expected.predicted;
    EXPECT_TRUE(std::equal(want.begin(), want.end(), ids.begin())) << from;
    EXPECT_EQ(remission, expected.remission);
    for (size_t i = 0; i < expected.size(); i += 997) {
      EXPECT_EQ(xyz[3 * i + 2], expected.points_S[i].z()) << i;
    }
    for (int k = 0; k < 16; ++k) EXPECT_EQ(pose[k], d.pose(3)(k / 4, k % 4)) << k;
  }
  EXPECT_EQ(evidential_octomap_dataset_load(c, 3, "evidence", error, sizeof(error)), -1);
  EXPECT_NE(std::string(error).find("\"predictions\" or \"labels\""), std::string::npos) << error;
  EXPECT_EQ(evidential_octomap_dataset_load(c, 10, "labels", error, sizeof(error)), -1);
  EXPECT_NE(std::string(error).find("no scan 10"), std::string::npos) << error;
  evidential_octomap_dataset_close(c);
}

TEST(DatasetCApi, OpeningAMissingDirectoryNamesIt) {
  char error[512] = "";
  EXPECT_EQ(evidential_octomap_dataset_open("/nonexistent/kitti", kittiClasses().c_str(), error,
                                            sizeof(error)),
            nullptr);
  EXPECT_NE(std::string(error).find("/nonexistent/kitti"), std::string::npos) << error;
  // A message longer than the buffer is cut, never written past it.
  char small[8];
  std::fill(small, small + 8, 'x');
  EXPECT_EQ(evidential_octomap_dataset_open("/nonexistent/kitti", kittiClasses().c_str(), small, 4),
            nullptr);
  EXPECT_EQ(small[3], '\0');
  EXPECT_EQ(small[4], 'x');
}
