// compareTrees(): two EvidentialOcTrees are equal when their settings match and every node
// (inner and leaf) has the same child layout, bit-identical log-odds and a bit-identical payload.
// Shared by the file, merge and copy tests (voxblox layer_test_utils style).
#pragma once

#include <gtest/gtest.h>
#include <octomap/OcTreeNode.h>

#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "evidential_octomap/detail/tree_editing.h"
#include "evidential_octomap/evidential_octree.h"

namespace evidential_octomap {
namespace test {

// A field-count check: a node that grows a field must have it serialised and compared here.
static_assert(sizeof(EvidentialOcTreeNode) == sizeof(octomap::OcTreeNode),
              "EvidentialOcTreeNode grew a field: serialise it in read/writeData and compare it "
              "in compareTrees()");

inline bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }
inline bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// Adds `amount` to class c of a leaf's payload (the prior where it has none): a hand edit.
inline void addToClass(EvidentialOcTree& tree, EvidentialOcTreeNode* leaf, int c, float amount) {
  std::vector<float> p = tree.payload(leaf);
  if (p.empty()) p.assign(tree.numClasses(), tree.rule().prior());
  p[c] += amount;
  detail::TreeEditing::setPayload(tree, leaf, p.data());
}

namespace detail {

inline bool compareNodes(const EvidentialOcTree& a, const EvidentialOcTreeNode* na,
                         const EvidentialOcTree& b, const EvidentialOcTreeNode* nb,
                         const std::string& where, std::string* why) {
  if (!sameBits(na->getValue(), nb->getValue())) {
    std::ostringstream s;
    s << where << ": log-odds " << na->getValue() << " vs " << nb->getValue();
    *why = s.str();
    return false;
  }
  if (na->hasSemantics() != nb->hasSemantics()) {
    *why = where + ": payload present in only one tree";
    return false;
  }
  const std::vector<float> pa = a.payload(na);
  const std::vector<float> pb = b.payload(nb);
  if (pa.size() != pb.size() || pa.empty() == na->hasSemantics()) {
    *why = where + ": payload() disagrees with hasSemantics()";
    return false;
  }
  if (!pa.empty()) {
    for (int c = 0; c < a.numClasses(); ++c) {
      if (!sameBits(pa[c], pb[c])) {
        std::ostringstream s;
        s << where << ": payload[" << c << "] " << pa[c] << " vs " << pb[c];
        *why = s.str();
        return false;
      }
    }
  }
  for (unsigned i = 0; i < 8; ++i) {
    const bool ca = a.nodeChildExists(na, i), cb = b.nodeChildExists(nb, i);
    if (ca != cb) {
      *why = where + ": child " + std::to_string(i) + " exists in only one tree";
      return false;
    }
    if (ca && !compareNodes(a, a.getNodeChild(na, i), b, b.getNodeChild(nb, i),
                            where + "/" + std::to_string(i), why)) {
      return false;
    }
  }
  return true;
}

}  // namespace detail

// Compares semantic settings (C, class names, rule and every parameter in SemanticConfig that
// the file format stores), occupancy parameters and all nodes.
inline ::testing::AssertionResult compareTrees(const EvidentialOcTree& a,
                                               const EvidentialOcTree& b) {
  auto fail = [](const std::string& what) { return ::testing::AssertionFailure() << what; };
  if (a.getTreeType() != b.getTreeType()) return fail("tree type differs");
  if (!sameBits(a.getResolution(), b.getResolution())) return fail("resolution differs");
  if (a.numClasses() != b.numClasses()) {
    return fail("C differs: " + std::to_string(a.numClasses()) + " vs " +
                std::to_string(b.numClasses()));
  }
  if (a.classNames() != b.classNames()) return fail("class names differ");
  if (a.rule().type() != b.rule().type()) return fail("fusion rule differs");
  const SemanticConfig& ca = a.config();
  const SemanticConfig& cb = b.config();
  if (ca.rule != cb.rule) return fail("config.rule differs");
  if (!sameBits(ca.length_scale, cb.length_scale) || !sameBits(ca.sigma0, cb.sigma0) ||
      !sameBits(ca.beta, cb.beta) || !sameBits(ca.gamma, cb.gamma) ||
      !sameBits(ca.drop_percent, cb.drop_percent) ||
      !sameBits(ca.ds_multiplier, cb.ds_multiplier) || !sameBits(ca.max_range, cb.max_range) ||
      !sameBits(ca.sbki_prior, cb.sbki_prior) || !sameBits(ca.evidence_cap, cb.evidence_cap)) {
    return fail("a numeric SemanticConfig parameter differs");
  }
  if (ca.adaptive_length != cb.adaptive_length ||
      ca.uncertainty_threshold != cb.uncertainty_threshold ||
      ca.reference_compat != cb.reference_compat ||
      ca.kernel_creates_leaves != cb.kernel_creates_leaves || ca.discretize != cb.discretize) {
    return fail("a SemanticConfig switch differs");
  }
  if (!sameBits(a.getClampingThresMinLog(), b.getClampingThresMinLog()) ||
      !sameBits(a.getClampingThresMaxLog(), b.getClampingThresMaxLog()) ||
      !sameBits(a.getProbHitLog(), b.getProbHitLog()) ||
      !sameBits(a.getProbMissLog(), b.getProbMissLog()) ||
      !sameBits(a.getOccupancyThresLog(), b.getOccupancyThresLog())) {
    return fail("occupancy parameters differ");
  }
  if (a.size() != b.size()) {
    return fail("node count differs: " + std::to_string(a.size()) + " vs " +
                std::to_string(b.size()));
  }
  if (a.numSemanticNodes() != b.numSemanticNodes()) {
    return fail("semantic node count differs: " + std::to_string(a.numSemanticNodes()) + " vs " +
                std::to_string(b.numSemanticNodes()));
  }
  if ((a.getRoot() == nullptr) != (b.getRoot() == nullptr)) return fail("only one tree is empty");
  if (a.getRoot()) {
    std::string why;
    if (!detail::compareNodes(a, a.getRoot(), b, b.getRoot(), "root", &why)) return fail(why);
  }
  return ::testing::AssertionSuccess();
}

}  // namespace test
}  // namespace evidential_octomap
