// Every ~param of the node, read in one place (voxblox ros_params.h). Semantic parameters go
// into the core's SemanticConfig and occupancy parameters into the tree; a missing parameter
// keeps the value the struct or OctoMap already has (nh.param(name, cfg.x, cfg.x)), so no core
// default is restated here. NodeConfig holds what only the node has, with its defaults written
// once below.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <ros/node_handle.h>

#include "conversions.h"
#include "evidential_octomap/calibration_file.h"
#include "evidential_octomap/MappingConfig.h"
#include "evidential_octomap/evidential_octree.h"
#include "evidential_octomap/io.h"
#include "evidential_octomap/semantic_config.h"
#include "visualization.h"

namespace evidential_octomap {

struct NodeConfig {
  std::string frame_id = "map";      // map frame; clouds are transformed into it
  double resolution = 0.2;           // leaf size [m]
  std::string classes;               // class-table yaml; "" = the package's SemanticKITTI table
  int num_classes = 0;               // 0 = from the class table; otherwise must agree with it
  std::string input_type = "auto";   // auto | evidence | alpha | logits | probabilities | label | none
  double label_evidence = kEvidenceMagnitude;  // one-hot evidence magnitude for `label` inputs
  std::string logit_transform = "softmax";  // logits -> evidence: softmax | exp | softplus
  double probability_evidence = kEvidenceMagnitude;  // E of probabilities and softmax logits
  bool label_is_raw = false;         // labels are raw dataset ids (table's learning map)
  double publish_rate = 1.0;         // max map publishing rate [Hz]; <= 0: after every scan
  double publish_radius = -1.0;      // > 0: views only within this radius of the sensor [m]
  // > 0: the whole-map outputs (evidential_map, occupancy_map, projected maps, octomap_msgs),
  // whose cost grows with the map, are rebuilt at most once per this period [s]; the views
  // follow publish_rate. A forced publish (reset, clear_bbx) sends them at once.
  double full_map_period = 0.0;
  UncertaintyView uncertainty_view = UncertaintyView::kErrorProbability;  // what it colours
  UncertaintyRange uncertainty_range;  // uncertainty colour range (fixed 0..1 or automatic)
  int queue_size = 5;                // tf2 MessageFilter queue (clouds waiting for their TF)
  int insert_queue_size = 1;         // clouds waiting for the insertion thread; when full, the
                                     // oldest is dropped (counted, warned, on ~status)
  bool latch = true;                 // latch the map topics (as octomap_server's `latch`)
  double load_map_max_mb = 4096.0;   // ~load_map refuses larger files (<= 0: no limit)
  // octomap_server parity.
  std::string map_file;              // map loaded at start-up: our .ot, or an occupancy .bt
  // Autosave: every autosave_period s (0: off) the map is written atomically to autosave_path
  // (default: beside ~map_file as <stem>.autosave.ot, else $ROS_HOME (~/.ros)/evidential_octomap/
  // <node name>.autosave.ot); at start-up with resume_from_autosave (default: on when autosave
  // is) the node resumes from that file when it exists. With a local map the autosave is a
  // snapshot directory <autosave_path>.local_map/ (local_map_snapshot.h).
  double autosave_period = 0.0;
  std::string autosave_path;
  bool resume_from_autosave = false;
  // Local map (local_map.h): local_map_radius > 0 keeps only the map within that radius [m] of
  // the sensor in memory, the rest as tiles under local_map_tile_directory (default $ROS_HOME
  // (~/.ros)/evidential_octomap/<node name>_tiles), one fresh subdirectory per map.
  double local_map_radius = 0.0;
  std::string local_map_tile_directory;
  std::string base_frame_id;         // frame of pointcloud_min_z/max_z ("" = frame_id)
  HeightBand pointcloud_band;        // pointcloud_min_z/max_z: input points kept [m]
  HeightBand occupancy_band;         // occupancy_min_z/max_z: leaves in views and 2-D maps [m]
  ColorMode full_map_colors = ColorMode::kClass;  // octomap_full's ColorOcTree colours
  // projected_cost_map: cost 0..100 per class name; classes left out cost class_cost_default.
  std::vector<std::pair<std::string, int>> class_costs;
  int class_cost_default = 100;
  // Camera path (off unless use_camera): evidence image + CameraInfo paint the LiDAR cloud.
  bool use_camera = false;
  std::string camera_input = "evidence";  // evidence (32FC(C)) | label (mono8/mono16)
  bool keep_outside_image = false;        // points outside the image: occupancy only, else dropped
  double camera_max_age = 0.2;            // max |t_cloud - t_image| [s]
};

// The keys of a calibration file (calibration_file.h) as ~params, loaded with rosparam or the
// launch files' config:= (evidence_cap is the setting's, read with the semantic parameters):
// null when neither ~calibration_version nor ~error_model_terms is set. Throws
// std::invalid_argument naming the parameter for a value that does not parse.
std::shared_ptr<const Calibration> readCalibrationParams(const ros::NodeHandle& nh,
                                                         double evidence_cap);

// Reads the node's own parameters. Throws std::invalid_argument for values that cannot work.
NodeConfig readNodeConfig(const ros::NodeHandle& nh);

// Reads the semantic parameters over `config` (names as in SemanticConfig; max range is
// sensor_model/max_range as in octomap_server). Throws std::invalid_argument, naming the
// parameter, for values the core's validation refuses (SemanticConfig::problem) and for a
// kernel no scan at `resolution` may use (supportProblem): the node refuses to start.
void readSemanticConfig(const ros::NodeHandle& nh, double resolution, SemanticConfig* config);

// Reads sensor_model/{hit,miss,min,max} over the tree's current values and sets them; throws
// std::invalid_argument outside SensorModel's ranges (hit 1 gave a map that could not load).
void readOccupancyParams(const ros::NodeHandle& nh, EvidentialOcTree* tree);

// dynamic_reconfigure (src/ros/cfg/Mapping.cfg): the values in use -> the server's config, and a
// config from the server -> semantic config, node config and sensor model, unchecked (the server
// checks them with reconfigureProblem before anything is applied). The semantic settings are
// the list's reconfigurable ones (settings.h), by their ~param names with "/" as "_".
void toReconfigure(const SemanticConfig& semantic, const EvidentialOcTree& tree,
                   const NodeConfig& node, MappingConfig* rc);
void fromReconfigure(const MappingConfig& rc, SemanticConfig* semantic, NodeConfig* node,
                     SensorModel* model);
// "" when a reconfigured setting may be applied to a map of leaf size `resolution`, else why not
// (the core's validation of both, and the kernel-support bound).
std::string reconfigureProblem(const SemanticConfig& semantic, const SensorModel& model,
                               double resolution);
// The slider bounds the server advertises: Mapping.cfg's, with the sensor model's taken from
// the core (SensorModel's ranges), so that no value inside them makes a map that cannot load.
void reconfigureLimits(MappingConfig* min, MappingConfig* max);

// The package's default class table (config/classes_semantickitti.yaml).
std::string defaultClassTablePath();

}  // namespace evidential_octomap
