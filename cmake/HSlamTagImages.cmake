# AprilTag images for the synthetic room's tags (the tag tests, the hslam_tag_room benchmark program and
# tutorial-hslam-servo --tag): Debian's libapriltag-dev draws them (apriltag_to_image). Optional: without it the tag
# tests skip and the servo program refuses --tag, each saying so. The module itself detects tags with ViSP's
# vpDetectorAprilTag and never links libapriltag.
#
# Defines the INTERFACE target hslam_tag_images (empty when libapriltag is missing) and HSLAM_HAVE_TAG_IMAGES.
find_path(HSLAM_APRILTAG_INCLUDE_DIR NAMES apriltag/tag36h11.h)
find_library(HSLAM_APRILTAG_LIBRARY NAMES apriltag)
find_library(HSLAM_APRILTAG_UTILS_LIBRARY NAMES apriltag-utils) # image_u8 (Debian splits it out)
add_library(hslam_tag_images INTERFACE)
if(HSLAM_APRILTAG_INCLUDE_DIR AND HSLAM_APRILTAG_LIBRARY AND HSLAM_APRILTAG_UTILS_LIBRARY)
  set(HSLAM_HAVE_TAG_IMAGES ON)
  target_include_directories(hslam_tag_images INTERFACE "${HSLAM_APRILTAG_INCLUDE_DIR}")
  target_link_libraries(hslam_tag_images INTERFACE "${HSLAM_APRILTAG_LIBRARY}" "${HSLAM_APRILTAG_UTILS_LIBRARY}")
  target_compile_definitions(hslam_tag_images INTERFACE HSLAM_HAVE_APRILTAG_IMAGES=1)
else()
  set(HSLAM_HAVE_TAG_IMAGES OFF)
  message(STATUS "libapriltag not found (Debian libapriltag-dev): the tests with a rendered AprilTag will skip and "
                 "tutorial-hslam-servo --tag is unavailable")
endif()
