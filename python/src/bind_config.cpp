// SemanticConfig: every mapping parameter, defaults from the C++ struct (never restated here).
#include <nanobind/stl/string.h>

#include <sstream>

#include "bindings.h"
#include "calibration_file.h"
#include "evidential_octomap/semantic_config.h"

namespace evidential_octomap::python {

void bindConfig(nb::module_& m) {
  nb::class_<SemanticConfig> config(
      m, "SemanticConfig",
      "Mapping parameters (see semantic_config.h). Keyword arguments set fields by name, e.g. "
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
      .def_rw("rule", &SemanticConfig::rule, "'dempster' (the paper), 'sbki' or 'ebs'.")
      .def_rw("length_scale", &SemanticConfig::length_scale, "Kernel length scale l [m].")
      .def_rw("sigma0", &SemanticConfig::sigma0, "Kernel amplitude.")
      .def_rw("beta", &SemanticConfig::beta, "Adaptive length factor.")
      .def_rw("gamma", &SemanticConfig::gamma, "Adaptive length decay.")
      .def_rw("drop_percent", &SemanticConfig::drop_percent,
              "Percentage of each scan's most uncertain points that are dropped (psi).")
      .def_rw("adaptive_length", &SemanticConfig::adaptive_length)
      .def_rw("uncertainty_threshold", &SemanticConfig::uncertainty_threshold)
      .def_rw("reference_compat", &SemanticConfig::reference_compat,
              "The authors' released configuration: gamma = 0 and count-cap down-sampling.")
      .def_rw("sbki_prior", &SemanticConfig::sbki_prior)
      .def_rw("evidence_cap", &SemanticConfig::evidence_cap,
              "dempster: opinions are read with the log-evidence capped at this: -1 follows the "
              "evidence (docs/calibration.md), 0 no cap, > 0 a fixed cap.")
      .def_rw("downsampling", &SemanticConfig::downsampling,
              "'average' (per cell of resolution / ds_multiplier) or 'count_cap' (the authors').")
      .def_rw("kernel_distance", &SemanticConfig::kernel_distance,
              "'voxel' (distance to the voxel's cube) or 'centre'.")
      .def_rw("ds_multiplier", &SemanticConfig::ds_multiplier,
              "Down-sampling parameter (<= 0: off): average grid resolution / ds_multiplier, "
              "or count cap ds_multiplier + 1 points per 2 x 2 x 2 voxels.")
      .def_rw("max_range", &SemanticConfig::max_range, "Max sensor range [m]; < 0: unlimited.")
      .def_rw("kernel_creates_leaves", &SemanticConfig::kernel_creates_leaves,
              "Let kernel updates create leaves in unknown space.")
      .def_rw("discretize", &SemanticConfig::discretize)
      .def_rw("fast_free_space", &SemanticConfig::fast_free_space)
      .def_rw("semantic_occupied_only", &SemanticConfig::semantic_occupied_only,
              "Semantic evidence only for occupied voxels and the scan's end voxels (live).")
      .def_rw("evidence_floor", &SemanticConfig::evidence_floor,
              "Point evidence below this counts as 0 (0: off; an insertion setting).")
      .def_rw("threads", &SemanticConfig::threads,
              "Threads of the semantic pass (0: OpenMP default).")
      .def("__repr__", [](const SemanticConfig& c) {
        std::ostringstream out;
        c.print(out);
        return out.str();
      });
  m.def("read_calibration", &tools::readCalibrationCap, nb::arg("path"),
        "The dempster read-out cap of a file written by `evidential_octomap calibrate`: "
        "SemanticConfig(evidence_cap=read_calibration(path)). Raises RuntimeError (naming the "
        "file and line) for an unreadable or invalid file.");
}

}  // namespace evidential_octomap::python
