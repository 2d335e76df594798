/*
 * H-SLAM for ViSP.
 */
// Map files (SlamSystem): vpHSlam::saveMap / loadMap. The format is map/MapFile.h; what goes into it is
// LocalMapper::mapSnapshot.
#include "system/SlamSystem.h"

#include "features/OrbVocabulary.h"
#include "map/MapFile.h"
#include "system/LocalMapper.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>
#include <visp3/hslam/vpHSlamVocabulary.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hslam
{
namespace
{
//! Relative tolerance on the intrinsics a loaded map must share with the system (both went through a text file).
constexpr double kIntrinsicsTolerance = 1e-6;

bool close(double a, double b)
{
  return std::fabs(a - b) <= kIntrinsicsTolerance * std::max(1., std::fabs(a));
}

std::string describe(const MapCamera &c)
{
  char text[160];
  std::snprintf(text, sizeof(text), "%dx%d, fx %.6g fy %.6g cx %.6g cy %.6g", c.width, c.height, c.fx, c.fy, c.cx,
                c.cy);
  return text;
}

std::string hex(std::uint64_t id)
{
  char text[24];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(id));
  return text;
}
} // namespace

MapCamera SlamSystem::mapCamera() const
{
  MapCamera c;
  c.width = m_preprocessor.width();
  c.height = m_preprocessor.height();
  c.fx = m_preprocessor.intrinsics().fx;
  c.fy = m_preprocessor.intrinsics().fy;
  c.cx = m_preprocessor.intrinsics().cx;
  c.cy = m_preprocessor.intrinsics().cy;
  return c;
}

void SlamSystem::requireGlobalMap(const std::string &path, const char *operation) const
{
  if (m_params.system.mode == vpHSlamParameters::modeVoStrict && !m_params.system.localizationOnly) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           path + ": " + operation +
                               " needs system.mode vo-reuse or slam (vo-strict discards the keyframes that leave the "
                               "window, so there is no map to keep)");
  }
}

void SlamSystem::saveMap(const std::string &path)
{
  requireGlobalMap(path, "saveMap");
  finishBackgroundWork(); // the map as the background bundle adjustment leaves it
  MapSnapshot map;
  map.camera = mapCamera();
  map.vocabularyId = m_vocabulary ? m_vocabulary->impl().fingerprint() : 0;
  {
    std::lock_guard<std::mutex> lock(m_mapperMutex);
    m_mapper->mapSnapshot(map.keyframes, map.edges);
  }
  if (map.keyframes.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, path + ": no map to save yet (no keyframe)");
  }
  saveMapFile(path, map);
  VP_HSLAM_LOG(vpHSlamLog::info, "map saved to " << path << ": " << map.keyframes.size() << " keyframes, "
                                                 << map.edges.size() << " pose-pose edges");
}

void SlamSystem::loadMap(const std::string &path)
{
  requireGlobalMap(path, "loadMap");
  if (m_frames.load() > 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           path + ": loadMap comes before the first frame (or after reset())");
  }
  MapSnapshot map = loadMapFile(path);
  const MapCamera mine = mapCamera();
  if (map.camera.width != mine.width || map.camera.height != mine.height || !close(map.camera.fx, mine.fx) ||
      !close(map.camera.fy, mine.fy) || !close(map.camera.cx, mine.cx) || !close(map.camera.cy, mine.cy)) {
    throw vpHSlamException(vpHSlamException::invalidCalibration,
                           path + ": the map was built with another camera (" + describe(map.camera) +
                               ") than this system's rectified camera (" + describe(mine) + ")");
  }
  if (map.vocabularyId != 0 && m_vocabulary && map.vocabularyId != m_vocabulary->impl().fingerprint()) {
    throw vpHSlamException(vpHSlamException::unsupported, path + ": the map was indexed with vocabulary " +
                                                              hex(map.vocabularyId) + ", this system uses vocabulary " +
                                                              hex(m_vocabulary->impl().fingerprint()) +
                                                              " (HSLAM_VOCABULARY or the shipped default)");
  }
  int lastId = -1;
  for (const GlobalKeyframe &kf : map.keyframes) {
    lastId = std::max(lastId, kf.id);
  }
  const size_t keyframes = map.keyframes.size();
  {
    std::lock_guard<std::mutex> lock(m_mapperMutex);
    m_mapper->restoreMap(std::move(map.keyframes), std::move(map.edges));
    // Localisation-only searches the loaded keyframes; otherwise they stay out of the relocalisation index, which
    // holds the current segment's keyframes only (their coordinates are not the loaded map's).
    if (m_params.system.localizationOnly && !m_mapper->indexGlobalMap()) {
      throw vpHSlamException(vpHSlamException::unsupported,
                             path + ": system.localizationOnly needs a vocabulary (none found: set HSLAM_VOCABULARY)");
    }
  }
  m_localizationReady = m_params.system.localizationOnly;
  m_localizedKeyframe = -1;
  m_localMapKeyframe = -1; // gathered from the previous map
  // New keyframes are numbered after the loaded ones: ids stay unique in the global map and in a saved map.
  m_keyframeCount = std::max(m_keyframeCount.load(), lastId + 1);
  m_recorder.setFirstKeyframeId(m_keyframeCount.load());
  VP_HSLAM_LOG(vpHSlamLog::info, "map loaded from " << path << ": " << keyframes << " keyframes");
}
} // namespace hslam
