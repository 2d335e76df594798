/*
 * H-SLAM for ViSP.
 */
//! \file EurocSource.h  EuRoC / TUM-VI ASL folder reader.
#ifndef HSLAM_IO_EUROC_SOURCE_H
#define HSLAM_IO_EUROC_SOURCE_H

#include "io/IndexedImageSource.h"

#include <memory>
#include <string>

namespace hslam
{
/*!
  Camera folder of an ASL dataset given the sequence folder, its mav0 folder or the cam0 folder itself (the one
  holding data.csv and data/); empty when \e path is none of these.
*/
std::string findEurocCameraFolder(const std::string &path);

/*!
  EuRoC / TUM-VI ASL reader: `cam0/data.csv` ("timestamp [ns],filename", '#' header), images in `cam0/data/`,
  calibration in `cam0/sensor.yaml` (or Options::cameraFile). Timestamps are the nanoseconds divided by 1e9.

  TUM-VI extras, optional: when the sequence folder (the parent of mav0) has `dso/cam0/times.txt`
  ("timestamp[ns] timestamp[s] exposure[ms]" per line), each frame gets the exposure of its nanosecond stamp;
  `dso/cam0/pcalib.txt` and `dso/cam0/vignette.png` give the photometric calibration.
*/
class EurocSource : public IndexedImageSource
{
public:
  EurocSource(const std::string &path, const vpHSlamImageSource::Options &options);
};
} // namespace hslam

#endif
