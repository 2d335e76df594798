# Install a package config so another CMake project can use the stand-alone build:
#   find_package(HSLAM REQUIRED)   ->   target_link_libraries(app PRIVATE VISP::visp_hslam)
include(CMakePackageConfigHelpers)
set(HSLAM_CMAKE_INSTALL_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/HSLAM")
install(EXPORT HSlamTargets NAMESPACE VISP:: DESTINATION "${HSLAM_CMAKE_INSTALL_DIR}")
configure_package_config_file("${CMAKE_CURRENT_LIST_DIR}/HSLAMConfig.cmake.in"
                              "${CMAKE_BINARY_DIR}/HSLAMConfig.cmake" INSTALL_DESTINATION "${HSLAM_CMAKE_INSTALL_DIR}")
write_basic_package_version_file("${CMAKE_BINARY_DIR}/HSLAMConfigVersion.cmake" COMPATIBILITY SameMinorVersion)
install(FILES "${CMAKE_BINARY_DIR}/HSLAMConfig.cmake" "${CMAKE_BINARY_DIR}/HSLAMConfigVersion.cmake"
        DESTINATION "${HSLAM_CMAKE_INSTALL_DIR}")

# The package's documentation (target `doc`).
include("${CMAKE_CURRENT_LIST_DIR}/HSlamDoc.cmake")
