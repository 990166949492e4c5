#include "MappingServer.h"

#include <cctype>
#include <chrono>
#include <map>
#include <sstream>

#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/TransformStamped.h>

#include "camera_projection.h"
#include "map_editing.h"
#include "conversions.h"
#include "evidential_octomap/io.h"
#include "visualization.h"

namespace evidential_octomap {
namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

octomap::pose6d toPose(const geometry_msgs::Transform& t) {
  return octomap::pose6d(
      octomap::point3d(t.translation.x, t.translation.y, t.translation.z),
      octomath::Quaternion(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z));
}

const char* tfReason(tf2_ros::filter_failure_reasons::FilterFailureReason reason) {
  switch (reason) {
    case tf2_ros::filter_failure_reasons::OutTheBack: return "older than the TF buffer";
    case tf2_ros::filter_failure_reasons::EmptyFrameID: return "empty header.frame_id";
    default: return "transform unavailable (queue overflow or timeout)";
  }
}

// Warns about a dropped cloud: a new kind of problem at once, repeats of one kind at most every
// 2 s (the kind is the message without its digits, so "point 17" and "point 3" are one kind).
void warnDropped(const std::string& message) {
  static std::mutex mutex;  // tf2 failure callbacks run outside the server's lock
  static std::map<std::string, ros::WallTime> last;
  std::lock_guard<std::mutex> lock(mutex);
  std::string kind;
  for (char ch : message)
    if (!std::isdigit(static_cast<unsigned char>(ch))) kind += ch;
  const ros::WallTime now = ros::WallTime::now();
  auto it = last.find(kind);
  if (it != last.end() && (now - it->second).toSec() < 2.0) return;
  last[kind] = now;
  ROS_WARN("%s", message.c_str());
}

}  // namespace

MappingServer::MappingServer(const ros::NodeHandle& nh, const ros::NodeHandle& nh_private)
    : nh_(nh), pnh_(nh_private), tf_listener_(tf_buffer_) {
  config_ = readNodeConfig(pnh_);
  readSemanticConfig(pnh_, &semantic_config_);
  classes_ = ClassTable::load(config_.classes);
  if (config_.num_classes != 0 && config_.num_classes != classes_.numClasses())
    throw std::invalid_argument("~num_classes = " + std::to_string(config_.num_classes) +
                                " disagrees with the class table " + config_.classes + " (" +
                                std::to_string(classes_.numClasses()) + " classes)");
  config_.num_classes = classes_.numClasses();
  tree_ = makeTree();
  {
    std::ostringstream s;
    semantic_config_.print(s);
    ROS_INFO_STREAM("evidential_mapping_node: frame " << config_.frame_id << ", resolution "
                    << config_.resolution << " m, C = " << config_.num_classes << " ("
                    << classes_.dataset << ", " << config_.classes << "), input "
                    << config_.input_type << "\n" << s.str());
  }

  // Outputs, latched as octomap_server latches its maps.
  semantic_markers_pub_ =
      nh_.advertise<visualization_msgs::MarkerArray>("occupied_cells_vis_array", 1, true);
  uncertainty_markers_pub_ =
      nh_.advertise<visualization_msgs::MarkerArray>("uncertainty_cells_vis_array", 1, true);
  cloud_pub_ = nh_.advertise<sensor_msgs::PointCloud2>("semantic_cloud", 1, true);
  map_pub_ = nh_.advertise<EvidentialMap>("evidential_map", 1, true);
  occupancy_pub_ = nh_.advertise<OccupancyMap>("occupancy_map", 1, true);

  save_srv_ = pnh_.advertiseService("save_map", &MappingServer::saveMap, this);
  load_srv_ = pnh_.advertiseService("load_map", &MappingServer::loadMap, this);
  reset_srv_ = pnh_.advertiseService("reset", &MappingServer::reset, this);
  clear_srv_ = pnh_.advertiseService("clear_bbx", &MappingServer::clearBbx, this);
  query_srv_ = pnh_.advertiseService("query", &MappingServer::query, this);

  // Run-time parameters: push the values in use, then listen.
  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<MappingConfig>>(reconfigure_mutex_, pnh_);
  MappingConfig rc;
  toReconfigure(semantic_config_, *tree_, config_, &rc);
  reconfigure_server_->updateConfig(rc);
  reconfigure_server_->setCallback(
      boost::bind(&MappingServer::reconfigure, this, boost::placeholders::_1, boost::placeholders::_2));

  // Input: cloud_in through a tf2 MessageFilter into frame_id.
  cloud_sub_.subscribe(nh_, "cloud_in", config_.queue_size);
  tf_filter_ = std::make_unique<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>>(
      cloud_sub_, tf_buffer_, config_.frame_id, config_.queue_size, nh_);
  tf_filter_->registerCallback(boost::bind(&MappingServer::cloudCallback, this, boost::placeholders::_1));
  tf_filter_->registerFailureCallback(boost::bind(&MappingServer::tfFailure, this,
                                                  boost::placeholders::_1, boost::placeholders::_2));

  if (config_.use_camera) {
    image_sub_.subscribe(nh_, "image_in", 2);
    info_sub_.subscribe(nh_, "camera_info", 2);
    image_sync_ = std::make_unique<
        message_filters::TimeSynchronizer<sensor_msgs::Image, sensor_msgs::CameraInfo>>(
        image_sub_, info_sub_, 5);
    image_sync_->registerCallback(boost::bind(&MappingServer::imageCallback, this,
                                              boost::placeholders::_1, boost::placeholders::_2));
    ROS_INFO("camera path on: image_in (%s) + camera_info paint cloud_in; outside points %s",
             config_.camera_input.c_str(),
             config_.keep_outside_image ? "kept occupancy-only" : "dropped");
  }
  restartPublishTimer();
}

std::unique_ptr<EvidentialOcTree> MappingServer::makeTree() {
  auto tree = std::make_unique<EvidentialOcTree>(config_.resolution, config_.num_classes,
                                                 semantic_config_);
  tree->setClassNames(classes_.names);
  if (tree_) {  // keep the sensor model in use (it may have been changed at run time)
    tree->setProbHit(tree_->getProbHit());
    tree->setProbMiss(tree_->getProbMiss());
    tree->setClampingThresMin(tree_->getClampingThresMin());
    tree->setClampingThresMax(tree_->getClampingThresMax());
  } else {
    readOccupancyParams(pnh_, tree.get());
  }
  return tree;
}

// --- input ------------------------------------------------------------------------------

void MappingServer::tfFailure(const sensor_msgs::PointCloud2ConstPtr& cloud,
                              tf2_ros::filter_failure_reasons::FilterFailureReason reason) {
  warnDropped("cloud dropped: no transform " + cloud->header.frame_id + " -> " +
              config_.frame_id + " (" + tfReason(reason) + "); map unchanged");
}

void MappingServer::cloudCallback(const sensor_msgs::PointCloud2ConstPtr& cloud) {
  std::lock_guard<std::mutex> lock(mutex_);
  geometry_msgs::TransformStamped T_W_S;
  try {
    T_W_S = tf_buffer_.lookupTransform(config_.frame_id, cloud->header.frame_id,
                                       cloud->header.stamp);
  } catch (const tf2::TransformException& e) {
    warnDropped(std::string("cloud dropped: ") + e.what() + "; map unchanged");
    return;
  }
  CloudReadOptions options;
  options.num_classes = tree_->numClasses();
  options.input = config_.use_camera ? EvidenceInput::kNone : evidenceInputFromName(config_.input_type);
  options.label_magnitude = static_cast<float>(config_.label_evidence);
  options.raw_label_table = config_.label_is_raw ? &classes_ : nullptr;
  SemanticCloud scan;
  std::string error = fromPointCloud2(*cloud, options, &scan);
  if (error.empty() && config_.use_camera) error = paintFromCamera(*cloud, &scan);
  if (!error.empty()) {
    warnDropped("cloud dropped (frame " + cloud->header.frame_id + "): " + error +
                "; map unchanged");
    return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  InsertStats stats;
  try {
    stats = tree_->insertSemanticScan(scan.points_S, scan.evidence, toPose(T_W_S.transform));
  } catch (const std::invalid_argument& e) {
    warnDropped(std::string("cloud dropped: ") + e.what() + "; map unchanged");
    return;
  }
  const double ms = msSince(t0);
  insert_ms_total_ += ms;
  ++scans_;
  last_origin_W_ = octomap::point3d(T_W_S.transform.translation.x, T_W_S.transform.translation.y,
                                    T_W_S.transform.translation.z);
  ROS_INFO("scan %zu: %zu points (%s), %zu semantic, %zu voxels updated, insert %.0f ms "
           "(occupancy %.0f, kernel %.0f, update %.0f); map %zu leaves, %zu semantic",
           scans_, stats.points_in, scan.source.c_str(), stats.semantic_points,
           stats.voxels_updated, ms, stats.ms_occupancy, stats.ms_kernel, stats.ms_update,
           tree_->getNumLeafNodes(), tree_->numSemanticNodes());
  markChanged();
  if (config_.publish_rate <= 0.0) publishViews(false);
}

void MappingServer::imageCallback(const sensor_msgs::ImageConstPtr& image,
                                  const sensor_msgs::CameraInfoConstPtr& info) {
  std::lock_guard<std::mutex> lock(mutex_);
  images_.emplace_back(image, info);
  while (images_.size() > 10) images_.pop_front();
}

std::string MappingServer::paintFromCamera(const sensor_msgs::PointCloud2& cloud,
                                           SemanticCloud* scan) {
  // The image nearest in time to the cloud, within camera/max_age.
  const std::pair<sensor_msgs::ImageConstPtr, sensor_msgs::CameraInfoConstPtr>* best = nullptr;
  double best_dt = config_.camera_max_age;
  for (const auto& pair : images_) {
    const double dt = std::abs((pair.first->header.stamp - cloud.header.stamp).toSec());
    if (dt <= best_dt) {
      best_dt = dt;
      best = &pair;
    }
  }
  if (!best) return "no evidence image within camera/max_age of the cloud";
  const sensor_msgs::Image& image = *best->first;
  geometry_msgs::TransformStamped T_C_S;
  try {
    T_C_S = tf_buffer_.lookupTransform(image.header.frame_id, cloud.header.frame_id,
                                       cloud.header.stamp);
  } catch (const tf2::TransformException& e) {
    return std::string("no camera extrinsics: ") + e.what();
  }
  cv_bridge::CvImageConstPtr cv_image;
  try {
    cv_image = cv_bridge::toCvShare(best->first);
  } catch (const cv_bridge::Exception& e) {
    return std::string("evidence image: ") + e.what();
  }
  const auto& q = T_C_S.transform.rotation;
  const auto& t = T_C_S.transform.translation;
  const octomath::Quaternion rot(q.w, q.x, q.y, q.z);
  cv::Matx33d R;
  for (int c = 0; c < 3; ++c) {
    octomap::point3d axis(c == 0, c == 1, c == 2);
    const octomap::point3d col = rot.rotate(axis);
    R(0, c) = col.x();
    R(1, c) = col.y();
    R(2, c) = col.z();
  }
  const PinholeCamera camera = cameraFromInfo(*best->second);
  const std::vector<long> pixels = projectToPixels(scan->points_S, R, cv::Vec3d(t.x, t.y, t.z), camera);
  octomap::Pointcloud painted;
  std::vector<float> evidence;
  std::string error = evidenceFromImage(scan->points_S, pixels, cv_image->image,
                                        tree_->numClasses(), float(config_.label_evidence),
                                        config_.keep_outside_image, &painted, &evidence);
  if (!error.empty()) return error;
  if (painted.size() == 0) return "no point of the cloud lands in the evidence image";
  scan->points_S = painted;
  scan->evidence.swap(evidence);
  scan->source = "camera " + image.header.frame_id;
  return "";
}

// --- output -----------------------------------------------------------------------------

void MappingServer::markChanged() { dirty_views_ = dirty_map_ = dirty_occupancy_ = true; }

// At publish_rate; with publish_rate <= 0 (publish after every scan) a 1 Hz timer still serves
// outputs that had no subscriber when their scan arrived.
void MappingServer::restartPublishTimer() {
  publish_timer_.stop();
  const double period = config_.publish_rate > 0.0 ? 1.0 / config_.publish_rate : 1.0;
  publish_timer_ = nh_.createTimer(ros::Duration(period), &MappingServer::publishTimer, this);
}

void MappingServer::publishTimer(const ros::TimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  publishViews(false);
}

// Publishes every output that is older than the map and has a subscriber (force: regardless
// of subscribers, used after reset so latched views are emptied).
void MappingServer::publishViews(bool force) {
  const bool want_markers = semantic_markers_pub_.getNumSubscribers() > 0 ||
                            uncertainty_markers_pub_.getNumSubscribers() > 0;
  const bool want_cloud = cloud_pub_.getNumSubscribers() > 0;
  const bool views = dirty_views_ && (force || want_markers || want_cloud);
  const bool map = dirty_map_ && (force || map_pub_.getNumSubscribers() > 0);
  const bool occupancy = dirty_occupancy_ && (force || occupancy_pub_.getNumSubscribers() > 0);
  if (!views && !map && !occupancy) return;

  const auto t0 = std::chrono::steady_clock::now();
  const ros::Time stamp = ros::Time::now();
  size_t n_voxels = 0;
  double ms_views = 0.0, ms_map = 0.0;
  if (views) {
    Box box;
    if (config_.publish_radius > 0.0) {
      const octomap::point3d r(config_.publish_radius, config_.publish_radius, config_.publish_radius);
      box.min = last_origin_W_ - r;
      box.max = last_origin_W_ + r;
    }
    const std::vector<VoxelView> voxels = occupiedVoxels(*tree_, box);
    n_voxels = voxels.size();
    const unsigned depth = tree_->getTreeDepth();
    if (force || semantic_markers_pub_.getNumSubscribers() > 0) {
      auto markers = semanticMarkers(voxels, classes_, config_.frame_id, depth);
      for (auto& m : markers.markers) m.header.stamp = stamp;
      semantic_markers_pub_.publish(markers);
    }
    if (force || uncertainty_markers_pub_.getNumSubscribers() > 0) {
      auto markers = uncertaintyMarkers(voxels, config_.uncertainty_range, config_.frame_id, depth);
      for (auto& m : markers.markers) m.header.stamp = stamp;
      uncertainty_markers_pub_.publish(markers);
    }
    if (force || want_cloud) {
      sensor_msgs::PointCloud2 cloud = toPointCloud2(voxels, classes_, config_.frame_id);
      cloud.header.stamp = stamp;
      cloud_pub_.publish(cloud);
    }
    dirty_views_ = false;
    ms_views = msSince(t0);
  }
  if (map) {
    EvidentialMap msg = toEvidentialMap(*tree_, config_.frame_id);
    msg.header.stamp = stamp;
    map_pub_.publish(msg);
    dirty_map_ = false;
    ms_map = msSince(t0) - ms_views;
  }
  if (occupancy) {
    OccupancyMap msg = toOccupancyMap(*tree_, config_.frame_id);
    msg.header.stamp = stamp;
    occupancy_pub_.publish(msg);
    dirty_occupancy_ = false;
  }
  const double ms = msSince(t0);
  publish_ms_total_ += ms;
  ++publishes_;
  ROS_INFO("published%s%s%s in %.1f ms (views of %zu voxels %.1f, evidential_map %.1f, "
           "occupancy_map %.1f; mean insert %.0f ms over %zu scans)",
           views ? " views" : "", map ? " map" : "", occupancy ? " occupancy" : "", ms, n_voxels,
           ms_views, ms_map, ms - ms_views - ms_map, scans_ ? insert_ms_total_ / scans_ : 0.0,
           scans_);
}

// --- services ---------------------------------------------------------------------------

bool MappingServer::saveMap(SaveMap::Request& req, SaveMap::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    evidential_octomap::saveMap(*tree_, req.path);
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
    ROS_ERROR("save_map: %s", e.what());
    return true;
  }
  res.success = true;
  res.message = "saved " + std::to_string(tree_->getNumLeafNodes()) + " leaves (" +
                std::to_string(tree_->numSemanticNodes()) + " semantic) to " + req.path;
  ROS_INFO("save_map: %s", res.message.c_str());
  return true;
}

bool MappingServer::loadMap(LoadMap::Request& req, LoadMap::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    std::unique_ptr<EvidentialOcTree> loaded = evidential_octomap::loadMap(req.path);
    if (loaded->numClasses() != tree_->numClasses())
      throw std::runtime_error(req.path + " has C = " + std::to_string(loaded->numClasses()) +
                               ", this node maps C = " + std::to_string(tree_->numClasses()));
    tree_ = std::move(loaded);
    semantic_config_ = tree_->config();
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
    ROS_ERROR("load_map: %s (map unchanged)", e.what());
    return true;
  }
  res.success = true;
  res.message = "loaded " + std::to_string(tree_->getNumLeafNodes()) + " leaves from " + req.path;
  ROS_INFO("load_map: %s", res.message.c_str());
  markChanged();
  publishViews(true);
  return true;
}

bool MappingServer::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  std::lock_guard<std::mutex> lock(mutex_);
  // Run-time (dynamic_reconfigure) values stay; ~rule and ~sbki_prior, which change what a
  // stored voxel means and so cannot change on a live map, are re-read here.
  std::string rule = semantic_config_.rule;
  pnh_.param("rule", rule, rule);
  pnh_.param("sbki_prior", semantic_config_.sbki_prior, semantic_config_.sbki_prior);
  try {
    fusionRuleFromName(rule);
    semantic_config_.rule = rule;
  } catch (const std::exception& e) {
    ROS_ERROR("reset: %s; keeping rule %s", e.what(), semantic_config_.rule.c_str());
  }
  tree_ = makeTree();
  scans_ = 0;
  insert_ms_total_ = 0.0;
  ROS_INFO("reset: map cleared (rule %s)", semantic_config_.rule.c_str());
  markChanged();
  publishViews(true);
  return true;
}

bool MappingServer::clearBbx(ClearBbx::Request& req, ClearBbx::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const octomap::point3d min(req.min.x, req.min.y, req.min.z), max(req.max.x, req.max.y, req.max.z);
  res.voxels_cleared = clearBox(tree_.get(), min, max);
  ROS_INFO("clear_bbx: %u leaves cleared in [%.2f %.2f %.2f] .. [%.2f %.2f %.2f]",
           res.voxels_cleared, min.x(), min.y(), min.z(), max.x(), max.y(), max.z());
  markChanged();
  publishViews(true);
  return true;
}

bool MappingServer::query(QueryMap::Request& req, QueryMap::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const int C = tree_->numClasses();
  res.num_classes = static_cast<uint16_t>(C);
  for (const auto& p : req.points) {
    const octomap::point3d point(p.x, p.y, p.z);
    const EvidentialOcTreeNode* node = tree_->search(point);
    const VoxelOpinion o = tree_->opinion(node);
    res.labels.push_back(o.label);
    res.uncertainties.push_back(o.uncertainty);
    res.occupancy.push_back(node ? static_cast<float>(node->getOccupancy()) : -1.f);
    for (int c = 0; c < C; ++c)
      res.beliefs.push_back(c < int(o.belief.size()) ? o.belief[c] : 0.f);
  }
  return true;
}

void MappingServer::reconfigure(MappingConfig& rc, uint32_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  SemanticConfig semantic = semantic_config_;
  NodeConfig node = config_;
  fromReconfigure(rc, &semantic, &node, tree_.get());
  try {
    tree_->setConfig(semantic);
    semantic_config_ = semantic;
  } catch (const std::exception& e) {
    ROS_ERROR("reconfigure: %s", e.what());
  }
  config_.label_evidence = node.label_evidence;
  if (node.publish_rate != config_.publish_rate) {
    config_.publish_rate = node.publish_rate;
    restartPublishTimer();
  }
}

}  // namespace evidential_octomap
