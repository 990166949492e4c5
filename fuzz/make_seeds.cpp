// Writes the seed corpus of the fuzz targets: real .ot files made by the library itself (so the
// seeds follow the file format as it changes), foreign OctoMap trees, and the class tables.
//   make_seeds <out_dir> <source_dir>
// out_dir/ot/*.ot, out_dir/class_table/*.yaml and out_dir/pointcloud2/*.bin are created. source_dir is the repository root
// (data/semantickitti_08_first10 and config/ are read from it; a missing dataset is skipped).
#include <sys/stat.h>

#include <cstdint>
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"

using evidential_octomap::EvidentialOcTree;
using evidential_octomap::SemanticConfig;

namespace {

void makeDir(const std::string& path) { ::mkdir(path.c_str(), 0755); }

size_t fileSize(const std::string& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  return in ? static_cast<size_t>(in.tellg()) : 0;
}

void save(const EvidentialOcTree& tree, const std::string& path) {
  evidential_octomap::saveMap(tree, path);
  std::cout << "  " << path << " (" << fileSize(path) << " B, " << tree.size() << " nodes, "
            << tree.numSemanticNodes() << " semantic)\n";
}

// A small synthetic scan: ground plane and a wall seen from origin, random evidence with some
// zero vectors, some confident points and some large values.
void syntheticScan(std::mt19937& rng, int num_classes, int n, octomap::Pointcloud* points,
                   std::vector<float>* evidence) {
  std::uniform_real_distribution<float> u01(0.f, 1.f);
  for (int i = 0; i < n; ++i) {
    const bool wall = i % 3 == 0;
    const float a = u01(rng) * 4.f - 2.f, b = u01(rng) * 2.f;
    if (wall) {
      points->push_back(3.0f, a, b);
    } else {
      points->push_back(1.0f + 2.f * u01(rng), a, 0.0f);
    }
    const int cls = wall ? (num_classes - 1) : 0;
    for (int c = 0; c < num_classes; ++c) {
      float e = (c == cls) ? 5.0f + 20.f * u01(rng) : u01(rng);
      if (i % 17 == 0) e = 0.0f;
      if (i % 29 == 0 && c == cls) e = 1e6f;
      evidence->push_back(e);
    }
  }
}

EvidentialOcTree syntheticMap(const std::string& rule, int num_classes, int scans, double res,
                              unsigned seed) {
  SemanticConfig config;
  config.rule = rule;
  EvidentialOcTree tree(res, num_classes, config);
  std::vector<std::string> names;
  for (int c = 0; c < num_classes; ++c) names.push_back("c" + std::to_string(c));
  tree.setClassNames(names);
  std::mt19937 rng(seed);
  for (int s = 0; s < scans; ++s) {
    octomap::Pointcloud points;
    std::vector<float> evidence;
    syntheticScan(rng, num_classes, 40, &points, &evidence);
    tree.insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.1f * s, 1.0f));
  }
  return tree;
}

std::vector<char> readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// One SemanticKITTI scan, subsampled, with the network's predictions as one-hot evidence.
bool kittiMap(const std::string& source_dir, const std::string& out_path) {
  const std::string dir = source_dir + "/data/semantickitti_08_first10/";
  const std::vector<char> bin = readFile(dir + "velodyne/000000.bin");
  const std::vector<char> labels = readFile(dir + "predictions/000000.label");
  if (bin.empty() || labels.size() * 4 != bin.size()) {
    std::cout << "  (SemanticKITTI scan not found or inconsistent, skipped)\n";
    return false;
  }
  const auto classes =
      evidential_octomap::ClassTable::load(source_dir + "/config/classes_semantickitti.yaml");
  const int num_classes = classes.numClasses();
  const size_t n = labels.size() / 4;
  const float* xyzr = reinterpret_cast<const float*>(bin.data());
  const uint32_t* raw = reinterpret_cast<const uint32_t*>(labels.data());
  octomap::Pointcloud points;
  std::vector<float> evidence;
  for (size_t i = 0; i < n; i += 97) {  // ~1.3k points, ~300 of them within 6 m
    const float x = xyzr[4 * i], y = xyzr[4 * i + 1], z = xyzr[4 * i + 2];
    if (x * x + y * y > 6.f * 6.f) continue;
    int cls = 0;
    try {
      cls = classes.classOfRaw(raw[i]);
    } catch (const std::out_of_range&) {
      continue;
    }
    points.push_back(x, y, z);
    for (int c = 0; c < num_classes; ++c) evidence.push_back(c == cls ? 20.0f : 0.0f);
  }
  EvidentialOcTree tree(0.5, num_classes);
  tree.setClassNames(classes.names);
  tree.insertSemanticScan(points, evidence, octomap::point3d(0.f, 0.f, 0.f));
  save(tree, out_path);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: make_seeds <out_dir> <source_dir>\n";
    return 2;
  }
  const std::string out = argv[1], source = argv[2];
  makeDir(out);
  makeDir(out + "/ot");
  makeDir(out + "/class_table");
  const std::string ot = out + "/ot/";
  try {
    save(EvidentialOcTree(0.1, 1), ot + "empty_c1.ot");
    {
      SemanticConfig sbki;
      sbki.rule = "sbki";
      save(EvidentialOcTree(0.25, 20, sbki), ot + "empty_c20_sbki.ot");  // header, no nodes
    }
    save(syntheticMap("dempster", 3, 2, 0.4, 1), ot + "dempster_c3.ot");
    save(syntheticMap("dempster", 1, 1, 0.5, 2), ot + "dempster_c1.ot");
    save(syntheticMap("sbki", 2, 1, 0.25, 3), ot + "sbki_c2.ot");
    save(syntheticMap("ebs", 4, 1, 0.3, 4), ot + "ebs_c4.ot");

    // A pruned block: eight sibling leaves with identical occupancy and payload.
    {
      EvidentialOcTree tree(0.2, 2);
      const octomap::OcTreeKey base = tree.coordToKey(octomap::point3d(0.05f, 0.05f, 0.05f));
      for (int i = 0; i < 8; ++i) {
        octomap::OcTreeKey key(base[0] & ~1, base[1] & ~1, base[2] & ~1);
        key[0] += i & 1;
        key[1] += (i >> 1) & 1;
        key[2] += (i >> 2) & 1;
        auto* leaf = evidential_octomap::detail::TreeEditing::leafForUpdate(tree, key, true);
        leaf->setLogOdds(0.85f);
        const float payload[2] = {1.5f, 0.25f};
        evidential_octomap::detail::TreeEditing::setPayload(tree, leaf, payload);
      }
      evidential_octomap::detail::TreeEditing::updateInnerNodes(tree);
      save(tree, ot + "pruned_c2.ot");
    }
    kittiMap(source, ot + "kitti08_000000_c20.ot");

    // Foreign trees: the generic reader returns them; loadMap must refuse them cleanly.
    {
      octomap::OcTree plain(0.2);
      octomap::ColorOcTree color(0.2);
      for (float x = 0.f; x < 1.f; x += 0.2f) {
        plain.updateNode(octomap::point3d(x, 0.f, 0.f), true);
        color.updateNode(octomap::point3d(x, 0.f, 0.f), true)->setColor(255, 0, 0);
      }
      plain.write(ot + "foreign_octree.ot");
      color.write(ot + "foreign_color.ot");
      std::cout << "  " << ot << "foreign_{octree,color}.ot\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "make_seeds: " << e.what() << "\n";
    return 1;
  }

  // PointCloud2 messages in fuzz_pointcloud2.cpp's encoding: options, fields, layout, data.
  makeDir(out + "/pointcloud2");
  {
    auto seed = [&](const std::string& name, std::vector<uint8_t> head, int points, int step,
                    const std::vector<float>& per_point) {
      std::vector<uint8_t> bytes = head;
      bytes.insert(bytes.end(), {1, uint8_t(points), 0, uint8_t(step), uint8_t(points * step),
                                 uint8_t((points * step) >> 8)});
      for (int i = 0; i < points; ++i) {
        std::vector<uint8_t> point(step, 0);
        std::memcpy(point.data(), per_point.data(),
                    std::min(per_point.size() * sizeof(float), size_t(step)));
        point[0] ^= uint8_t(i);  // points differ a little
        bytes.insert(bytes.end(), point.begin(), point.end());
      }
      std::ofstream(out + "/pointcloud2/" + name, std::ios::binary)
          .write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
    };
    // name indices: x 0, y 1, z 2, evidence 3, evidence_0.. 4-6, alpha 7, alpha_0/1 8/9, label 10
    // datatypes: uint16 4, float32 7, float64 8
    seed("evidence_c3.bin", {2, 0, 0, 4, 0, 0, 7, 1, 1, 4, 7, 1, 2, 8, 7, 1, 3, 12, 7, 3}, 4, 24,
         {1.5f, 0.5f, 0.2f, 5.0f, 0.1f, 0.0f});
    seed("channels_c3.bin", {2, 1, 0, 6, 0, 0, 7, 1, 1, 4, 7, 1, 2, 8, 7, 1, 4, 12, 7, 1, 5, 16,
                             7, 1, 6, 20, 7, 1}, 3, 24, {2.0f, 1.0f, 0.0f, 0.0f, 9.0f, 1.0f});
    seed("alpha_c2.bin", {1, 2, 0, 5, 0, 0, 7, 1, 1, 4, 7, 1, 2, 8, 7, 1, 8, 12, 7, 1, 9, 16, 7, 1},
         3, 20, {3.0f, -1.0f, 0.5f, 4.0f, 1.0f});
    seed("label_c4_bigendian.bin", {3, 3, 1, 4, 0, 0, 7, 1, 1, 4, 7, 1, 2, 8, 7, 1, 10, 12, 4, 1},
         4, 16, {0.0f, 0.0f, 0.0f, 0.0f});
    seed("double_xyz_c1.bin", {0, 0, 2, 4, 0, 0, 8, 1, 1, 8, 8, 1, 2, 16, 8, 1, 3, 24, 7, 1}, 2,
         28, {0.0f, 1.875f, 0.0f, 0.0f, 0.0f, 0.0f, 3.0f});
  }

  // Class tables: the shipped ones and a minimal one.
  for (const char* name : {"classes_semantickitti.yaml", "classes_rellis3d.yaml"}) {
    const std::vector<char> text = readFile(source + "/config/" + name);
    if (text.empty()) continue;
    std::ofstream(out + "/class_table/" + name, std::ios::binary).write(text.data(), text.size());
  }
  std::ofstream(out + "/class_table/minimal.yaml")
      << "dataset: tiny\nignore_class: 0\nclasses:\n  - {name: a, color: [1, 2, 3]}\n"
         "  - {name: b, color: [4, 5, 6]}\nlearning_map:\n  0: 0\n  7: 1\n";
  // Service calls (fuzzMapServices): byte strings of one kind of call each, and a mix.
  makeDir(out + "/services");
  for (int kind = 0; kind < 6; ++kind) {
    std::vector<uint8_t> bytes;
    uint32_t state = 1234567u + kind;
    for (int i = 0; i < 96; ++i) {
      state = state * 1664525u + 1013904223u;
      bytes.push_back(i % 24 == 0 ? uint8_t(kind < 5 ? kind : state >> 24) : uint8_t(state >> 24));
    }
    std::ofstream(out + "/services/calls_" + std::to_string(kind) + ".bin", std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
  }
  std::cout << "seeds written to " << out << "\n";
  return 0;
}
