// A printed AprilTag as an image, to hang in the synthetic room (vpHSlamSyntheticScene::addWallTag): drawn by
// Debian's libapriltag (apriltag_to_image) when the build found it (HSLAM_HAVE_APRILTAG_IMAGES, target
// hslam_tag_images of cmake/HSlamTagImages.cmake). Header-only; used by tutorial-hslam-servo --tag and the tag tests.
#ifndef HSLAM_TUTORIAL_TAG_PICTURE_H
#define HSLAM_TUTORIAL_TAG_PICTURE_H

#include <visp3/core/vpImage.h>

#ifdef HSLAM_HAVE_APRILTAG_IMAGES
#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
#endif

namespace hslam_tag
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

/*!
  Tag36h11 number \e id as printed: one pixel per cell, with its white margin (10 x 10); empty when this build
  cannot draw tags. \e blackCells is set to the cells its black square spans (8): the tag's size is that square's
  side (vpDetectorAprilTag's convention).
*/
inline vpImage<unsigned char> tag36h11Image(int id, unsigned int &blackCells)
{
  vpImage<unsigned char> I;
  blackCells = 0;
#ifdef HSLAM_HAVE_APRILTAG_IMAGES
  apriltag_family_t *family = tag36h11_create();
  image_u8_t *image = apriltag_to_image(family, id);
  I.resize(static_cast<unsigned int>(image->height), static_cast<unsigned int>(image->width));
  for (int y = 0; y < image->height; ++y) {
    for (int x = 0; x < image->width; ++x) {
      I[static_cast<unsigned int>(y)][static_cast<unsigned int>(x)] = image->buf[y * image->stride + x];
    }
  }
  blackCells = static_cast<unsigned int>(family->width_at_border);
  image_u8_destroy(image);
  tag36h11_destroy(family);
#else
  (void)id;
#endif
  return I;
}
} // namespace hslam_tag

#endif
