// The ROS 1 mapping server: subscribers, tf2, services, timers and publishers around one
// EvidentialOcTree. Conversions, parameters and markers live in their own files; the maths
// lives in the core library.
#pragma once

#include <deque>
#include <memory>
#include <mutex>
#include <string>

#include <boost/thread/recursive_mutex.hpp>
#include <dynamic_reconfigure/server.h>
#include <message_filters/subscriber.h>
#include <message_filters/time_synchronizer.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>

#include "evidential_octomap/ClearBbx.h"
#include "evidential_octomap/LoadMap.h"
#include "evidential_octomap/MappingConfig.h"
#include "evidential_octomap/QueryMap.h"
#include "evidential_octomap/SaveMap.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "ros_params.h"

namespace evidential_octomap {

class MappingServer {
 public:
  // Reads every parameter from nh_private; throws std::exception for unusable parameters
  // (unreadable class table, num_classes disagreeing with it, unknown rule).
  MappingServer(const ros::NodeHandle& nh, const ros::NodeHandle& nh_private);

  const EvidentialOcTree& tree() const { return *tree_; }

 private:
  // --- input ----------------------------------------------------------------------------
  void cloudCallback(const sensor_msgs::PointCloud2ConstPtr& cloud);
  void tfFailure(const sensor_msgs::PointCloud2ConstPtr& cloud,
                 tf2_ros::filter_failure_reasons::FilterFailureReason reason);
  void imageCallback(const sensor_msgs::ImageConstPtr& image,
                     const sensor_msgs::CameraInfoConstPtr& info);
  // Replaces the cloud's evidence by the camera's; "" or why the scan cannot be painted.
  std::string paintFromCamera(const sensor_msgs::PointCloud2& cloud, SemanticCloud* scan);

  // --- output ---------------------------------------------------------------------------
  void publishTimer(const ros::TimerEvent&);
  void publishViews(bool force);
  void markChanged();
  void restartPublishTimer();

  // --- services -------------------------------------------------------------------------
  bool saveMap(SaveMap::Request& req, SaveMap::Response& res);
  bool loadMap(LoadMap::Request& req, LoadMap::Response& res);
  bool reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  bool clearBbx(ClearBbx::Request& req, ClearBbx::Response& res);
  bool query(QueryMap::Request& req, QueryMap::Response& res);
  void reconfigure(MappingConfig& config, uint32_t level);

  // A fresh, empty tree from the current parameters.
  std::unique_ptr<EvidentialOcTree> makeTree();

  ros::NodeHandle nh_, pnh_;
  NodeConfig config_;
  SemanticConfig semantic_config_;
  ClassTable classes_;
  std::unique_ptr<EvidentialOcTree> tree_;
  std::mutex mutex_;  // map + config, shared by callbacks and services

  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  message_filters::Subscriber<sensor_msgs::PointCloud2> cloud_sub_;
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>> tf_filter_;

  // Camera path.
  message_filters::Subscriber<sensor_msgs::Image> image_sub_;
  message_filters::Subscriber<sensor_msgs::CameraInfo> info_sub_;
  std::unique_ptr<message_filters::TimeSynchronizer<sensor_msgs::Image, sensor_msgs::CameraInfo>>
      image_sync_;
  std::deque<std::pair<sensor_msgs::ImageConstPtr, sensor_msgs::CameraInfoConstPtr>> images_;

  ros::Publisher semantic_markers_pub_, uncertainty_markers_pub_, cloud_pub_, map_pub_,
      occupancy_pub_;
  ros::ServiceServer save_srv_, load_srv_, reset_srv_, clear_srv_, query_srv_;
  ros::Timer publish_timer_;
  std::unique_ptr<dynamic_reconfigure::Server<MappingConfig>> reconfigure_server_;
  boost::recursive_mutex reconfigure_mutex_;

  // Which outputs are older than the map; each is sent when it has a subscriber.
  bool dirty_views_ = false, dirty_map_ = false, dirty_occupancy_ = false;
  octomap::point3d last_origin_W_;
  size_t scans_ = 0;
  double insert_ms_total_ = 0.0, publish_ms_total_ = 0.0;
  size_t publishes_ = 0;
};

}  // namespace evidential_octomap
