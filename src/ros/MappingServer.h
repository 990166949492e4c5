// The ROS 1 mapping server: subscribers, tf2, services, timers and publishers around one
// EvidentialOcTree. Conversions, parameters, outputs and markers live in their own files; the
// maths lives in the core library.
//
// Threads: clouds (and camera images) are received on their own callback queue and spinner,
// which looks up the transform, reads the cloud's points and evidence and puts the result in a
// bounded queue of the newest clouds; one insertion thread takes clouds from that queue and
// fuses them into the map. A slow insert therefore never blocks reception, reading a cloud never
// delays an insert, and every cloud that cannot be mapped is counted, warned (throttled) and
// reported on ~status and /diagnostics. Services and the publish timers run on the node's own
// callback queue; the map mutex serialises them with the insertion thread. A publish pass holds
// the map lock only to read the map (voxel views, whole-map messages); markers are built and
// messages serialised and sent after it is released.
#pragma once

#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/TransformStamped.h>
#include <message_filters/subscriber.h>
#include <message_filters/time_synchronizer.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <boost/thread/recursive_mutex.hpp>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "evidential_octomap/BoundingBoxQuery.h"
#include "evidential_octomap/ClearBbx.h"
#include "evidential_octomap/LoadMap.h"
#include "evidential_octomap/MappingConfig.h"
#include "evidential_octomap/MappingStatus.h"
#include "evidential_octomap/QueryMap.h"
#include "evidential_octomap/SaveMap.h"
#include "evidential_octomap/class_table.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/local_map.h"
#include "latest_queue.h"
#include "map_outputs.h"
#include "ros_params.h"

namespace evidential_octomap {

class MappingServer {
 public:
  // Reads every parameter from nh_private; throws std::exception for unusable parameters
  // (unreadable class table, num_classes disagreeing with it, unknown rule).
  MappingServer(const ros::NodeHandle& nh, const ros::NodeHandle& nh_private);
  // Stops reception, then the insertion thread (a cloud being inserted is finished first).
  ~MappingServer();

 private:
  // A received cloud with its sensor pose, waiting for the insertion thread.
  struct PendingCloud {
    sensor_msgs::PointCloud2ConstPtr cloud;
    SemanticCloud scan;    // read on the reception thread
    double read_ms = 0.0;  // how long reading took
    geometry_msgs::TransformStamped T_W_S;
    geometry_msgs::TransformStamped T_F_S;  // into the frame of pointcloud_min_z/max_z
  };

  // --- input (reception thread) ---------------------------------------------------------
  void cloudCallback(const sensor_msgs::PointCloud2ConstPtr& cloud);
  void tfFailure(const sensor_msgs::PointCloud2ConstPtr& cloud,
                 tf2_ros::filter_failure_reasons::FilterFailureReason reason);
  void imageCallback(const sensor_msgs::ImageConstPtr& image,
                     const sensor_msgs::CameraInfoConstPtr& info);
  void subscribeInputs();

  // --- insertion thread -----------------------------------------------------------------
  void insertionLoop();
  void insertCloud(PendingCloud& pending);
  // Camera evidence and the height band, outside the map lock; "" or why the cloud is dropped.
  std::string prepareScan(PendingCloud& pending);
  void dropInvalid(const std::string& frame_id, const std::string& error);
  // Replaces the cloud's evidence by the camera's; "" or why the scan cannot be painted.
  std::string paintFromCamera(const sensor_msgs::PointCloud2& cloud, SemanticCloud* scan);

  // --- output ---------------------------------------------------------------------------
  void publishTimer(const ros::TimerEvent&);
  void statusTimer(const ros::TimerEvent&);
  // Publishes the stale outputs that have subscribers (all with `force`). Takes the map mutex
  // to read the map, so callers must not hold it; passes are serialised by publish_mutex_.
  void publishMap(bool force);
  void readMap(const OctomapMsgsInterface::MapVisitor& visit);  // under the map mutex
  void publishStatus();
  void restartPublishTimer();

  // --- services -------------------------------------------------------------------------
  bool saveMap(SaveMap::Request& req, SaveMap::Response& res);
  bool loadMap(LoadMap::Request& req, LoadMap::Response& res);
  bool reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  void resetMap();  // a fresh tree with the run-time settings (takes the map mutex)
  bool clearBox(ClearBbx::Request& req, ClearBbx::Response& res);
  bool clearBbx(BoundingBoxQuery::Request& req, BoundingBoxQuery::Response& res);
  bool query(QueryMap::Request& req, QueryMap::Response& res);
  void reconfigure(MappingConfig& config, uint32_t level);

  // A fresh, empty tree with these settings, at the resolution and with the sensor model of the
  // map in use (at start-up: ~resolution and the ~sensor_model parameters).
  std::unique_ptr<EvidentialOcTree> makeTree(const SemanticConfig& semantic);
  // How clouds are read: from ~input_type & co., parsed once (and on reconfigure).
  CloudReadOptions cloudReadOptions() const;
  // ~map_file at start-up (as octomap_server's map file argument): our .ot, or a .bt whose
  // occupancy the map starts from. Throws when it cannot be loaded.
  void loadStartupMap();
  // Our .ot (same C) or an occupancy .bt, as a map with this node's classes; throws.
  std::unique_ptr<EvidentialOcTree> readMapFile(const std::string& path,
                                                bool* occupancy_only) const;
  // Makes `map` the node's map (map mutex held).
  void adoptMap(std::unique_ptr<EvidentialOcTree> map, bool occupancy_only);
  // Reads `tree` with the calibration's error model where it was fitted for the tree's classes
  // and rule (warns otherwise: the map's error probability is then 1 - max p).
  void attachErrorModel(EvidentialOcTree* tree) const;
  // A service's path: relative paths are taken from the node's working directory.
  static std::string absolutePath(const std::string& path);
  // Map size into status_ (map mutex held). Counting leaves walks the whole map (tens of ms in a
  // large one, growing with it), so after an insert it is recorded only when walks then take at
  // most 2 % of the time (and, with clouds waiting, at most one a second); the insertion thread
  // brings it up to date once clouds stop coming (recordMapSizeWhenIdle).
  void recordMapSize();
  void recordMapSizeAfterInsert();
  void recordMapSizeWhenIdle();
  std::chrono::steady_clock::time_point map_size_recorded_{};
  double map_size_walk_ms_ = 0.0;  // the last walk's duration
  std::atomic<bool> map_size_stale_{false};  // inserts since the last walk
  // Autosave (~autosave_period): the thread, one autosave, and the resume at start-up.
  void autosaveLoop();
  double autosaveOnce();  // the map lock's hold [ms]
  void resumeFromAutosave();
  void resumeTiles(const std::vector<std::string>& tiles);
  std::string snapshotBase() const;  // where the autosave of a local map goes
  static std::string defaultAutosavePath(const std::string& map_file);
  // A new local map over tree_ in a fresh tile subdirectory, after tree_ changes (map mutex
  // held); none when ~local_map/radius is 0. Throws what LocalMap's constructor throws.
  void startLocalMap();
  void restartLocalMap();  // startLocalMap, or none when it throws (logged, on ~status)
  void stopLocalMap();     // none, its tile directory deleted
  static void removeTilesOfDeadNodes(const std::string& base);
  void followLocalMap(const geometry_msgs::Vector3& origin_W);
  // The whole map: tree_, or with a local map the tree merged with its tiles (map mutex held).
  std::unique_ptr<EvidentialOcTree> globalMap() const;
  // Records why a cloud or an autosave failed in ~status (last_error).
  void recordError(const std::string& message);

  ros::NodeHandle nh_, pnh_;
  // The node's own parameters. The map's settings and resolution are read from tree_ alone
  // (config_.resolution is only ~resolution, the size of the first map).
  NodeConfig config_;
  ClassTable classes_;
  std::shared_ptr<const Calibration> calibration_;  // ~calibration_* params; null: none
  CloudReadOptions read_options_;  // under options_mutex_ (read on the reception thread)
  std::mutex options_mutex_;
  std::unique_ptr<EvidentialOcTree> tree_;
  std::unique_ptr<LocalMap> local_map_;  // over tree_, with ~local_map/radius > 0
  size_t local_maps_started_ = 0;
  std::mutex mutex_;  // map, config and outputs: insertion thread, services, timers
  std::mutex publish_mutex_;  // one publish pass at a time; taken before mutex_, never after
  std::atomic<int> inserts_waiting_{0};  // the insertion thread waits for mutex_

  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;

  // Reception: its own callback queue and thread, so a long insert or service never stalls it.
  ros::CallbackQueue intake_queue_;
  std::unique_ptr<ros::AsyncSpinner> intake_spinner_;
  message_filters::Subscriber<sensor_msgs::PointCloud2> cloud_sub_;
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>> tf_filter_;
  message_filters::Subscriber<sensor_msgs::Image> image_sub_;
  message_filters::Subscriber<sensor_msgs::CameraInfo> info_sub_;
  std::unique_ptr<message_filters::TimeSynchronizer<sensor_msgs::Image, sensor_msgs::CameraInfo>>
      image_sync_;
  std::mutex images_mutex_;
  std::deque<std::pair<sensor_msgs::ImageConstPtr, sensor_msgs::CameraInfoConstPtr>> images_;

  // Insertion.
  std::unique_ptr<LatestQueue<PendingCloud>> clouds_;
  std::thread insertion_thread_;

  // Map files (save_map, load_map): their own callback queue and thread.
  ros::CallbackQueue files_queue_;
  std::unique_ptr<ros::AsyncSpinner> files_spinner_;

  std::unique_ptr<MapOutputs> outputs_;
  ros::Publisher status_pub_, diagnostics_pub_;
  ros::ServiceServer save_srv_, load_srv_, reset_srv_, clear_srv_, clear_box_srv_, query_srv_;
  ros::Timer publish_timer_, status_timer_;
  boost::recursive_mutex reconfigure_mutex_;  // before the server that locks it
  std::unique_ptr<dynamic_reconfigure::Server<MappingConfig>> reconfigure_server_;

  // Autosave: its thread sleeps on autosave_cv_ until the period ends or the node stops.
  std::thread autosave_thread_;
  std::mutex autosave_mutex_;
  std::condition_variable autosave_cv_;
  bool stopping_ = false;                // under autosave_mutex_
  uint64_t map_changes_ = 0;             // under mutex_: inserts, edits, loads, resets
  uint64_t autosaved_changes_ = 0;       // map_changes_ at the last autosave (autosave thread)
  bool autosaved_once_ = false;

  std::mutex status_mutex_;  // status_ and last_diagnosed_: every thread updates counters
  MappingStatus status_, last_diagnosed_;
  double insert_ms_total_ = 0.0;
  octomap::point3d last_origin_W_;
};

}  // namespace evidential_octomap
