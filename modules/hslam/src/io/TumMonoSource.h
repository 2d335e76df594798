/*
 * H-SLAM for ViSP.
 */
//! \file TumMonoSource.h  TUM monoVO sequence reader.
#ifndef HSLAM_IO_TUM_MONO_SOURCE_H
#define HSLAM_IO_TUM_MONO_SOURCE_H

#include "io/IndexedImageSource.h"

#include <string>

namespace hslam
{
/*!
  TUM monoVO reader (Engel et al. 2016 layout): `images/` (sorted by name), `times.txt` ("id time[s]
  [exposure[ms]]" per line, one per image, same order), `camera.txt` (DSO format, or Options::cameraFile), and the
  optional photometric calibration `pcalib.txt` + `vignette.png`.

  `images.zip` alone is not read (no zip library among the module's dependencies): vpHSlamException::unsupported
  asks to unzip it into images/. A different count of images and times.txt lines, or an id that disagrees with
  the numbered image name, raises vpHSlamException::invalidTimestamps.
*/
class TumMonoSource : public IndexedImageSource
{
public:
  TumMonoSource(const std::string &path, const vpHSlamImageSource::Options &options);
};
} // namespace hslam

#endif
