/*
 * H-SLAM for ViSP.
 */
//! \file KittiSource.h  KITTI odometry sequence reader (left grey camera).
#ifndef HSLAM_IO_KITTI_SOURCE_H
#define HSLAM_IO_KITTI_SOURCE_H

#include "io/IndexedImageSource.h"

#include <string>

namespace hslam
{
/*!
  KITTI odometry reader: `times.txt` (one time in seconds per line), `image_0/NNNNNN.png` (frame i is the
  zero-padded six-digit i, as the benchmark names them), `calib.txt` (its P0 line, or Options::cameraFile). The
  image size, absent from calib.txt, is read from the first image. Every listed image must exist and image_0/
  must hold exactly as many images as times.txt has lines.
*/
class KittiSource : public IndexedImageSource
{
public:
  KittiSource(const std::string &path, const vpHSlamImageSource::Options &options);
};
} // namespace hslam

#endif
