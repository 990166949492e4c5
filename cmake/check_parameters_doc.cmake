# ctest: the committed docs/parameters.md must be what `evidential_octomap parameters` prints.
execute_process(COMMAND ${CLI} parameters OUTPUT_VARIABLE generated RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${CLI} parameters failed (${rc})")
endif()
file(READ ${EXPECTED} committed)
if(NOT generated STREQUAL committed)
  message(FATAL_ERROR "${EXPECTED} is not what the list of settings gives; regenerate it:\n"
    "  build/core/src/tools/evidential_octomap parameters > docs/parameters.md")
endif()
