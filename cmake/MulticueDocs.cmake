# API reference from the /// comments of src/multicue (Doxygen). When doxygen is installed,
#   cmake --build build --target multicue_api_docs
# writes ${PROJECT_BINARY_DIR}/docs/api/index.html, with docs/api.md as its main page. The target
# is not part of ALL; without doxygen nothing is defined. See docs/api.md.
find_package(Doxygen QUIET)
if(DOXYGEN_FOUND)
  set(MULTICUE_DOCS_BINARY_DIR ${PROJECT_BINARY_DIR}/docs)
  configure_file(${PROJECT_SOURCE_DIR}/docs/Doxyfile.in ${MULTICUE_DOCS_BINARY_DIR}/Doxyfile @ONLY)
  add_custom_target(multicue_api_docs
    COMMAND Doxygen::doxygen ${MULTICUE_DOCS_BINARY_DIR}/Doxyfile
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
    COMMENT "API reference (Doxygen) -> ${MULTICUE_DOCS_BINARY_DIR}/api/index.html"
    VERBATIM)
else()
  message(STATUS "multicue: doxygen not found; the API reference target multicue_api_docs is not defined")
endif()
