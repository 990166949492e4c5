// ClassTable: names, colours and the raw-label map of config/classes_*.yaml.
#include <nanobind/stl/string.h>
#include <nanobind/stl/vector.h>

#include "bindings.h"
#include "evidential_octomap/class_table.h"

namespace evidential_octomap::python {

namespace {
nb::ndarray<nb::numpy, uint8_t> colorArray(const ClassTable& table) {
  std::vector<uint8_t> rgb;
  rgb.reserve(table.colors.size() * 3);
  for (const auto& c : table.colors) rgb.insert(rgb.end(), c.begin(), c.end());
  return toNumpy(std::move(rgb), {table.colors.size(), 3});
}

Array<int32_t> classesOfRaw(
    const ClassTable& table,
    const nb::ndarray<const uint32_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>& raw) {
  std::vector<int32_t> classes(raw.shape(0));
  const uint32_t* data = raw.data();
  for (size_t i = 0; i < classes.size(); ++i) classes[i] = table.classOfRaw(data[i]);
  return toNumpy(std::move(classes), {raw.shape(0)});
}
}  // namespace

void bindClassTable(nb::module_& m) {
  nb::class_<ClassTable>(
      m, "ClassTable", "Class names, colours and raw-label map of a dataset (a YAML class table).")
      .def_static("load", &ClassTable::load, nb::arg("path"),
                  "Reads a YAML class table; raises RuntimeError naming the file and the problem.")
      .def_ro("dataset", &ClassTable::dataset)
      .def_ro("names", &ClassTable::names, "C class names, index = class id.")
      .def_ro("ground", &ClassTable::ground,
              "C flags: the class is a ground surface (its points' kernel support is flatter).")
      .def_ro("movable", &ClassTable::movable,
              "C flags: the class moves (movable_clearing_observations clears it).")
      .def_prop_ro("colors", &colorArray, kShared, "(C, 3) uint8 RGB colours.")
      .def_ro("ignore_class", &ClassTable::ignore_class,
              "Class excluded from evaluation queries (-1: none).")
      .def_prop_ro("num_classes", &ClassTable::numClasses)
      .def("classes_of_raw", &classesOfRaw, nb::arg("raw_labels"),
           "Class ids of raw dataset labels (lower 16 bits used); raises IndexError naming an "
           "unknown id.")
      .def("__len__", &ClassTable::numClasses)
      .def("__repr__", [](const ClassTable& t) {
        return "ClassTable('" + t.dataset + "', " + std::to_string(t.numClasses()) + " classes)";
      });
}

}  // namespace evidential_octomap::python
