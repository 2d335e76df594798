/*
 * H-SLAM for ViSP.
 */
/*!
  \file MapFile.h
  \brief H-SLAM's map file: the global map (keyframes kept lean, their points in inverse-depth form, the pose-pose
  edges) with the camera it was built with and the vocabulary it was indexed with. vpHSlam::saveMap / loadMap.

  Layout (little-endian, common/BinaryIo.h), version 3 (versions 1 and 2 are still read: 1 has observer ids without
  pixels, 1 and 2 no metric frame):
  \verbatim
  offset  bytes  field
  0       8      magic "HSLAMMAP"
  8       4      format version (3)
  12      4      descriptor bytes (32: 256-bit ORB)
  16      4+4    image width, height (rectified, pixels)
  24      4x8    fx, fy, cx, cy of the rectified pinhole camera the pixels and inverse depths refer to
  56      8      vocabulary id (OrbVocabulary::fingerprint(); 0: built without a vocabulary)
  64      4      keyframe count, then per keyframe:
                   id, frame id, segment (3 x i32), timestamp, exposure (2 x f64), cMw (qx qy qz qw tx ty tz: 7 x f64),
                   affine a, b (2 x f64), culled (u8), point count (u32), then per point:
                     u, v, idepth, idepth variance (4 x f32), ORB (32 bytes), ORB angle (f32),
                     flags (u8: 1 corner, 2 has ORB), state (u8: GlobalPointState), observer count (u32),
                     per observer: id (i32), the pixel it saw the point at (u, v: 2 x f32, NaN if unknown)
  ...     4      pose-pose edge count, then per edge:
                   from, to (2 x i32), toMfrom (7 x f64), information (36 x f64, row-major), consecutive (u8)
  ...     1      metric frame present (u8: 0 or 1; vpHSlam::setTag()), then if 1:
                   tag frame (u8), segment (i32), oMw (qx qy qz qw tx ty tz: 7 x f64), scale, scale uncertainty
                   (2 x f64): map points X of that segment are at scale oRw X + otw in metres
  end-8   8      checksum: hashBytes() of every byte before it
  \endverbatim
  Reading checks everything before anything is used: magic, version, descriptor size, checksum, counts against the
  bytes left, finite values in range (unit quaternions, positive inverse depths, pixels inside the image), unique
  keyframe ids (and ids and segments below 2^30), edges and observers naming keyframes of the file. Any failure is a
  vpHSlamException naming the file and the reason (parseError: corrupt, truncated; unsupported: another version or
  descriptor size).
*/
#ifndef HSLAM_MAP_MAP_FILE_H
#define HSLAM_MAP_MAP_FILE_H

#include "map/GlobalMap.h"

#include <visp3/core/vpConfig.h>

#include <cstdint>
#include <string>
#include <vector>

namespace hslam
{
//! The rectified camera a map's pixels and inverse depths refer to.
struct MapCamera {
  int width = 0, height = 0;
  double fx = 0., fy = 0., cx = 0., cy = 0.;
};

//! The metric frame a map was given by a tag (map/MetricFrame.h), as the file keeps it.
struct MapMetricFrame {
  bool present = false;
  bool tagFrame = false;        //!< the output frame is the tag's (else the map's axes, scaled)
  int segment = 0;              //!< map segment it was fitted in
  SE3d oMw;                     //!< rigid part of the similarity map -> output
  double scale = 1.;            //!< metres per map unit
  double scaleUncertainty = 1.; //!< relative standard deviation of scale
};

//! Everything a map file holds.
struct MapSnapshot {
  MapCamera camera;
  std::uint64_t vocabularyId = 0; //!< 0: built without a vocabulary
  std::vector<GlobalKeyframe> keyframes;
  std::vector<PosePoseEdge> edges;
  MapMetricFrame metric; //!< version 3; absent in older files
};

//! Current format version written by saveMapFile().
constexpr std::uint32_t kMapFileVersion = 3;
//! Oldest version loadMapFile() still reads.
constexpr std::uint32_t kOldestMapFileVersion = 1;

//! Write \e map to \e path atomically (a temporary file renamed over it). Throws vpHSlamException on I/O errors.
VISP_EXPORT void saveMapFile(const std::string &path, const MapSnapshot &map);
//! Read and check a map file (see the file comment for the errors).
VISP_EXPORT MapSnapshot loadMapFile(const std::string &path);
//! Same checks on bytes already in memory (\e path only names them in errors; the fuzz target uses this).
VISP_EXPORT MapSnapshot parseMapFile(const std::string &bytes, const std::string &path);
} // namespace hslam

#endif
