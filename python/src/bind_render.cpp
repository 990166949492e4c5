// The CLI's top-down PNG renders (src/render/render.cpp, OpenCV), so the Python package draws its
// pictures with the one renderer. Compiled only when OpenCV is found (see python/CMakeLists.txt).
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bindings.h"
#include "evidential_octomap/evaluation/metrics.h"
#include "render.h"

namespace evidential_octomap::python {

void bindRender(nb::module_& m) {
  m.def(
      "render_top_down",
      [](const EvidentialOcTree& tree, const ClassTable& classes, const std::string& path,
         const std::string& mode, const std::vector<std::string>& caption) {
        nb::gil_scoped_release release;
        const tools::TopDownGrid grid = tools::makeGrid(tree, nullptr);
        if (mode == "semantic") {
          tools::writePng(path, tools::renderSemantic(tree, classes, grid, caption));
        } else if (mode == "uncertainty") {
          tools::writePng(path, tools::renderUncertainty(tree, grid, caption));
        } else {
          throw std::invalid_argument("mode must be 'semantic' or 'uncertainty', got '" + mode +
                                      "'");
        }
      },
      nb::arg("tree"), nb::arg("classes"), nb::arg("path"), nb::arg("mode") = "semantic",
      nb::arg("caption") = std::vector<std::string>(),
      "Writes the CLI's top-down PNG of the map ('semantic': classes with a legend, "
      "'uncertainty': u with a colour bar; each column shows its highest occupied leaf, +y up).");
}

}  // namespace evidential_octomap::python
