/*
 * H-SLAM for ViSP.
 */
//! \file ImageSequenceSource.h  Plain image folders and printf-numbered image files.
#ifndef HSLAM_IO_IMAGE_SEQUENCE_SOURCE_H
#define HSLAM_IO_IMAGE_SEQUENCE_SOURCE_H

#include "io/IndexedImageSource.h"

#include <string>
#include <vector>

namespace hslam
{
/*!
  Images without a list: either every image of a folder, sorted by name, or the files of a printf pattern
  ("seq/img_%04d.png": the first existing number in [0, 1000) opens the run, which ends at the first missing
  number). No timestamps: frame i (counted from the first image, before Options::startFrame) is at i / frameRate
  seconds, Options::frameRate in Hz. A camera file is required: Options::cameraFile, else camera.txt, camera.xml or
  camera.yaml beside the images.

  Files are read one by one with io::readGreyImage() (never through vpVideoReader, which skips unreadable frames).
*/
class ImageSequenceSource : public IndexedImageSource
{
public:
  ImageSequenceSource(const std::string &path, const vpHSlamImageSource::Options &options);
};

//! True when \e pattern holds exactly one integer conversion ("%d", "%04d", ...) and no other '%'.
VISP_EXPORT bool isImagePattern(const std::string &pattern);
/*!
  Files of a printf pattern: from the first existing number in [0, \e maxFirstIndex) up to the first gap. A file
  of the pattern numbered after the gap (a missing frame, whose followers would be dropped silently) is an error.
  \exception vpHSlamException::invalidArgument for a malformed pattern; vpHSlamException::fileNotFound naming the
  missing file and the first one after it when the numbering has a gap.
*/
VISP_EXPORT std::vector<std::string> expandImagePattern(const std::string &pattern, unsigned int maxFirstIndex = 1000);
} // namespace hslam

#endif
