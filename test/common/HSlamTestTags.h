// AprilTags for the synthetic scene: the family's image (tutorials/servo/TagPicture.h, drawn by libapriltag) hung on
// a wall of vpHSlamSyntheticScene with its exact pose.
#ifndef HSLAM_TEST_TAGS_H
#define HSLAM_TEST_TAGS_H

#include "../../tutorials/servo/TagPicture.h"

#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

namespace hslam_test
{
using hslam_tag::canDrawTags;

#define HSLAM_REQUIRE_TAG_IMAGES()                                                                                     \
  do {                                                                                                                 \
    if (!hslam_test::canDrawTags()) {                                                                                  \
      GTEST_SKIP() << "libapriltag (Debian libapriltag-dev) not found at build time: no tag image to render";          \
    }                                                                                                                  \
  } while (0)

/*!
  Hang tag36h11 number \e id on a wall of \e scene, centred at \e centre (world, metres), its black square \e size
  metres wide. Returns wMt, the tag frame of vpDetectorAprilTag::getPose() in the scene's world.
*/
inline vpHomogeneousMatrix hangTag36h11(vpHSlamSyntheticScene &scene, int id, const vpColVector &centre, double size)
{
  unsigned int blackCells = 0;
  const vpImage<unsigned char> tag = hslam_tag::tag36h11Image(id, blackCells);
  return scene.addWallTag(tag, blackCells, centre, size);
}
} // namespace hslam_test

#endif
