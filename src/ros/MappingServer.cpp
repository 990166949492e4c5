#include "MappingServer.h"

#include <cv_bridge/cv_bridge.h>
#include <diagnostic_msgs/DiagnosticArray.h>

#include <cctype>
#include <algorithm>
#include <cstdlib>
#include <iomanip>
#include <chrono>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include <signal.h>
#include <unistd.h>

#include "camera_projection.h"
#include "conversions.h"
#include "map_services.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/local_map_snapshot.h"
#include "node_status.h"
#include "startup_report.h"

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
    case tf2_ros::filter_failure_reasons::OutTheBack:
      return "older than the TF buffer";
    case tf2_ros::filter_failure_reasons::EmptyFrameID:
      return "empty header.frame_id";
    default:
      return "transform unavailable (queue overflow or timeout)";
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
  SemanticConfig semantic;
  readSemanticConfig(pnh_, config_.resolution, &semantic);
  classes_ = ClassTable::load(config_.classes);
  if (config_.num_classes != 0 && config_.num_classes != classes_.numClasses())
    throw std::invalid_argument("~num_classes = " + std::to_string(config_.num_classes) +
                                " disagrees with the class table " + config_.classes + " (" +
                                std::to_string(classes_.numClasses()) + " classes)");
  config_.num_classes = classes_.numClasses();
  calibration_ = readCalibrationParams(pnh_, semantic.evidence_cap);
  if (calibration_) {
    const std::string problem = calibration_->problemWith(classes_.names, semantic.rule);
    if (!problem.empty()) throw std::invalid_argument("~calibration: " + problem);
  }
  read_options_ = cloudReadOptions();
  tree_ = makeTree(semantic);
  if (!config_.map_file.empty()) loadStartupMap();
  if (config_.autosave_path.empty()) config_.autosave_path = defaultAutosavePath(config_.map_file);
  config_.autosave_path = absolutePath(config_.autosave_path);
  if (config_.resume_from_autosave) resumeFromAutosave();  // (starts the local map it adopts)
  if (!local_map_) startLocalMap();
  {
    std::ostringstream s;
    tree_->config().print(s);
    ROS_INFO_STREAM("evidential_mapping_node: frame "
                    << config_.frame_id << ", resolution " << tree_->getResolution()
                    << " m, C = " << config_.num_classes << " (" << classes_.dataset << ", "
                    << config_.classes << "), input " << config_.input_type << ", insertion queue "
                    << config_.insert_queue_size << "\n"
                    << s.str());
  }
  reportSettingsProfile(pnh_, tree_->config());

  outputs_ = std::make_unique<MapOutputs>(nh_, pnh_, config_, classes_,
                                          [this](const OctomapMsgsInterface::MapVisitor& visit) {
                                            readMap(visit);
                                          });
  status_pub_ = pnh_.advertise<MappingStatus>("status", 1, true);
  diagnostics_pub_ = nh_.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 1);
  status_.queue_capacity = static_cast<uint32_t>(config_.insert_queue_size);

  // Files on their own queue and thread: a long load or save never holds up queries, clear_bbx,
  // reset or the timers (and loading parses without the map lock).
  ros::NodeHandle files_nh(pnh_);
  files_nh.setCallbackQueue(&files_queue_);
  save_srv_ = files_nh.advertiseService("save_map", &MappingServer::saveMap, this);
  load_srv_ = files_nh.advertiseService("load_map", &MappingServer::loadMap, this);
  files_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &files_queue_);
  files_spinner_->start();
  reset_srv_ = pnh_.advertiseService("reset", &MappingServer::reset, this);
  clear_srv_ = pnh_.advertiseService("clear_bbx", &MappingServer::clearBbx, this);
  clear_box_srv_ = pnh_.advertiseService("clear_box", &MappingServer::clearBox, this);
  query_srv_ = pnh_.advertiseService("query", &MappingServer::query, this);

  // Run-time parameters: push the values in use, then listen.
  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<MappingConfig>>(reconfigure_mutex_, pnh_);
  MappingConfig lo, hi;
  reconfigureLimits(&lo, &hi);
  reconfigure_server_->setConfigMin(lo);
  reconfigure_server_->setConfigMax(hi);
  MappingConfig rc;
  toReconfigure(tree_->config(), *tree_, config_, &rc);
  reconfigure_server_->updateConfig(rc);
  reconfigure_server_->setCallback(boost::bind(&MappingServer::reconfigure, this,
                                               boost::placeholders::_1, boost::placeholders::_2));

  clouds_ = std::make_unique<LatestQueue<PendingCloud>>(size_t(config_.insert_queue_size));
  insertion_thread_ = std::thread(&MappingServer::insertionLoop, this);
  if (config_.autosave_period > 0.0) {
    std::error_code ec;
    std::filesystem::create_directories(std::filesystem::path(config_.autosave_path).parent_path(),
                                        ec);
    ROS_INFO("autosave: every %g s to %s (atomic; resume at start-up %s)", config_.autosave_period,
             config_.autosave_path.c_str(), config_.resume_from_autosave ? "on" : "off");
    autosave_thread_ = std::thread(&MappingServer::autosaveLoop, this);
  }
  subscribeInputs();
  restartPublishTimer();
  status_timer_ = nh_.createTimer(ros::Duration(1.0), &MappingServer::statusTimer, this);
  publishStatus();
}

MappingServer::~MappingServer() {
  // Every source of callbacks stops before the members it uses go away: a tf2 MessageFilter or
  // Synchronizer outliving its subscriber, or a callback left queued for it, aborts the process
  // (boost::lock_error on a destroyed mutex; ros/geometry2#379, ros/ros_comm#720), which for a
  // nodelet takes the whole manager down.
  if (intake_spinner_) intake_spinner_->stop();
  if (files_spinner_) files_spinner_->stop();
  cloud_sub_.unsubscribe();
  image_sub_.unsubscribe();
  info_sub_.unsubscribe();
  intake_queue_.disable();
  intake_queue_.clear();
  publish_timer_.stop();
  status_timer_.stop();
  reconfigure_server_.reset();
  clouds_->close();
  if (insertion_thread_.joinable()) insertion_thread_.join();
  if (autosave_thread_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(autosave_mutex_);
      stopping_ = true;
    }
    autosave_cv_.notify_all();
    autosave_thread_.join();
    autosaveOnce();  // a clean shutdown loses nothing
  }
  stopLocalMap();
  image_sync_.reset();
  tf_filter_.reset();
}

void MappingServer::subscribeInputs() {
  ros::NodeHandle intake_nh(nh_);
  intake_nh.setCallbackQueue(&intake_queue_);
  // The subscriber's own queue only has to bridge the moments the reception thread is busy with
  // a transform lookup; clouds that wait for TF sit in the MessageFilter (queue_size).
  cloud_sub_.subscribe(intake_nh, "cloud_in", 20);
  tf_filter_ = std::make_unique<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>>(
      cloud_sub_, tf_buffer_, config_.frame_id, config_.queue_size, intake_nh);
  if (!config_.base_frame_id.empty() && config_.base_frame_id != config_.frame_id)
    tf_filter_->setTargetFrames({config_.frame_id, config_.base_frame_id});
  tf_filter_->registerCallback(
      boost::bind(&MappingServer::cloudCallback, this, boost::placeholders::_1));
  tf_filter_->registerFailureCallback(boost::bind(
      &MappingServer::tfFailure, this, boost::placeholders::_1, boost::placeholders::_2));
  if (config_.use_camera) {
    image_sub_.subscribe(intake_nh, "image_in", 2);
    info_sub_.subscribe(intake_nh, "camera_info", 2);
    image_sync_ = std::make_unique<
        message_filters::TimeSynchronizer<sensor_msgs::Image, sensor_msgs::CameraInfo>>(
        image_sub_, info_sub_, 5);
    image_sync_->registerCallback(boost::bind(&MappingServer::imageCallback, this,
                                              boost::placeholders::_1, boost::placeholders::_2));
    ROS_INFO("camera path on: image_in (%s) + camera_info paint cloud_in; outside points %s",
             config_.camera_input.c_str(),
             config_.keep_outside_image ? "kept occupancy-only" : "dropped");
  }
  intake_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &intake_queue_);
  intake_spinner_->start();
}

std::unique_ptr<EvidentialOcTree> MappingServer::makeTree(const SemanticConfig& semantic) {
  const double resolution = tree_ ? tree_->getResolution() : config_.resolution;
  auto tree = std::make_unique<EvidentialOcTree>(resolution, config_.num_classes, semantic);
  tree->setClasses(classes_);
  if (tree_) {  // keep the sensor model in use (it may have been changed at run time)
    tree->setSensorModel(tree_->sensorModel());
  } else {
    readOccupancyParams(pnh_, tree.get());
  }
  attachErrorModel(tree.get());
  return tree;
}

void MappingServer::attachErrorModel(EvidentialOcTree* tree) const {
  if (!calibration_ || !calibration_->error_model) return;
  const std::string problem = calibration_->problemWith(tree->classNames(), tree->rule().name());
  if (problem.empty()) {
    tree->setErrorModel(calibration_->error_model);
  } else {
    ROS_WARN("%s; this map's error probability is 1 - max p", problem.c_str());
  }
}

// --- input (reception thread) -------------------------------------------------------------

void MappingServer::tfFailure(const sensor_msgs::PointCloud2ConstPtr& cloud,
                              tf2_ros::filter_failure_reasons::FilterFailureReason reason) {
  {
    std::lock_guard<std::mutex> lock(status_mutex_);
    ++status_.clouds_dropped_tf;
  }
  warnDropped("cloud dropped: no transform " + cloud->header.frame_id + " -> " + config_.frame_id +
              " (" + tfReason(reason) + "); map unchanged");
}

void MappingServer::cloudCallback(const sensor_msgs::PointCloud2ConstPtr& cloud) {
  PendingCloud pending;
  pending.cloud = cloud;
  try {
    pending.T_W_S =
        tf_buffer_.lookupTransform(config_.frame_id, cloud->header.frame_id, cloud->header.stamp);
    pending.T_F_S = pending.T_W_S;  // pointcloud_min_z/max_z apply in base_frame_id, else map
    if (!config_.base_frame_id.empty() && !config_.pointcloud_band.unbounded())
      pending.T_F_S = tf_buffer_.lookupTransform(config_.base_frame_id, cloud->header.frame_id,
                                                 cloud->header.stamp);
  } catch (const tf2::TransformException& e) {
    {
      std::lock_guard<std::mutex> lock(status_mutex_);
      ++status_.clouds_dropped_tf;
    }
    warnDropped(std::string("cloud dropped: ") + e.what() + "; map unchanged");
    return;
  }
  // Read here, not on the insertion thread: the next insert does not wait for it.
  const auto t_read = std::chrono::steady_clock::now();
  CloudReadOptions options;
  {
    std::lock_guard<std::mutex> lock(options_mutex_);
    options = read_options_;
  }
  const std::string error = fromPointCloud2(*cloud, options, &pending.scan);
  pending.read_ms = msSince(t_read);
  if (!error.empty()) {
    dropInvalid(cloud->header.frame_id, error);
    return;
  }
  const std::optional<PendingCloud> dropped = clouds_->push(std::move(pending));
  uint64_t dropped_total = 0;
  double insert_ms = 0.0;
  {
    std::lock_guard<std::mutex> lock(status_mutex_);
    ++status_.clouds_received;
    if (!dropped) return;
    dropped_total = ++status_.clouds_dropped_queue;
    insert_ms = status_.last_insert_ms;
  }
  char text[320];
  std::snprintf(text, sizeof(text),
                "cloud dropped (stamp %.3f): insertion is behind the input (an insert takes "
                "%.0f ms, ~insert_queue_size is %zu); %llu dropped so far. Slow the input "
                "(rosbag play -r), or raise ~insert_queue_size to absorb bursts",
                dropped->cloud->header.stamp.toSec(), insert_ms, clouds_->capacity(),
                static_cast<unsigned long long>(dropped_total));
  warnDropped(text);
}

void MappingServer::imageCallback(const sensor_msgs::ImageConstPtr& image,
                                  const sensor_msgs::CameraInfoConstPtr& info) {
  std::lock_guard<std::mutex> lock(images_mutex_);
  images_.emplace_back(image, info);
  while (images_.size() > 10) images_.pop_front();
}

// --- insertion thread ---------------------------------------------------------------------

void MappingServer::insertionLoop() {
  for (;;) {
    recordMapSizeWhenIdle();
    std::optional<PendingCloud> pending = clouds_->pop();
    if (!pending) break;
    try {
      insertCloud(*pending);
    } catch (const std::exception& e) {  // never let one cloud end the thread
      {
        std::lock_guard<std::mutex> lock(status_mutex_);
        ++status_.clouds_dropped_invalid;
      }
      recordError(std::string("cloud dropped: ") + e.what());
      warnDropped(std::string("cloud dropped: ") + e.what() + "; map unchanged");
    }
    publishStatus();
  }
}

CloudReadOptions MappingServer::cloudReadOptions() const {
  CloudReadOptions options;
  options.num_classes = config_.num_classes;
  options.input =
      config_.use_camera ? EvidenceInput::kNone : evidenceInputFromName(config_.input_type);
  options.label_magnitude = static_cast<float>(config_.label_evidence);
  options.logit_transform = logitTransformFromName(config_.logit_transform);
  options.probability_magnitude = static_cast<float>(config_.probability_evidence);
  options.raw_label_table = config_.label_is_raw ? &classes_ : nullptr;
  return options;
}

void MappingServer::dropInvalid(const std::string& frame_id, const std::string& error) {
  {
    std::lock_guard<std::mutex> status_lock(status_mutex_);
    ++status_.clouds_dropped_invalid;
  }
  recordError("cloud dropped (frame " + frame_id + "): " + error);
  warnDropped("cloud dropped (frame " + frame_id + "): " + error + "; map unchanged");
}

std::string MappingServer::prepareScan(PendingCloud& pending) {
  SemanticCloud& scan = pending.scan;
  if (config_.use_camera) {
    const std::string error = paintFromCamera(*pending.cloud, &scan);
    if (!error.empty()) return error;
  }
  if (keepHeightBand(toPose(pending.T_F_S.transform), config_.pointcloud_band,
                     config_.num_classes, &scan) > 0 &&
      scan.points_S.size() == 0)
    return "no point within pointcloud_min_z .. pointcloud_max_z";
  return "";
}

void MappingServer::insertCloud(PendingCloud& pending) {
  const sensor_msgs::PointCloud2& cloud = *pending.cloud;
  const auto t_read = std::chrono::steady_clock::now();
  const std::string error = prepareScan(pending);
  if (!error.empty()) {
    dropInvalid(cloud.header.frame_id, error);
    return;
  }
  const SemanticCloud& scan = pending.scan;
  const double read_ms = pending.read_ms + msSince(t_read);
  const auto t_wait = std::chrono::steady_clock::now();
  ++inserts_waiting_;
  std::unique_lock<std::mutex> lock(mutex_);
  --inserts_waiting_;
  const double lock_wait_ms = msSince(t_wait);
  const auto t0 = std::chrono::steady_clock::now();
  InsertStats stats;
  try {
    followLocalMap(pending.T_W_S.transform.translation);
    stats =
        tree_->insertSemanticScan(scan.points_S, scan.evidence, toPose(pending.T_W_S.transform));
  } catch (const std::invalid_argument& e) {
    {
      std::lock_guard<std::mutex> status_lock(status_mutex_);
      ++status_.clouds_dropped_invalid;
    }
    recordError(std::string("cloud dropped: ") + e.what());
    warnDropped(std::string("cloud dropped: ") + e.what() + "; map unchanged");
    return;
  }
  ++map_changes_;
  if (!(calibration_ && calibration_->error_model) && scan.source != "label" &&
      scan.source.rfind("none", 0) != 0) {
    ROS_WARN_ONCE("%s (~calibration params: config:=calibration.yaml)", kUncalibratedNote);
  }
  const double ms = msSince(t0);
  const auto& t = pending.T_W_S.transform.translation;
  last_origin_W_ = octomap::point3d(t.x, t.y, t.z);
  size_t scans = 0;
  {
    std::lock_guard<std::mutex> status_lock(status_mutex_);
    scans = ++status_.clouds_inserted;
    insert_ms_total_ += ms;
    status_.last_insert_ms = ms;
    status_.mean_insert_ms = insert_ms_total_ / double(scans);
    status_.last_read_ms = read_ms;
    status_.last_lock_wait_ms = lock_wait_ms;
    status_.max_lock_wait_ms = std::max(status_.max_lock_wait_ms, lock_wait_ms);
    status_.last_points = static_cast<uint32_t>(stats.points_in);
    status_.local_map_tiles_on_disk = local_map_ ? uint32_t(local_map_->tilesOnDisk()) : 0;
    status_.local_map_tiles_written = local_map_ ? local_map_->tilesWritten() : 0;
    status_.local_map_tiles_read = local_map_ ? local_map_->tilesRead() : 0;
  }
  recordMapSizeAfterInsert();
  ROS_INFO(
      "scan %zu: %zu points (%s, read in %.0f ms), %zu semantic, %zu voxels updated, insert "
      "%.0f ms (occupancy %.0f, kernel %.0f, update %.0f); map %zu semantic leaves; %zu waiting",
      scans, stats.points_in, scan.source.c_str(), read_ms, stats.semantic_points,
      stats.voxels_updated, ms,
      stats.ms_occupancy, stats.ms_kernel, stats.ms_update, tree_->numSemanticNodes(),
      clouds_->size());
  outputs_->markStale();
  lock.unlock();
  if (config_.publish_rate <= 0.0) publishMap(false);
}

std::string MappingServer::paintFromCamera(const sensor_msgs::PointCloud2& cloud,
                                           SemanticCloud* scan) {
  // The image nearest in time to the cloud, within camera/max_age.
  std::pair<sensor_msgs::ImageConstPtr, sensor_msgs::CameraInfoConstPtr> best;
  {
    std::lock_guard<std::mutex> lock(images_mutex_);
    double best_dt = config_.camera_max_age;
    for (const auto& pair : images_) {
      const double dt = std::abs((pair.first->header.stamp - cloud.header.stamp).toSec());
      if (dt <= best_dt) {
        best_dt = dt;
        best = pair;
      }
    }
  }
  if (!best.first) return "no evidence image within camera/max_age of the cloud";
  const sensor_msgs::Image& image = *best.first;
  geometry_msgs::TransformStamped T_C_S;
  try {
    T_C_S = tf_buffer_.lookupTransform(image.header.frame_id, cloud.header.frame_id,
                                       cloud.header.stamp);
  } catch (const tf2::TransformException& e) {
    return std::string("no camera extrinsics: ") + e.what();
  }
  cv_bridge::CvImageConstPtr cv_image;
  try {
    cv_image = cv_bridge::toCvShare(best.first);
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
  const PinholeCamera camera = cameraFromInfo(*best.second);
  const std::vector<long> pixels =
      projectToPixels(scan->points_S, R, cv::Vec3d(t.x, t.y, t.z), camera);
  octomap::Pointcloud painted;
  std::vector<float> evidence;
  float label_magnitude = 0.0f;
  {
    std::lock_guard<std::mutex> lock(options_mutex_);
    label_magnitude = read_options_.label_magnitude;
  }
  std::string error = evidenceFromImage(scan->points_S, pixels, cv_image->image,
                                        config_.num_classes, label_magnitude,
                                        config_.keep_outside_image, &painted, &evidence);
  if (!error.empty()) return error;
  if (painted.size() == 0) return "no point of the cloud lands in the evidence image";
  scan->points_S = painted;
  scan->evidence.swap(evidence);
  scan->source = "camera " + image.header.frame_id;
  return "";
}

// --- output -------------------------------------------------------------------------------

// At publish_rate; with publish_rate <= 0 (publish after every scan) a 1 Hz timer still serves
// outputs that had no subscriber when their scan arrived.
void MappingServer::restartPublishTimer() {
  publish_timer_.stop();
  const double period = config_.publish_rate > 0.0 ? 1.0 / config_.publish_rate : 1.0;
  publish_timer_ = nh_.createTimer(ros::Duration(period), &MappingServer::publishTimer, this);
}

void MappingServer::publishTimer(const ros::TimerEvent&) { publishMap(false); }

// Readers of the map (views chunk by chunk, octomap_msgs services) let a waiting insert go first:
// std::mutex is not fair, and a reader taking it again and again would starve the insert.
void MappingServer::readMap(const OctomapMsgsInterface::MapVisitor& visit) {
  while (inserts_waiting_.load() > 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::lock_guard<std::mutex> lock(mutex_);
  visit(*tree_, classes_);
}

void MappingServer::publishMap(bool force) {
  std::lock_guard<std::mutex> pass(publish_mutex_);
  const auto t0 = std::chrono::steady_clock::now();
  octomap::point3d origin_W;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    origin_W = last_origin_W_;
  }
  const std::string sent = outputs_->publish(classes_, origin_W, force);
  if (sent.empty()) return;
  const double hold_ms = outputs_->longestHoldMs();
  uint64_t scans = 0;
  double mean_ms = 0.0;
  {
    std::lock_guard<std::mutex> lock(status_mutex_);
    scans = status_.clouds_inserted;
    mean_ms = status_.mean_insert_ms;
    status_.last_publish_ms = msSince(t0);
    status_.max_publish_ms = std::max(status_.max_publish_ms, status_.last_publish_ms);
    status_.last_publish_lock_ms = hold_ms;
    status_.max_publish_lock_ms = std::max(status_.max_publish_lock_ms, hold_ms);
    status_.last_views_ms = outputs_->lastViewsMs();
    status_.last_full_maps_ms = outputs_->lastMapsMs();
  }
  ROS_INFO("published%s in %.0f ms, map lock held at most %.0f ms at a time (mean insert %.0f ms "
           "over %llu scans)",
           sent.c_str(), msSince(t0), hold_ms, mean_ms, static_cast<unsigned long long>(scans));
}

void MappingServer::recordMapSizeAfterInsert() {
  // Walks take at most 2 % of the time; with clouds waiting, at most one a second too.
  const double walks_apart = 50.0 * map_size_walk_ms_;
  if (msSince(map_size_recorded_) >=
      (clouds_->size() == 0 ? walks_apart : std::max(1000.0, walks_apart))) {
    recordMapSize();
  } else {
    map_size_stale_ = true;
  }
}

// Before waiting for the next cloud: when none comes for a moment and inserts went unrecorded.
void MappingServer::recordMapSizeWhenIdle() {
  if (!map_size_stale_ || clouds_->waitFor(std::chrono::milliseconds(300))) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!map_size_stale_) return;  // a service recorded it meanwhile
  recordMapSize();
  publishStatus();
}

void MappingServer::recordMapSize() {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t leaves = tree_->getNumLeafNodes();
  const size_t semantic = tree_->numSemanticNodes();
  const size_t bytes = tree_->memoryUsage();
  map_size_walk_ms_ = msSince(t0);
  map_size_recorded_ = std::chrono::steady_clock::now();
  map_size_stale_ = false;
  std::lock_guard<std::mutex> lock(status_mutex_);
  status_.map_leaves = leaves;
  status_.map_semantic_leaves = semantic;
  status_.map_memory_bytes = bytes;
}

void MappingServer::publishStatus() {
  MappingStatus status;
  {
    std::lock_guard<std::mutex> lock(status_mutex_);
    status_.queue_length = static_cast<uint32_t>(clouds_->size());
    status_.header.stamp = ros::Time::now();
    status = status_;
  }
  status_pub_.publish(status);
}

void MappingServer::statusTimer(const ros::TimerEvent&) {
  publishStatus();
  MappingStatus now, before;
  {
    std::lock_guard<std::mutex> lock(status_mutex_);
    now = status_;
    before = last_diagnosed_;
    last_diagnosed_ = status_;
  }
  diagnostic_msgs::DiagnosticArray array;
  array.header.stamp = now.header.stamp;
  array.status.push_back(toDiagnosticStatus(now, before, ros::this_node::getName()));
  diagnostics_pub_.publish(array);
}

// --- services ---------------------------------------------------------------------------

std::string MappingServer::absolutePath(const std::string& path) {
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(path, ec);
  return ec ? path : absolute.lexically_normal().string();
}

// Our .ot, or (first line "# Octomap OcTree binary file") a .bt whose occupancy the map takes.
// Reads no node state but the constant config, so it runs without the map lock.
std::unique_ptr<EvidentialOcTree> MappingServer::readMapFile(const std::string& path,
                                                             bool* occupancy_only) const {
  std::string first_line;
  if (std::filesystem::is_regular_file(path)) {  // never open a FIFO or a device to sniff it
    std::ifstream in(path, std::ios::binary);
    std::getline(in, first_line);
  }
  *occupancy_only = first_line.rfind("# Octomap OcTree binary file", 0) == 0;
  std::unique_ptr<EvidentialOcTree> tree;
  if (*occupancy_only) {
    tree = loadBinaryOccupancy(path, config_.num_classes, SemanticConfig());  // see adoptMap
    tree->setClasses(classes_);
  } else {
    const uint64_t limit =
        config_.load_map_max_mb > 0.0 ? uint64_t(config_.load_map_max_mb * 1e6) : 0;
    tree = evidential_octomap::loadMap(path, limit);
  }
  if (tree->numClasses() != config_.num_classes)
    throw std::runtime_error(path + " has C = " + std::to_string(tree->numClasses()) +
                             ", this node maps C = " + std::to_string(config_.num_classes));
  return tree;
}

// A map read from a .bt has only occupancy: it takes the settings and the sensor model in use
// (map mutex held). An .ot brings its own settings and resolution, which the node then maps with.
void MappingServer::adoptMap(std::unique_ptr<EvidentialOcTree> map, bool occupancy_only) {
  if (occupancy_only && tree_) {
    map->setConfig(tree_->config());
    map->setSensorModel(tree_->sensorModel());
  }
  map->setMovableClasses(classes_.movable);  // not stored in an .ot
  attachErrorModel(map.get());
  tree_ = std::move(map);
  restartLocalMap();
}

void MappingServer::loadStartupMap() {
  const std::string path = absolutePath(config_.map_file);
  bool occupancy_only = false;
  try {
    adoptMap(readMapFile(path, &occupancy_only), occupancy_only);
  } catch (const std::exception& e) {
    throw std::runtime_error("~map_file: " + std::string(e.what()));
  }
  if (tree_->getResolution() != config_.resolution) {
    ROS_WARN("~map_file %s has resolution %g m; the node maps at it (not ~resolution %g m)",
             path.c_str(), tree_->getResolution(), config_.resolution);
  }
  ROS_INFO("~map_file: loaded %zu leaves (%zu semantic) from %s", tree_->getNumLeafNodes(),
           tree_->numSemanticNodes(), path.c_str());
}

bool MappingServer::saveMap(SaveMap::Request& req, SaveMap::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  res.path = absolutePath(req.path);
  const bool occupancy_only = res.path.size() > 3 && res.path.substr(res.path.size() - 3) == ".bt";
  size_t leaves = 0, semantic = 0;
  try {
    const std::unique_ptr<EvidentialOcTree> global = globalMap();  // with tiles on disk
    const EvidentialOcTree& map = global ? *global : *tree_;
    if (occupancy_only)
      saveBinaryOccupancy(map, res.path);
    else
      evidential_octomap::saveMap(map, res.path);
    leaves = map.getNumLeafNodes();
    semantic = map.numSemanticNodes();
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
    ROS_ERROR("save_map: %s", e.what());
    return true;
  }
  res.success = true;
  res.message = "saved " + std::to_string(leaves) + " leaves (" +
                (occupancy_only ? std::string("occupancy only, .bt")
                                : std::to_string(semantic) + " semantic") +
                ") to " + res.path;
  ROS_INFO("save_map: %s", res.message.c_str());
  return true;
}

bool MappingServer::loadMap(LoadMap::Request& req, LoadMap::Response& res) {
  // Parsed without the map lock: mapping and queries go on while a large file loads. Files are
  // read only when regular (a FIFO would block, /dev/zero never end) and up to the size limit.
  const std::string path = absolutePath(req.path);
  std::unique_ptr<EvidentialOcTree> loaded;
  bool occupancy_only = false;
  try {
    loaded = readMapFile(path, &occupancy_only);
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
    ROS_ERROR("load_map: %s (map unchanged)", e.what());
    return true;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    adoptMap(std::move(loaded), occupancy_only);
    ++map_changes_;
    res.success = true;
    res.message = "loaded " + std::to_string(tree_->getNumLeafNodes()) + " leaves from " + path;
    ROS_INFO("load_map: %s", res.message.c_str());
    recordMapSize();
    outputs_->markStale();
  }
  publishMap(false);
  return true;
}

bool MappingServer::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  resetMap();
  publishMap(true);
  return true;
}

void MappingServer::resetMap() {
  std::lock_guard<std::mutex> lock(mutex_);
  // Run-time (dynamic_reconfigure) values stay; ~rule and ~sbki_prior, which change what a
  // stored voxel means and so cannot change on a live map, are re-read here.
  SemanticConfig semantic = tree_->config();
  std::string rule = semantic.rule;
  pnh_.param("rule", rule, rule);
  pnh_.param("sbki_prior", semantic.sbki_prior, semantic.sbki_prior);
  try {
    fusionRuleFromName(rule);
    semantic.rule = rule;
  } catch (const std::exception& e) {
    ROS_ERROR("reset: %s; keeping rule %s", e.what(), semantic.rule.c_str());
  }
  tree_ = makeTree(semantic);
  restartLocalMap();
  ++map_changes_;
  ROS_INFO("reset: map cleared (rule %s, resolution %g m)", tree_->config().rule.c_str(),
           tree_->getResolution());
  recordMapSize();
  outputs_->markStale();
}

bool MappingServer::clearBox(ClearBbx::Request& req, ClearBbx::Response& res) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    clearBoxRequest(tree_.get(), req, &res);
    if (!res.success) {
      ROS_ERROR("clear_bbx: %s; map unchanged", res.message.c_str());
      return true;
    }
    ++map_changes_;
    ROS_INFO("clear_bbx: %u leaves cleared in [%.2f %.2f %.2f] .. [%.2f %.2f %.2f]",
             res.voxels_cleared, req.min.x, req.min.y, req.min.z, req.max.x, req.max.y,
             req.max.z);
    recordMapSize();
    outputs_->markStale();
  }
  publishMap(true);
  return true;
}

// octomap_server's ~clear_bbx: its reply is empty, so a refused box fails the call (and is
// logged with the reason); ~clear_box replies with the count and the reason.
bool MappingServer::clearBbx(BoundingBoxQuery::Request& req, BoundingBoxQuery::Response&) {
  ClearBbx::Request box;
  box.min = req.min;
  box.max = req.max;
  ClearBbx::Response res;
  return clearBox(box, res) && res.success;
}

bool MappingServer::query(QueryMap::Request& req, QueryMap::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    answerQuery(*tree_, req, &res, local_map_.get());
  } catch (const std::runtime_error& e) {  // a tile on disk that cannot be read
    ROS_ERROR("query: %s", e.what());
    return false;
  }
  return true;
}

// --- local map -------------------------------------------------------------------------------

void MappingServer::startLocalMap() {
  stopLocalMap();
  if (config_.local_map_radius <= 0.0) return;
  std::string base = config_.local_map_tile_directory;
  if (base.empty()) {
    const char* ros_home = std::getenv("ROS_HOME");
    const char* home = std::getenv("HOME");
    base = (ros_home ? std::string(ros_home) : std::string(home ? home : ".") + "/.ros") +
           "/evidential_octomap/" + ros::this_node::getName().substr(1) + "_tiles";
  }
  base = absolutePath(base);
  if (local_maps_started_ == 0) removeTilesOfDeadNodes(base);
  // One fresh subdirectory per map (start-up, reset, load_map): tiles of another map never mix.
  const std::string dir = base + "/map_" + std::to_string(::getpid()) + "_" +
                          std::to_string(++local_maps_started_);
  local_map_ = std::make_unique<LocalMap>(tree_.get(), dir, config_.local_map_radius);
  ROS_INFO("local map: radius %g m, tiles of %g m in %s", local_map_->radius(),
           local_map_->tileEdge(), dir.c_str());
}

// The tiles of a map the node no longer holds (reset, load_map, shutdown) are deleted: an
// autosave snapshot keeps its own links of them.
void MappingServer::stopLocalMap() {
  if (!local_map_) return;
  const std::string dir = local_map_->directory();
  local_map_.reset();
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

// map_<pid>_<n> directories of a node killed before it could delete them (kill -9, a crash, a
// power cut): no process has that pid, so nothing reads them any more.
void MappingServer::removeTilesOfDeadNodes(const std::string& base) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(base, ec)) {
    unsigned long pid = 0, n = 0;
    char end = 0;
    const std::string name = entry.path().filename().string();
    if (std::sscanf(name.c_str(), "map_%lu_%lu%c", &pid, &n, &end) != 2 || pid == 0) continue;
    if (::kill(pid_t(pid), 0) != 0 && errno == ESRCH) {
      ROS_INFO("local map: removing %s (tiles of a node that is gone)", entry.path().c_str());
      std::filesystem::remove_all(entry.path(), ec);
    }
  }
}

// Tiles out and in for the sensor's position (map mutex held). A tile that cannot be written
// (a full disk) stays in memory and mapping goes on; settings reaching beyond the radius throw
// std::invalid_argument, and the cloud is dropped like any refused cloud.
void MappingServer::followLocalMap(const geometry_msgs::Vector3& origin_W) {
  if (!local_map_) return;
  try {
    local_map_->follow(octomap::point3d(origin_W.x, origin_W.y, origin_W.z));
  } catch (const std::runtime_error& e) {
    recordError(std::string("local map: ") + e.what());
    ROS_ERROR_THROTTLE(10.0, "local map: %s; the tile stays in memory", e.what());
  }
}

// After load_map or reset: a map the local map cannot follow stays whole in memory (logged).
void MappingServer::restartLocalMap() {
  try {
    startLocalMap();
  } catch (const std::exception& e) {
    local_map_.reset();
    ROS_ERROR("local map: %s; the whole map stays in memory", e.what());
    recordError(std::string("local map off: ") + e.what());
  }
}

std::unique_ptr<EvidentialOcTree> MappingServer::globalMap() const {
  return local_map_ ? local_map_->globalMap() : nullptr;
}

// --- autosave and recovery ------------------------------------------------------------------

std::string MappingServer::defaultAutosavePath(const std::string& map_file) {
  if (!map_file.empty()) {
    const std::filesystem::path p(map_file);
    return (p.parent_path() / (p.stem().string() + ".autosave.ot")).string();
  }
  std::string home;
  if (const char* ros_home = std::getenv("ROS_HOME")) {
    home = ros_home;
  } else if (const char* user_home = std::getenv("HOME")) {
    home = std::string(user_home) + "/.ros";
  } else {
    home = ".";
  }
  std::string name = ros::this_node::getName();
  for (char& ch : name)
    if (ch == '/') ch = '_';
  while (!name.empty() && name.front() == '_') name.erase(0, 1);
  return home + "/evidential_octomap/" + (name.empty() ? "map" : name) + ".autosave.ot";
}

void MappingServer::recordError(const std::string& message) {
  std::lock_guard<std::mutex> lock(status_mutex_);
  status_.last_error = message;
}

// With a local map the autosave is a snapshot directory (local_map_snapshot.h) beside the path:
// the resident tree and links of the tiles, so it never builds the whole map in memory.
std::string MappingServer::snapshotBase() const { return config_.autosave_path + ".local_map"; }

// Both kinds of autosave are only ever replaced by rename, so the file or snapshot found is the
// newest complete one; a killed writer's temporaries are never read. When both exist (the local
// map was switched on or off between runs), the newer is taken.
void MappingServer::resumeFromAutosave() {
  const std::string& path = config_.autosave_path;
  const LocalMapSnapshot snapshot = newestLocalMapSnapshot(snapshotBase());
  std::error_code ec;
  const auto written = [&ec](const std::string& p) { return std::filesystem::last_write_time(p, ec); };
  const bool have_file = std::filesystem::exists(path, ec);
  const bool use_snapshot =
      !snapshot.directory.empty() && (!have_file || written(snapshot.resident) > written(path));
  const std::string from = use_snapshot ? snapshot.resident : path;
  if (!use_snapshot && !have_file) {
    ROS_INFO("autosave: none at %s yet: starting %s", path.c_str(),
             config_.map_file.empty() ? "with an empty map" : "from ~map_file");
    return;
  }
  const auto stamp = written(from);
  const double age_s =
      ec ? -1.0
         : std::chrono::duration<double>(std::filesystem::file_time_type::clock::now() - stamp)
               .count();
  bool occupancy_only = false;
  try {
    adoptMap(readMapFile(from, &occupancy_only), occupancy_only);
    if (use_snapshot) resumeTiles(snapshot.tiles);
  } catch (const std::exception& e) {
    ROS_ERROR("autosave: cannot resume from %s: %s; starting %s (the next autosave replaces it)",
              from.c_str(), e.what(), config_.map_file.empty() ? "empty" : "from ~map_file");
    recordError(std::string("autosave not resumed: ") + e.what());
    return;
  }
  ROS_INFO("autosave: resumed from %s, written %.1f s ago: %zu leaves (%zu semantic) in memory, "
           "%zu tiles on disk", (use_snapshot ? snapshot.directory : path).c_str(), age_s,
           tree_->getNumLeafNodes(), tree_->numSemanticNodes(),
           local_map_ ? local_map_->tilesOnDisk() : size_t(0));
}

// A snapshot's tiles become the local map's tiles on disk; without a local map that can take
// them (switched off, another radius) they are merged into the tree: nothing is lost.
void MappingServer::resumeTiles(const std::vector<std::string>& tiles) {
  if (local_map_) {
    try {
      local_map_->adoptTiles(tiles);
      return;
    } catch (const std::runtime_error& e) {
      ROS_WARN("autosave: %s; the snapshot's tiles are merged into the map in memory", e.what());
    }
  }
  for (const std::string& tile : tiles) {
    try {
      tree_->merge(*evidential_octomap::loadMap(tile));
    } catch (const std::exception& e) {
      ROS_ERROR("autosave: %s; that tile's part of the map is lost", e.what());
      recordError(std::string("autosave tile not resumed: ") + e.what());
    }
  }
  restartLocalMap();
}

// At most a tenth of the node's time goes to the autosave's hold of the map lock: a map that
// takes long to serialise is saved less often than the period (logged), never more often.
void MappingServer::autosaveLoop() {
  constexpr double kPeriodPerStall = 10.0;
  double stall_s = 0.0;
  std::unique_lock<std::mutex> lock(autosave_mutex_);
  while (!stopping_) {
    const double wait_s = std::max(config_.autosave_period, kPeriodPerStall * stall_s);
    if (wait_s > config_.autosave_period) {
      ROS_INFO_THROTTLE(300.0, "autosave: the map lock was held %.1f s; next autosave in %.0f s "
                        "(~autosave_period %g s), to keep mapping stalled < 10 %% of the time",
                        stall_s, wait_s, config_.autosave_period);
    }
    const auto wait = std::chrono::duration<double>(wait_s);
    if (autosave_cv_.wait_for(lock, wait, [this] { return stopping_; })) break;
    lock.unlock();
    stall_s = autosaveOnce() / 1000.0;
    lock.lock();
  }
}

// The map is serialised under the map lock (inserts wait for that long: the stall, reported on
// ~status) and written outside it: a slow or full disk never holds up mapping. Returns the
// stall [ms] (0 when there was nothing new to save).
double MappingServer::autosaveOnce() {
  std::string bytes, problem, staging;
  uint64_t changes = 0;
  double stall_ms = 0.0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    changes = map_changes_;
    if (autosaved_once_ && changes == autosaved_changes_) return 0.0;  // nothing new to save
    const auto t0 = std::chrono::steady_clock::now();
    problem = tree_->parameterProblem();
    try {
      if (problem.empty() && local_map_) staging = stageLocalMapSnapshot(*local_map_, snapshotBase());
    } catch (const std::exception& e) {
      problem = e.what();
    }
    if (problem.empty()) {
      std::ostringstream s;
      s << std::setprecision(17);  // as saveMap: the same bytes
      if (!tree_->write(s) || !s.good()) problem = "the map could not be serialised";
      bytes = s.str();
    }
    stall_ms = msSince(t0);
  }
  std::string written = config_.autosave_path;
  try {
    if (!problem.empty()) throw std::runtime_error("cannot save " + written + ": " + problem);
    if (staging.empty())
      writeFileAtomically(written, bytes);
    else
      written = commitLocalMapSnapshot(staging, bytes, snapshotBase());
  } catch (const std::exception& e) {
    std::error_code ec;
    if (!staging.empty()) std::filesystem::remove_all(staging, ec);  // (a failed commit did)
    {
      std::lock_guard<std::mutex> lock(status_mutex_);
      ++status_.autosaves_failed;
      status_.last_error = std::string("autosave failed: ") + e.what();
    }
    ROS_ERROR_THROTTLE(10.0, "autosave failed: %s; mapping goes on, the previous autosave is kept",
                       e.what());
    return stall_ms;
  }
  autosaved_changes_ = changes;
  const bool first = !autosaved_once_;
  autosaved_once_ = true;
  {
    std::lock_guard<std::mutex> lock(status_mutex_);
    ++status_.autosaves_written;
    status_.last_autosave_stall_ms = stall_ms;
    status_.max_autosave_stall_ms = std::max(status_.max_autosave_stall_ms, stall_ms);
  }
  if (first) {
    ROS_INFO("autosave: wrote %s (%zu bytes; map lock held %.1f ms)", written.c_str(),
             bytes.size(), stall_ms);
  } else {
    ROS_DEBUG("autosave: wrote %s (%zu bytes; map lock held %.1f ms)", written.c_str(),
              bytes.size(), stall_ms);
  }
  return stall_ms;
}

// A setting the core refuses (or a kernel the machine cannot afford) is not applied: the values
// in use stay and go back to the server, so clients see what the node maps with.
void MappingServer::reconfigure(MappingConfig& rc, uint32_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  SemanticConfig semantic = tree_->config();
  NodeConfig node = config_;
  SensorModel model = tree_->sensorModel();
  fromReconfigure(rc, &semantic, &node, &model);
  const std::string problem = reconfigureProblem(semantic, model, tree_->getResolution());
  if (!problem.empty()) {
    ROS_ERROR("reconfigure refused: %s; the values in use stay", problem.c_str());
    toReconfigure(tree_->config(), *tree_, config_, &rc);
    return;
  }
  tree_->setConfig(semantic);
  tree_->setSensorModel(model);
  ++map_changes_;
  config_.label_evidence = node.label_evidence;
  {
    std::lock_guard<std::mutex> options_lock(options_mutex_);
    read_options_.label_magnitude = static_cast<float>(node.label_evidence);
  }
  if (node.publish_rate != config_.publish_rate) {
    config_.publish_rate = node.publish_rate;
    restartPublishTimer();
  }
}

}  // namespace evidential_octomap
