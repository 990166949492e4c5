// SemanticConfig: one attribute per setting of settings.h (defaults from the C++ struct).
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include <sstream>

#include "bindings.h"
#include "evidential_octomap/calibration_file.h"
#include "evidential_octomap/settings.h"
#include "evidential_octomap/subjective_logic.h"

namespace evidential_octomap::python {

void bindConfig(nb::module_& m) {
  nb::class_<SemanticConfig> config(
      m, "SemanticConfig",
      "Mapping parameters (docs/parameters.md). Keyword arguments set fields by name, e.g. "
      "SemanticConfig(rule='sbki', max_range=50.0).");
  config.def(nb::init<>())
      .def("__init__",
           [](SemanticConfig* self, nb::kwargs kwargs) {
             new (self) SemanticConfig();
             nb::object py_self = nb::find(self);
             nb::inst_mark_ready(py_self);  // constructed: its attributes may be set now
             for (auto [name, value] : kwargs) {
               if (!nb::hasattr(py_self, name)) {
                 throw nb::type_error(
                     ("SemanticConfig has no parameter '" + nb::cast<std::string>(name) + "'")
                         .c_str());
               }
               nb::setattr(py_self, name, value);
             }
           })
      .def("__repr__", [](const SemanticConfig& c) {
        std::ostringstream out;
        c.print(out);
        return out.str();
      });
  // One attribute per setting of settings.h, documented there.
  for (const Setting& setting : settingList()) {
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(std::declval<SemanticConfig&>().*member)>;
          config.def_prop_rw(
              setting.name, [member](const SemanticConfig& c) { return c.*member; },
              [member](SemanticConfig& c, const T& value) { c.*member = value; }, setting.help);
        },
        setting.field);
  }
  m.attr("EVIDENCE_MAGNITUDE") = kEvidenceMagnitude;
  nb::class_<Calibration>(m, "Calibration",
                          "A file written by `evidential_octomap calibrate` "
                          "(docs/calibration.md): the read-out cap and the error model of one "
                          "rule and class table. tree.apply_calibration(read_calibration(path)).")
      .def_ro("version", &Calibration::version)
      .def_ro("rule", &Calibration::rule, "The rule it was fitted for.")
      .def_ro("classes", &Calibration::classes, "The class names it was fitted for, in order.")
      .def_ro("evidence_cap", &Calibration::evidence_cap, "-1: the adaptive cap.")
      .def_prop_ro(
          "error_model_terms",
          [](const Calibration& c) {
            return c.error_model ? c.error_model->terms() : std::vector<std::string>();
          },
          "The error model's terms ([] when the file has none).")
      .def_ro("source", &Calibration::source);
  m.attr("UNCALIBRATED_NOTE") = kUncalibratedNote;
  m.def("read_calibration", &readCalibration, nb::arg("path"),
        "Reads a calibration file. Raises RuntimeError (naming the file and line) for an "
        "unreadable or invalid file.");
}

}  // namespace evidential_octomap::python
