/*
 * H-SLAM for ViSP.
 */
/*!
  \file RelocalizationIndex.h
  \brief What relocalisation searches: the keyframes of the current map segment by bag of words, and the map
  points (world position + ORB descriptor) of those that left the window.

  The mapper adds each new keyframe with the descriptors of the points it selected (BoW vector into a
  KeyframeDatabase), and stores a snapshot of a keyframe's points when the keyframe is marginalised (their estimate
  is final then). Points of keyframes still in the window are taken from the window at query time (their estimate
  still moves). A lost frame's BoW vector queries the database; candidates come best first.
  A new map segment clears the index: relocalisation is into the same map.

  Threading: not thread-safe; owned by the mapper and used under the system's mapper mutex.
*/
#ifndef HSLAM_TRACKING_RELOCALIZATION_INDEX_H
#define HSLAM_TRACKING_RELOCALIZATION_INDEX_H

#include "features/ImagePyramid.h"
#include "features/OrbVocabulary.h"
#include "loop/KeyframeDatabase.h"
#include "map/GlobalMap.h"
#include "map/Keyframe.h"
#include "tracking/Relocalizer.h"

#include <visp3/core/vpConfig.h>

#include <map>
#include <memory>
#include <vector>

namespace hslam
{
/*!
  The relocalisation index of the current map segment.

  What it owns: the bag-of-words database of the segment's keyframes and the final described corners (world
  coordinates) of those that left the window.

  What it is given: each new window keyframe (addKeyframe(): its selected points' descriptors), each keyframe leaving
  the window (storeKeyframe()), culled keyframes (removeKeyframe()), stored keyframes a loop correction moved
  (refreshKeyframe()), or a whole loaded map (indexGlobalMap()).

  What it hands back: the keyframes most like a lost frame, each with its points and its neighbours' in world
  coordinates and their direct index (candidatesFor()), which the relocaliser matches and solves PnP with.
*/
class VISP_EXPORT RelocalizationIndex
{
public:
  //! Levels above the leaves at which the direct index groups features (ORB-SLAM2: 4 with L = 6).
  static constexpr int kDirectIndexLevelsUp = 4;

  //! \e vocabulary must outlive the index (the system owns it); \e K0: the keyframes' level-0 intrinsics.
  RelocalizationIndex(const OrbVocabulary &vocabulary, const PinholeIntrinsics &K0);

  // ---- keyframes as the mapper has them
  //! A new window keyframe: its BoW vector from every selected point's descriptor.
  void addKeyframe(const Keyframe &kf);
  //! A keyframe leaving the window: its final described corners in world coordinates.
  void storeKeyframe(const Keyframe &kf);
  //! A stored keyframe moved (loop correction): its points again from \e g (kept only when it had points).
  void refreshKeyframe(const GlobalKeyframe &g);
  //! Every keyframe of \e map (localisation-only in a loaded map): BoW vector of its described points, corners.
  void indexGlobalMap(const GlobalMap &map);
  /*!
    Keyframes most similar to a lost frame (BoW), best first (\e preferred first when given), each with its points
    and those of its neighbours in time (from \e window while they are in it) in world coordinates and with their
    direct index; the frame's direct index is filled on the way.
  */
  std::vector<RelocalizationKeyframe> candidatesFor(RelocalizationFrame &frame, int maxCandidates, int preferred,
                                                    const std::vector<KeyframePtr> &window) const;

  // ---- by id

  //! A new keyframe, with the descriptors of its selected points.
  void addKeyframe(int id, const std::vector<OrbDescriptor> &descriptors);
  //! Final points of a marginalised keyframe (world positions and descriptors).
  void setKeyframePoints(int id, std::vector<Eigen::Vector3d> wX, std::vector<OrbDescriptor> descriptors);
  //! Stored points of a keyframe (false when it has none yet: still in the window).
  bool keyframePoints(int id, RelocalizationKeyframe &out) const;
  //! Fill \e keyframe.direct from its descriptors.
  void index(RelocalizationKeyframe &keyframe) const;
  //! BoW vector and direct index of a lost frame's keypoints.
  void describeFrame(RelocalizationFrame &frame, BowVector &bow) const;
  //! Keyframe ids best first, at most \e maxCandidates.
  std::vector<int> candidates(const BowVector &bow, int maxCandidates) const;

  //! The keyframe database itself (loop detection queries it with its own rules).
  const KeyframeDatabase &database() const { return m_database; }
  //! A culled keyframe leaves the database (no candidate any more) with its stored points.
  void removeKeyframe(int id);
  void clear();
  std::size_t size() const { return m_database.size(); }
  //! Bytes held on the heap (database and stored points), allocator overhead included.
  double memoryBytes() const;

private:
  //! Corners of \e kf with a descriptor and an inverse depth, in world coordinates.
  void keyframePointsWorld(const Keyframe &kf, RelocalizationKeyframe &out) const;

  const OrbVocabulary &m_vocabulary;
  PinholeIntrinsics m_K0;
  KeyframeDatabase m_database;
  std::map<int, RelocalizationKeyframe> m_points;
};
} // namespace hslam

#endif
