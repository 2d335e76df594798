# API documentation of the public headers (Doxygen): `cmake --build build --target doc` writes build/doc/html/.
# The ctest package.doc builds it and fails on any Doxygen warning (skipped when doxygen is not installed).
find_package(Doxygen QUIET)
set(HSLAM_DOC_OUTPUT "${CMAKE_BINARY_DIR}/doc")
set(HSLAM_DOC_INPUT "${PROJECT_SOURCE_DIR}/modules/hslam/include/visp3/hslam ${PROJECT_SOURCE_DIR}/modules/hslam/doc")
configure_file("${PROJECT_SOURCE_DIR}/modules/hslam/doc/Doxyfile.in" "${CMAKE_BINARY_DIR}/Doxyfile" @ONLY)
if(DOXYGEN_FOUND)
  add_custom_target(doc
    COMMAND "${CMAKE_COMMAND}" -E make_directory "${HSLAM_DOC_OUTPUT}"
    COMMAND "${DOXYGEN_EXECUTABLE}" "${CMAKE_BINARY_DIR}/Doxyfile"
    WORKING_DIRECTORY "${CMAKE_BINARY_DIR}"
    COMMENT "Doxygen: API documentation in ${HSLAM_DOC_OUTPUT}/html")
endif()
