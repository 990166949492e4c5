// The one settings list (settings.h) and the core's checks, for front ends written in Python
// (the ROS 2 node declares its parameters from it and refuses values by these checks).
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <cmath>

#include "bindings.h"
#include "evidential_octomap/sensor_model.h"
#include "evidential_octomap/settings.h"

namespace evidential_octomap::python {
namespace {

// A number bound as None when it is infinite or NaN (no bound, no special value).
nb::object bound(double v) { return std::isfinite(v) ? nb::cast(v) : nb::none(); }

nb::dict describe(const Setting& s, const SemanticConfig& defaults) {
  nb::dict d;
  d["name"] = s.name;
  d["ros_name"] = s.rosName();
  d["type"] = s.typeName();
  d["scope"] = s.scope == SettingScope::kMap ? "map" : "insert";
  d["help"] = s.help ? s.help : "";
  d["default"] = std::visit([&](auto member) { return nb::cast(defaults.*member); }, s.field);
  d["min"] = bound(s.range.lo);
  d["max"] = bound(s.range.hi);
  d["min_open"] = s.range.lo_open;
  d["max_open"] = s.range.hi_open;
  d["special"] = bound(s.range.special);
  d["range_text"] = s.range.text;
  d["choices"] = s.choices;
  return d;
}

}  // namespace

void bindSettings(nb::module_& m) {
  m.def(
      "settings",
      [] {
        const SemanticConfig defaults;
        nb::list out;
        for (const Setting& s : settingList()) out.append(describe(s, defaults));
        return out;
      },
      "Every setting of SemanticConfig, in the order the core checks them: dicts of name, "
      "ros_name, type, scope ('map' or 'insert'), help, default, min, max (None: unbounded), "
      "min_open, max_open, special (a value allowed outside the range, or None), range_text "
      "and choices.");
  m.def(
      "config_problem", [](const SemanticConfig& c) { return c.problem(); }, nb::arg("config"),
      "The first value of the config the core refuses, said as its error says it; '' when none.");
  m.def(
      "support_problem",
      [](const SemanticConfig& c, double resolution) { return c.supportProblem(resolution); },
      nb::arg("config"), nb::arg("resolution"),
      "Why the kernel support is beyond what a scan may cost at this resolution; '' when it is "
      "not.");
  m.def(
      "sensor_model_problem",
      [](double hit, double miss, double clamp_min, double clamp_max) {
        SensorModel model;
        model.hit = hit;
        model.miss = miss;
        model.clamp_min = clamp_min;
        model.clamp_max = clamp_max;
        model.occupancy_threshold = 0.5;
        return model.problem();
      },
      nb::arg("hit"), nb::arg("miss"), nb::arg("clamp_min"), nb::arg("clamp_max"),
      "Why an occupancy sensor model is unusable (the check of the tree and the .ot files); '' "
      "when it is usable.");
}

}  // namespace evidential_octomap::python
