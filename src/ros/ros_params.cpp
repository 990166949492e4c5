#include "ros_params.h"

#include <dynamic_reconfigure/Config.h>
#include <ros/package.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <variant>

#include "evidential_octomap/io.h"
#include "evidential_octomap/settings.h"

namespace evidential_octomap {

std::string defaultClassTablePath() {
  return ros::package::getPath("evidential_octomap") + "/config/classes_semantickitti.yaml";
}

namespace {

// ~class_costs: a dictionary {class name: cost}; ~class_cost_default for the others.
void readClassCosts(const ros::NodeHandle& nh, NodeConfig* c) {
  nh.param("class_cost_default", c->class_cost_default, c->class_cost_default);
  XmlRpc::XmlRpcValue table;
  if (!nh.getParam("class_costs", table)) return;
  if (table.getType() != XmlRpc::XmlRpcValue::TypeStruct)
    throw std::invalid_argument("~class_costs must be a dictionary {class name: cost 0..100}");
  for (auto& [name, cost] : table) {
    if (cost.getType() != XmlRpc::XmlRpcValue::TypeInt)
      throw std::invalid_argument("~class_costs/" + name + " must be an integer 0..100");
    c->class_costs.emplace_back(name, static_cast<int>(cost));
  }
}

}  // namespace

NodeConfig readNodeConfig(const ros::NodeHandle& nh) {
  NodeConfig c;
  nh.param("frame_id", c.frame_id, c.frame_id);
  nh.param("resolution", c.resolution, c.resolution);
  nh.param("classes", c.classes, c.classes);
  if (c.classes.empty()) c.classes = defaultClassTablePath();
  nh.param("num_classes", c.num_classes, c.num_classes);
  nh.param("input_type", c.input_type, c.input_type);
  nh.param("label_evidence", c.label_evidence, c.label_evidence);
  nh.param("logit_transform", c.logit_transform, c.logit_transform);
  nh.param("probability_evidence", c.probability_evidence, c.probability_evidence);
  nh.param("label_is_raw", c.label_is_raw, c.label_is_raw);
  nh.param("publish_rate", c.publish_rate, c.publish_rate);
  nh.param("publish_radius", c.publish_radius, c.publish_radius);
  nh.param("full_map_period", c.full_map_period, c.full_map_period);
  std::string view = "error_probability";
  nh.param("uncertainty_view", view, view);
  c.uncertainty_view = uncertaintyViewFromName(view);  // throws with the valid names
  nh.param("uncertainty_range/automatic", c.uncertainty_range.automatic,
           c.uncertainty_range.automatic);
  nh.param("uncertainty_range/min", c.uncertainty_range.min, c.uncertainty_range.min);
  nh.param("uncertainty_range/max", c.uncertainty_range.max, c.uncertainty_range.max);
  nh.param("queue_size", c.queue_size, c.queue_size);
  nh.param("insert_queue_size", c.insert_queue_size, c.insert_queue_size);
  nh.param("latch", c.latch, c.latch);
  nh.param("load_map/max_file_mb", c.load_map_max_mb, c.load_map_max_mb);
  nh.param("map_file", c.map_file, c.map_file);
  nh.param("autosave_period", c.autosave_period, c.autosave_period);
  nh.param("autosave_path", c.autosave_path, c.autosave_path);
  nh.param("resume_from_autosave", c.resume_from_autosave, c.autosave_period > 0.0);
  if (!(c.autosave_period >= 0.0) || !std::isfinite(c.autosave_period))
    throw std::invalid_argument("~autosave_period must be >= 0 s (0: off)");
  nh.param("local_map/radius", c.local_map_radius, c.local_map_radius);
  nh.param("local_map/tile_directory", c.local_map_tile_directory, c.local_map_tile_directory);
  if (!(c.local_map_radius >= 0.0) || !std::isfinite(c.local_map_radius))
    throw std::invalid_argument("~local_map/radius must be >= 0 m (0: off)");
  nh.param("base_frame_id", c.base_frame_id, c.base_frame_id);
  nh.param("pointcloud_min_z", c.pointcloud_band.min_z, c.pointcloud_band.min_z);
  nh.param("pointcloud_max_z", c.pointcloud_band.max_z, c.pointcloud_band.max_z);
  nh.param("occupancy_min_z", c.occupancy_band.min_z, c.occupancy_band.min_z);
  nh.param("occupancy_max_z", c.occupancy_band.max_z, c.occupancy_band.max_z);
  std::string colors = "class";
  nh.param("full_map_colors", colors, colors);
  try {
    c.full_map_colors = colorModeFromName(colors);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("~full_map_colors: ") + e.what());
  }
  readClassCosts(nh, &c);
  nh.param("use_camera", c.use_camera, c.use_camera);
  nh.param("camera/input", c.camera_input, c.camera_input);
  nh.param("camera/keep_outside_image", c.keep_outside_image, c.keep_outside_image);
  nh.param("camera/max_age", c.camera_max_age, c.camera_max_age);
  if (!(c.resolution > 0.0)) throw std::invalid_argument("~resolution must be > 0");
  if (c.label_evidence < 0.0) throw std::invalid_argument("~label_evidence must be >= 0");
  if (c.queue_size < 1) throw std::invalid_argument("~queue_size must be >= 1");
  if (!(c.pointcloud_band.min_z < c.pointcloud_band.max_z))
    throw std::invalid_argument("~pointcloud_min_z must be < ~pointcloud_max_z");
  if (!(c.occupancy_band.min_z < c.occupancy_band.max_z))
    throw std::invalid_argument("~occupancy_min_z must be < ~occupancy_max_z");
  if (c.insert_queue_size < 1) throw std::invalid_argument("~insert_queue_size must be >= 1");
  if (!(c.probability_evidence >= 0.0))
    throw std::invalid_argument("~probability_evidence must be >= 0");
  logitTransformFromName(c.logit_transform);  // throws with the valid names
  if (c.camera_input != "evidence" && c.camera_input != "label")
    throw std::invalid_argument("~camera/input must be 'evidence' or 'label'");
  evidenceInputFromName(c.input_type);  // throws with the valid names
  return c;
}

std::shared_ptr<const Calibration> readCalibrationParams(const ros::NodeHandle& nh,
                                                         double evidence_cap) {
  if (!nh.hasParam("calibration_version") && !nh.hasParam("error_model_terms")) return nullptr;
  int version = 1;
  std::string rule = "dempster";
  std::vector<std::string> classes, terms;
  std::vector<double> weights;
  nh.param("calibration_version", version, version);
  nh.param("calibration_rule", rule, rule);
  const auto list = [&](const char* name, auto* values) {
    if (nh.hasParam(name) && !nh.getParam(name, *values))
      throw std::invalid_argument(std::string("~") + name + " must be a list");
  };
  list("calibration_classes", &classes);
  list("error_model_terms", &terms);
  list("error_model_weights", &weights);
  try {
    return std::make_shared<const Calibration>(makeCalibration(
        version, rule, classes, evidence_cap, terms, weights, nh.getNamespace() + " params"));
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("~calibration: ") + e.what());
  }
}

void readSemanticConfig(const ros::NodeHandle& nh, double resolution, SemanticConfig* config) {
  SemanticConfig& c = *config;
  for (const Setting& s : settingList()) {  // one ~param per setting, default the struct's
    std::visit([&](auto member) { nh.param(s.rosName(), c.*member, c.*member); }, s.field);
  }
  std::string problem = c.problem();
  if (problem.empty()) problem = c.supportProblem(resolution);
  if (!problem.empty()) throw std::invalid_argument("~parameters refused: " + problem);
}

void readOccupancyParams(const ros::NodeHandle& nh, EvidentialOcTree* tree) {
  SensorModel model = tree->sensorModel();
  nh.param("sensor_model/hit", model.hit, model.hit);
  nh.param("sensor_model/miss", model.miss, model.miss);
  nh.param("sensor_model/min", model.clamp_min, model.clamp_min);
  nh.param("sensor_model/max", model.clamp_max, model.clamp_max);
  const std::string problem = model.problem();
  if (!problem.empty()) throw std::invalid_argument("~" + problem);
  tree->setSensorModel(model);
}

namespace {

// A dynamic_reconfigure parameter's name for a setting of the list: its ~param with "/" as "_".
std::string reconfigureName(const Setting& s) {
  std::string name = s.rosName();
  std::replace(name.begin(), name.end(), '/', '_');
  return name;
}

template <class Param>
Param& paramOf(std::vector<Param>* params, const std::string& name) {
  for (Param& p : *params)
    if (p.name == name) return p;
  throw std::logic_error("Mapping.cfg has no parameter " + name);  // test_settings checks it
}

// Copies each reconfigurable setting of the list from `semantic` into the Config message, or
// (to_message false) back.
void exchangeSettings(dynamic_reconfigure::Config* msg, SemanticConfig* semantic,
                      bool to_message) {
  for (const Setting& s : settingList()) {
    if (!s.reconfigurable) continue;
    std::visit([&](auto member) {
      auto& field = semantic->*member;
      using T = std::decay_t<decltype(field)>;
      const auto copy = [&](auto& value) {
        if (to_message) {
          value = field;
        } else {
          field = static_cast<T>(value);
        }
      };
      if constexpr (std::is_same_v<T, bool>) {
        copy(paramOf(&msg->bools, reconfigureName(s)).value);
      } else if constexpr (std::is_floating_point_v<T>) {
        copy(paramOf(&msg->doubles, reconfigureName(s)).value);
      } else if constexpr (std::is_integral_v<T>) {
        copy(paramOf(&msg->ints, reconfigureName(s)).value);
      }
    }, s.field);
  }
}

}  // namespace

void toReconfigure(const SemanticConfig& semantic, const EvidentialOcTree& tree,
                   const NodeConfig& node, MappingConfig* rc) {
  // A default-constructed MappingConfig is uninitialised (the generated struct has no
  // initialisers) and __toMessage__ reads every field: start from the generated defaults.
  *rc = MappingConfig::__getDefault__();
  dynamic_reconfigure::Config msg;
  rc->__toMessage__(msg);
  SemanticConfig values = semantic;
  exchangeSettings(&msg, &values, true);
  rc->__fromMessage__(msg);
  rc->sensor_model_hit = tree.getProbHit();
  rc->sensor_model_miss = tree.getProbMiss();
  rc->sensor_model_min = tree.getClampingThresMin();
  rc->sensor_model_max = tree.getClampingThresMax();
  rc->publish_rate = node.publish_rate;
  rc->label_evidence = node.label_evidence;
}

void fromReconfigure(const MappingConfig& rc, SemanticConfig* semantic, NodeConfig* node,
                     SensorModel* model) {
  dynamic_reconfigure::Config msg;
  rc.__toMessage__(msg);
  exchangeSettings(&msg, semantic, false);
  model->hit = rc.sensor_model_hit;
  model->miss = rc.sensor_model_miss;
  model->clamp_min = rc.sensor_model_min;
  model->clamp_max = rc.sensor_model_max;
  node->publish_rate = rc.publish_rate;
  node->label_evidence = rc.label_evidence;
}

std::string reconfigureProblem(const SemanticConfig& semantic, const SensorModel& model,
                               double resolution) {
  std::string problem = semantic.problem();
  if (problem.empty()) problem = semantic.supportProblem(resolution);
  if (problem.empty()) problem = model.problem();
  return problem;
}

void reconfigureLimits(MappingConfig* min, MappingConfig* max) {
  *min = MappingConfig::__getMin__();
  *max = MappingConfig::__getMax__();
  min->sensor_model_hit = SensorModel::kMinHit;
  max->sensor_model_hit = SensorModel::kMaxHit;
  min->sensor_model_miss = SensorModel::kMinMiss;
  max->sensor_model_miss = SensorModel::kMaxMiss;
  min->sensor_model_min = SensorModel::kMinClampMin;
  max->sensor_model_min = SensorModel::kMaxClampMin;
  min->sensor_model_max = SensorModel::kMinClampMax;
  max->sensor_model_max = SensorModel::kMaxClampMax;
}

}  // namespace evidential_octomap
