// evidential_octomap/MappingNodelet: the same MappingServer in a nodelet manager, so a driver
// nodelet in the same manager hands its clouds over without serialisation.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "MappingServer.h"

namespace evidential_octomap {

class MappingNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      server_ = std::make_unique<MappingServer>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL("evidential_octomap/MappingNodelet: %s", e.what());
      throw;
    }
  }
  std::unique_ptr<MappingServer> server_;
};

}  // namespace evidential_octomap

PLUGINLIB_EXPORT_CLASS(evidential_octomap::MappingNodelet, nodelet::Nodelet)
