#include "node_status.h"

#include <cstdio>
#include <utility>

namespace evidential_octomap {
namespace {

void addValue(diagnostic_msgs::DiagnosticStatus* status, const std::string& key, double value) {
  diagnostic_msgs::KeyValue kv;
  kv.key = key;
  char text[64];
  std::snprintf(text, sizeof(text), "%.10g", value);
  kv.value = text;
  status->values.push_back(kv);
}

}  // namespace

diagnostic_msgs::DiagnosticStatus toDiagnosticStatus(const MappingStatus& now,
                                                     const MappingStatus& before,
                                                     const std::string& node_name) {
  diagnostic_msgs::DiagnosticStatus d;
  d.name = node_name + ": cloud insertion";
  d.hardware_id = node_name;
  const uint64_t queue = now.clouds_dropped_queue - before.clouds_dropped_queue;
  const uint64_t invalid = now.clouds_dropped_invalid - before.clouds_dropped_invalid;
  const uint64_t tf = now.clouds_dropped_tf - before.clouds_dropped_tf;
  char text[256];
  if (queue + invalid + tf > 0) {
    d.level = diagnostic_msgs::DiagnosticStatus::WARN;
    std::snprintf(text, sizeof(text),
                  "dropped %llu clouds since the last report (%llu: insertion queue full, %llu: "
                  "unreadable, %llu: no transform); insert %.0f ms",
                  static_cast<unsigned long long>(queue + invalid + tf),
                  static_cast<unsigned long long>(queue), static_cast<unsigned long long>(invalid),
                  static_cast<unsigned long long>(tf), now.last_insert_ms);
  } else {
    d.level = diagnostic_msgs::DiagnosticStatus::OK;
    std::snprintf(text, sizeof(text), "%llu clouds inserted, none dropped since the last report",
                  static_cast<unsigned long long>(now.clouds_inserted));
  }
  d.message = text;
  const std::pair<const char*, double> values[] = {
      {"clouds received", double(now.clouds_received)},
      {"clouds inserted", double(now.clouds_inserted)},
      {"dropped: insertion queue full", double(now.clouds_dropped_queue)},
      {"dropped: unreadable", double(now.clouds_dropped_invalid)},
      {"dropped: no transform", double(now.clouds_dropped_tf)},
      {"queue length", double(now.queue_length)},
      {"queue capacity", double(now.queue_capacity)},
      {"last insert [ms]", double(now.last_insert_ms)},
      {"mean insert [ms]", double(now.mean_insert_ms)},
      {"map leaves", double(now.map_leaves)},
      {"map semantic leaves", double(now.map_semantic_leaves)},
      {"map memory [bytes]", double(now.map_memory_bytes)}};
  for (const auto& [key, value] : values) addValue(&d, key, value);
  return d;
}

}  // namespace evidential_octomap
