// Built only when octomap_msgs is found (src/ros/CMakeLists.txt); octomap_msgs_absent.cpp
// otherwise.
#include "octomap_msgs_interface.h"

#include <octomap_msgs/GetOctomap.h>
#include <octomap_msgs/Octomap.h>

#include <chrono>
#include <cstdio>
#include <memory>

#include "octomap_msgs_conversions.h"
#include "stale_output.h"

namespace evidential_octomap {
namespace {

class OctomapMsgsOutputs : public OctomapMsgsInterface {
 public:
  OctomapMsgsOutputs(ros::NodeHandle& nh, const NodeConfig& config, WithMap with_map)
      : config_(config), with_map_(std::move(with_map)) {
    binary_.publisher = nh.advertise<octomap_msgs::Octomap>("octomap_binary", 1, config_.latch);
    full_.publisher = nh.advertise<octomap_msgs::Octomap>("octomap_full", 1, config_.latch);
    evidential_.publisher =
        nh.advertise<octomap_msgs::Octomap>("evidential_octomap_full", 1, config_.latch);
    binary_srv_ = nh.advertiseService("octomap_binary", &OctomapMsgsOutputs::binaryService, this);
    full_srv_ = nh.advertiseService("octomap_full", &OctomapMsgsOutputs::fullService, this);
  }

  void markStale() override { binary_.stale = full_.stale = evidential_.stale = true; }

  std::string publish(const EvidentialOcTree& tree, const ClassTable& classes, bool force,
                      Outbox* outbox) override {
    std::string sent;
    const ros::Time now = ros::Time::now();
    // Builds (timed, under the map lock) one message; it is sent from the outbox.
    auto send = [&](StaleOutput* output, const char* name, auto build) {
      const auto t0 = std::chrono::steady_clock::now();
      auto msg = std::make_shared<octomap_msgs::Octomap>(build());
      msg->header.stamp = now;
      output->claim();
      outbox->push_back([output, msg] { output->publisher.publish(*msg); });
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      char part[80];
      std::snprintf(part, sizeof(part), " %s (%.1f MB, %.0f ms)", name, msg->data.size() / 1e6,
                    ms);
      sent += part;
    };
    const std::string& frame = config_.frame_id;
    if (binary_.wanted(force))
      send(&binary_, "octomap_binary", [&] { return toOctomapBinary(tree, frame); });
    if (full_.wanted(force)) send(&full_, "octomap_full", [&] { return full(tree, classes); });
    if (evidential_.wanted(force))
      send(&evidential_, "evidential_octomap_full",
           [&] { return toOctomapEvidential(tree, frame); });
    return sent;
  }

 private:
  octomap_msgs::Octomap full(const EvidentialOcTree& tree, const ClassTable& classes) const {
    return toOctomapFull(
        tree, classes, config_.full_map_colors, config_.frame_id);
  }

  bool binaryService(octomap_msgs::GetOctomap::Request&, octomap_msgs::GetOctomap::Response& res) {
    with_map_([&](const EvidentialOcTree& tree, const ClassTable&) {
      res.map = toOctomapBinary(tree, config_.frame_id);
    });
    res.map.header.stamp = ros::Time::now();
    return true;
  }

  bool fullService(octomap_msgs::GetOctomap::Request&, octomap_msgs::GetOctomap::Response& res) {
    with_map_([&](const EvidentialOcTree& tree, const ClassTable& classes) {
      res.map = full(tree, classes);
    });
    res.map.header.stamp = ros::Time::now();
    return true;
  }

  NodeConfig config_;
  WithMap with_map_;
  StaleOutput binary_, full_, evidential_;
  ros::ServiceServer binary_srv_, full_srv_;
};

}  // namespace

bool OctomapMsgsInterface::available() { return true; }

std::unique_ptr<OctomapMsgsInterface> OctomapMsgsInterface::create(ros::NodeHandle& nh,
                                                                   const NodeConfig& config,
                                                                   WithMap with_map) {
  return std::make_unique<OctomapMsgsOutputs>(nh, config, std::move(with_map));
}

}  // namespace evidential_octomap
