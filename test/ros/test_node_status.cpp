// toDiagnosticStatus: OK while nothing was dropped since the last report, WARN naming each
// reason otherwise, and every counter as a key/value pair.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "node_status.h"

using namespace evidential_octomap;

namespace {

std::map<std::string, std::string> valuesOf(const diagnostic_msgs::DiagnosticStatus& d) {
  std::map<std::string, std::string> v;
  for (const auto& kv : d.values) v[kv.key] = kv.value;
  return v;
}

MappingStatus sample() {
  MappingStatus s;
  s.clouds_received = 12;
  s.clouds_inserted = 9;
  s.clouds_dropped_queue = 3;
  s.clouds_dropped_invalid = 1;
  s.clouds_dropped_tf = 2;
  s.queue_length = 1;
  s.queue_capacity = 1;
  s.last_insert_ms = 1234.5;
  s.map_leaves = 551000;
  return s;
}

}  // namespace

TEST(NodeStatus, NoNewDropsIsOk) {
  const MappingStatus s = sample();
  const auto d = toDiagnosticStatus(s, s, "/mapper");
  EXPECT_EQ(d.level, diagnostic_msgs::DiagnosticStatus::OK);
  EXPECT_EQ(d.name, "/mapper: cloud insertion");
  EXPECT_NE(d.message.find("9 clouds inserted"), std::string::npos) << d.message;
}

TEST(NodeStatus, NewDropsWarnWithEachReason) {
  MappingStatus before = sample(), now = sample();
  now.clouds_dropped_queue += 4;
  now.clouds_dropped_tf += 1;
  const auto d = toDiagnosticStatus(now, before, "/mapper");
  EXPECT_EQ(d.level, diagnostic_msgs::DiagnosticStatus::WARN);
  EXPECT_NE(d.message.find("dropped 5 clouds"), std::string::npos) << d.message;
  EXPECT_NE(d.message.find("4: insertion queue full"), std::string::npos) << d.message;
  EXPECT_NE(d.message.find("0: unreadable"), std::string::npos) << d.message;
  EXPECT_NE(d.message.find("1: no transform"), std::string::npos) << d.message;
  EXPECT_EQ(cloudsDropped(now), 7u + 1u + 3u);
}

TEST(NodeStatus, EveryCounterIsAKeyValue) {
  const auto v = valuesOf(toDiagnosticStatus(sample(), MappingStatus(), "/mapper"));
  EXPECT_EQ(v.at("clouds received"), "12");
  EXPECT_EQ(v.at("clouds inserted"), "9");
  EXPECT_EQ(v.at("dropped: insertion queue full"), "3");
  EXPECT_EQ(v.at("dropped: unreadable"), "1");
  EXPECT_EQ(v.at("dropped: no transform"), "2");
  EXPECT_EQ(v.at("queue length"), "1");
  EXPECT_EQ(v.at("last insert [ms]"), "1234.5");
  EXPECT_EQ(v.at("map leaves"), "551000");
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
