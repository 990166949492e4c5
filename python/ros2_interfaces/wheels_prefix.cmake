# Shared by the interface packages here: find the ROS 2 wheels' CMake packages and ament index in
# the prefix of the environment that installed them (the venv, or pip's isolated build
# environment), after find_package(Python3 ... NumPy).
execute_process(
  COMMAND "${Python3_EXECUTABLE}" -c
    "import sys, pathlib, ament_package, geometry_msgs; print(';'.join(dict.fromkeys([sys.prefix] + [str(pathlib.Path(m.__file__).parents[4]) for m in (ament_package, geometry_msgs)])))"
  OUTPUT_VARIABLE ros_prefixes OUTPUT_STRIP_TRAILING_WHITESPACE COMMAND_ERROR_IS_FATAL ANY)
list(PREPEND CMAKE_PREFIX_PATH ${ros_prefixes})
string(REPLACE ";" ":" ament_prefix_path "${ros_prefixes}")
set(ENV{AMENT_PREFIX_PATH} "${ament_prefix_path}")

# The wheels' exported Python targets name the include directories of the interpreter they were
# built with (/opt/python/...): point them at this interpreter's and its numpy's. Call after the
# find_package calls that import them.
macro(use_this_python_for_the_wheels_targets)
  get_property(imported_targets DIRECTORY PROPERTY IMPORTED_TARGETS)
  foreach(target IN LISTS imported_targets)
    if(target MATCHES "__rosidl_generator_py$")
      set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES
        "${Python3_INCLUDE_DIRS};${Python3_NumPy_INCLUDE_DIRS}")
    endif()
  endforeach()
endmacro()
