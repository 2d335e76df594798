// AprilTags for the synthetic scene: the family's image drawn by libapriltag (Debian libapriltag-dev), hung on a
// wall of vpHSlamSyntheticScene with its exact pose.
#ifndef HSLAM_TEST_TAGS_H
#define HSLAM_TEST_TAGS_H

#include <visp3/core/vpColVector.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpMath.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#ifdef HSLAM_HAVE_APRILTAG_IMAGES
#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
#endif

namespace hslam_test
{
//! True when this build can draw tags (libapriltag was found).
inline bool canDrawTags()
{
#ifdef HSLAM_HAVE_APRILTAG_IMAGES
  return true;
#else
  return false;
#endif
}

#define HSLAM_REQUIRE_TAG_IMAGES()                                                                                     \
  do {                                                                                                                 \
    if (!hslam_test::canDrawTags()) {                                                                                  \
      GTEST_SKIP() << "libapriltag (Debian libapriltag-dev) not found at build time: no tag image to render";          \
    }                                                                                                                  \
  } while (0)

//! A tag36h11 tag as printed: one pixel per cell (10 x 10 with its white margin); empty when it cannot be drawn.
//! \e blackCells is set to the cells of its black square (8): the tag's size is that square's side.
inline vpImage<unsigned char> tag36h11Image(int id, int &blackCells)
{
  vpImage<unsigned char> I;
  blackCells = 0;
#ifdef HSLAM_HAVE_APRILTAG_IMAGES
  apriltag_family_t *family = tag36h11_create();
  image_u8_t *image = apriltag_to_image(family, id);
  I.resize(static_cast<unsigned int>(image->height), static_cast<unsigned int>(image->width));
  for (int y = 0; y < image->height; ++y) {
    for (int x = 0; x < image->width; ++x) {
      I[y][x] = image->buf[y * image->stride + x];
    }
  }
  blackCells = family->width_at_border;
  image_u8_destroy(image);
  tag36h11_destroy(family);
#else
  (void)id;
#endif
  return I;
}

/*!
  Hang tag36h11 number \e id on a wall of \e scene, centred at \e centre (world, metres), its black square \e size
  metres wide. Returns wMt, the tag frame of vpDetectorAprilTag::getPose() in the scene's world: the picture's frame
  (y down, z into the wall) turned half a turn about its x axis (ViSP's tag frame has y up and z out of the tag).
*/
inline vpHomogeneousMatrix hangTag36h11(vpHSlamSyntheticScene &scene, int id, const vpColVector &centre, double size)
{
  int blackCells = 0;
  const vpImage<unsigned char> tag = tag36h11Image(id, blackCells);
  const vpHomogeneousMatrix wMp = scene.addWallPicture(tag, centre, size * tag.getWidth() / blackCells);
  return wMp * vpHomogeneousMatrix(0., 0., 0., M_PI, 0., 0.);
}
} // namespace hslam_test

#endif
