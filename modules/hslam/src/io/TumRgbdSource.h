/*
 * H-SLAM for ViSP.
 */
//! \file TumRgbdSource.h  TUM RGB-D sequence reader (colour stream only).
#ifndef HSLAM_IO_TUM_RGBD_SOURCE_H
#define HSLAM_IO_TUM_RGBD_SOURCE_H

#include "io/IndexedImageSource.h"

#include <string>

namespace hslam
{
/*!
  TUM RGB-D reader: `rgb.txt` ("timestamp[s] filename" per line, '#' comments, file names relative to the
  folder), images converted to grey. The benchmark ships no calibration file: Options::cameraFile, else
  `camera.txt` (DSO) or `camera.xml` (ViSP) in the folder; none of them is an error naming what was looked for.

  H-SLAM extension of the layout (what tutorial-hslam-synthetic writes; all optional, absent from the benchmark's
  own folders): `pcalib.txt` and/or `vignette.png` in the folder are loaded as the photometric calibration (TUM
  monoVO formats, vignette of the camera's size), and `times.txt` ("id time[s] exposure[ms]" per line) gives the
  exposures. times.txt must list the frames of rgb.txt one by one in the same order: a different line count, a
  time differing by more than 1 us, or a numeric id differing from a numbered image name raises
  vpHSlamException::invalidTimestamps naming times.txt (and the line).
*/
class TumRgbdSource : public IndexedImageSource
{
public:
  TumRgbdSource(const std::string &path, const vpHSlamImageSource::Options &options);
};

/*!
  Camera file of a folder for formats without their own: Options::cameraFile, else the first of camera.txt,
  camera.xml, camera.yaml present in \e folder; empty when none.
*/
std::string findFolderCameraFile(const std::string &folder, const vpHSlamImageSource::Options &options);
} // namespace hslam

#endif
