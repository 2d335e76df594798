/*
 * H-SLAM for ViSP.
 */
/*!
  \file LocalMapper.h
  \brief The mapping back end: the conductor of the window (mapping/KeyframeWindow.h), the global map's upkeep
  (map/GlobalMapKeeper.h), the relocalisation index (tracking/RelocalizationIndex.h), the tracking reference
  (tracking/TrackingReference.h) and the loop closer (loop/LoopCloser.h).

  makeKeyframe() calls them in DSO's order (FullSystem::makeKeyFrame), then H-SLAM's: trace the window's immature
  points in the new frame, insert the keyframe (activation), optimise the window, build the tracking reference, drop
  points out of view, select new immature points, re-use stored points, marginalise the flagged keyframes (each is
  indexed for relocalisation, handed to the loop closer and stored in the global map), then look for a loop and
  apply its correction. makeNonKeyframe() only traces.

  Threading: not thread-safe. Owned by SlamSystem and used by one thread at a time (the mapping thread, or the
  caller in deterministic mode, under SlamSystem's mapper mutex); the loop closer's global bundle adjustment runs on
  its own thread in real time. Frames given to it are then owned by it; their poses (cMw) and brightness are
  written here.
*/
#ifndef HSLAM_SYSTEM_LOCAL_MAPPER_H
#define HSLAM_SYSTEM_LOCAL_MAPPER_H

#include "features/ImagePyramid.h"
#include "loop/LoopCloser.h"
#include "map/Frame.h"
#include "map/GlobalMap.h"
#include "map/GlobalMapKeeper.h"
#include "map/Keyframe.h"
#include "mapping/KeyframeWindow.h"
#include "math/SE3.h"
#include "math/Sim3.h"
#include "tracking/TrackingReference.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <atomic>
#include <chrono>
#include <map>
#include <memory>
#include <vector>

namespace hslam
{
class CoarseTracker;
class OrbVocabulary;
class RelocalizationIndex;
struct TwoViewInitialization;
struct RelocalizationKeyframe;
struct RelocalizationFrame;
struct WindowView;

class VISP_EXPORT LocalMapper
{
public:
  //! What the back end reports about a keyframe it holds (or just let go).
  struct KeyframeState {
    int id = -1;
    SE3d wMc;
    bool inWindow = true;
    unsigned int activePoints = 0;
    double scale = 1.; //!< loop correction: the keyframe's map was divided by this (frames tracked on it follow)
  };

  /*!
    \param vocabulary : when not null (hybrid / indirect tracking with relocalisation), keyframes are indexed for
    relocalisation (it must outlive the mapper).
  */
  LocalMapper(const vpHSlamParameters &params, const PinholeIntrinsics &K0, int width, int height,
              bool photometricCalibration, const OrbVocabulary *vocabulary = nullptr);
  ~LocalMapper();

  /*!
    Start a map from a two-view initialisation.
    \param first : the first frame (host of the initial points); its pose becomes \e wMfirst.
    \param second : the frame that initialised; its pose is wMfirst * (init.c2Mc1)^-1.
    \return false when too few points could be made (the caller keeps initialising).
  */
  bool initialize(const FramePtr &first, int firstKeyframeId, const FramePtr &second, int secondKeyframeId,
                  const TwoViewInitialization &init, const SE3d &wMfirst);

  /*!
    Make \e frame (pose cMw already set from its tracking reference) the newest keyframe.
    \param seedKeyframe : a stored keyframe a relocalisation placed the frame against (-1: none); its stored points
    and its neighbours' are searched for re-use whether or not they pass the usual overlap test, so that a window
    left without points is seeded again from the stored map.
  */
  void makeKeyframe(const FramePtr &frame, int keyframeId, int seedKeyframe = -1);
  //! Trace the immature points of the window in \e frame (pose already set).
  void makeNonKeyframe(const FramePtr &frame);

  /*!
    Set \e tracker's reference to the newest keyframe with every active point of the window expressed in it.
    \return false when the window is empty.
  */
  bool prepareTrackingReference(CoarseTracker &tracker, int &keyframeId, AffineBrightness &affine,
                                double &exposure) const;

  //! States of the window's keyframes and of those marginalised since the last call (then forgotten).
  void takeKeyframeStates(std::vector<KeyframeState> &states);
  //! World positions of the active points.
  void activePointsWorld(std::vector<Eigen::Vector3d> &points) const;

  int activePointCount() const;
  int immaturePointCount() const;
  //! Bytes held by the window's keyframes (pyramids, images, points); with marginalizedMemoryBytes(), all the map.
  double windowMemoryBytes() const;
  /*!
    Bytes held for keyframes that left the window: global map (points, graph), relocalisation index and loop closer.
    Counting walks every stored point, which grows with the map (8 % of hslam_many_laps' time at 5,700 stored
    keyframes when it ran at every keyframe): the bytes are counted again when the stored keyframes changed by 2 %
    since the last count (at every keyframe in a map of fewer than 50), or with \e exact; in between, the last
    count per stored keyframe times the stored keyframes.
  */
  double marginalizedMemoryBytes(bool exact = false);
  //! Keyframes whose data is held: the window's and those stored in the global map.
  int keyframesHeld() const { return static_cast<int>(m_window->size() + m_keeper.globalMap().keyframes().size()); }
  //! Pose of the newest keyframe (world-to-camera); identity when none.
  SE3d newestKeyframe_cMw() const;
  int newestKeyframeId() const;

  /*!
    True when the last window optimisation of one of the first keyframes had an RMSE too high for a correct
    initialisation (DSO's check on keyframes 2 to 4): the caller should start again.
  */
  bool initializationFailed() const { return m_window->initializationFailed(); }

  /*!
    A lost camera was relocalised into this segment's map (the relocalisation confirmed by the map's points): the
    window RMSE check of the first keyframes stops for the segment. The first keyframe after a cover is taken from
    far away and fits the window worse; that says the camera moved while lost, not that the initialisation was wrong,
    and failing it discarded every frame tracked before the cover (7-Scenes, frames 60-100 black, point budget 510:
    the 63 frames of the first keyframes dropped from the output).
  */
  void noteRelocalization();

  //! Drop the window (a new segment starts; the global map keeps the old segment's keyframes).
  void clear();

  // ---- global map (system.mode vo-reuse and slam)
  //! Counters of global-map re-use since the start.
  using ReuseStatistics = GlobalMapKeeper::Statistics;
  ReuseStatistics reuseStatistics() const;
  //! True when marginalised keyframes are kept (system.mode is not vo-strict).
  bool keepsGlobalMap() const;
  //! The same rule for a mode, before any mapper exists (the system decides from it what to load).
  static bool keepsGlobalMap(vpHSlamParameters::Mode mode) { return mode != vpHSlamParameters::modeVoStrict; }
  const GlobalMap &globalMap() const { return m_keeper.globalMap(); }
  // ---- loops (system.mode slam; loop/LoopCloser.h does the work)
  using LoopRecord = hslam::LoopRecord;
  using LoopStatistics = hslam::LoopStatistics;
  //! True while a loop correction runs (read by the tracking thread: tracking must not wait for it).
  bool correctingLoop() const { return m_correctingLoop.load(); }
  //! Loop counters since the start (or the last reset()); all zero without a loop closer.
  LoopStatistics loopStatistics() const;
  //! Bytes the loop closer holds (loop features and their database), counted in marginalizedMemoryBytes().
  double loopMemoryBytes() const;
  /*!
    Real time: write back a background global bundle adjustment that has ended (or wait for the running one when
    \e wait; the loop closer's thread then finishes its queued work first and its corrections are applied); true
    when something was written back (its keyframes' states are then to be taken).
  */
  bool collectGlobalBundleAdjustment(bool wait);
  /*!
    Landmarks seen in metres (the tag's sightings in the current segment, with the metric frame's scale): constraints
    of every correction's pose graph from now on. Nothing without a loop closer.
  */
  void setLandmarkSightings(LandmarkSightings landmarks);
  /*!
    A landmark seen from keyframe \e keyframe (in the window) was seen before from stored keyframes: the segment is
    corrected as after a loop, with the sightings as the measurement (deterministic: now; real time: on the loop
    closer's thread, applied at a later keyframe). True when a correction was applied now (its keyframes' states are
    then to be taken).
  */
  bool correctLandmarks(int keyframe);

  // ---- map files (vpHSlam::saveMap / loadMap)
  /*!
    The map as a file holds it: the global map's keyframes and edges, and the window's keyframes as if marginalised
    now (marginalised and active points, pose-pose edges from the window's last linearisation). Observers and edges
    naming keyframes that are not held (a window dropped when tracking was lost) are left out. The window is not
    changed.
  */
  void mapSnapshot(std::vector<GlobalKeyframe> &keyframes, std::vector<PosePoseEdge> &edges);
  /*!
    Make a loaded map the global map; only on an empty mapper (nothing tracked yet). Its keyframes keep their
    segments and the mapper's next segment comes after them, so re-use and loop detection (which stay within a
    segment) never mix the loaded map's coordinates with the new run's.
  */
  void restoreMap(std::vector<GlobalKeyframe> keyframes, std::vector<PosePoseEdge> edges);
  //! Drop everything, global map included (vpHSlam::reset()); clear() keeps the global map.
  void reset();

  //! Map points in world coordinates with their status: active window points and global ones (stored state).
  void mapPointsWorld(std::vector<Eigen::Vector3d> &points, std::vector<int> &status) const;

  // ---- relocalisation (only with a vocabulary)
  //! Memory the descriptors add to a keyframe (point descriptors, BoW vector, stored points), bytes; 0 without. The
  //! relocalisation index's share is that of the last count of marginalizedMemoryBytes().
  double descriptorBytesPerKeyframe() const;
  //! True when keyframes are indexed for relocalisation.
  bool indexesKeyframes() const;
  /*!
    Keyframes of the segment most similar to a lost frame (BoW), best first, with their points (world) and direct
    index; the frame's direct index is filled on the way.
  */
  std::vector<RelocalizationKeyframe> relocalizationCandidates(RelocalizationFrame &frame, int maxCandidates,
                                                               int preferred = -1) const;
  //! The window's keyframes (id, pose, frame with its raw image), oldest first: WindowRelocalization's input.
  std::vector<WindowView> windowViews() const;
  /*!
    Index every keyframe of the global map for relocalisation (localisation-only in a loaded map): BoW vector of its
    described points, corners with their world positions. False without a vocabulary.
  */
  bool indexGlobalMap();
  /*!
    Localisation-only: the stored points of keyframe \e id, of its neighbours in time and of its co-visible
    keyframes, in world coordinates (ReferenceFeature::Xref is the world position), with the ids of those keyframes.
  */
  void localMapFeatures(int id, std::vector<ReferenceFeature> &features, std::vector<int> &keyframeIds) const;
  /*!
    Localisation-only: the stored points of \e keyframeIds (any kind, with or without a descriptor) expressed in a
    camera at \e refMw, as a direct tracking reference (the inverse depths of a located frame from the map).
  */
  void localMapReference(const std::vector<int> &keyframeIds, const SE3d &refMw,
                         std::vector<CoarseTrackerPoint> &points) const;
  //! Of \e keyframeIds, the stored keyframe whose camera is closest to \e cMw (centre distance; -1 when none).
  int closestKeyframe(const SE3d &cMw, const std::vector<int> &keyframeIds) const;

private:
  //! Optimise, check, build the tracking reference, drop points out of view, new immature points, re-use,
  //! marginalise.
  void finishKeyframe(const KeyframePtr &kf, int seedKeyframe = -1);
  //! Keyframe \e id leaves the window: indexed for relocalisation, handed to the loop closer, stored.
  void marginalize(int id);
  //! Loop detection for the keyframes handed over (slam mode), and the correction of an accepted loop.
  void closeLoops();
  /*!
    Correct the stored keyframes of the segment after \e loop: the loop closer's pose graph (window fixed), then
    every stored keyframe's pose and its points' inverse depths (the map follows its host), its loop features, the
    relocalisation index and the reported trajectory. Returns false when the optimisation failed (nothing changed).
  */
  bool correctLoop(const DetectedLoop &loop);
  //! Deterministic: solve \e correction (a loop's or a landmark's) in this thread and apply it; false when it failed.
  bool solveAndApply(LoopCloser::Correction &correction);
  /*!
    Apply a solved correction (a loop's or a landmark's): every stored keyframe of its solution moves (pose, points),
    the trajectory follows, a global bundle adjustment may start. \e t0: when the correction started here; its
    solveMs: time the loop closer's thread spent on it.
  */
  void applyCorrection(const LoopCloser::Correction &correction, std::chrono::steady_clock::time_point t0);
  //! Real time: apply the corrections the loop closer's thread solved (with \e wait, after its queued work).
  bool applySolvedCorrections(bool wait);
  //! A stored keyframe moved: report its pose (and the scale of the move) and refresh its relocalisation points.
  void publishStoredKeyframe(int id, double scale);
  //! After a correction: the global bundle adjustment (loop.globalBundleAdjustment), in order when deterministic,
  //! else in the background (collected by collectGlobalBundleAdjustment() at a later keyframe).
  void startGlobalBundleAdjustment();
  void finishGlobalBundleAdjustment(const GlobalBundleJob &job);
  //! The window's refinement of re-used points, as the global map's upkeep asks for it.
  ReuseRefinement reuseRefinement() const;
  std::map<int, SE3d> windowPoses() const;
  //! The per-segment components, fresh (a new segment shares nothing with the old one).
  void makeSegmentComponents();

  vpHSlamParameters m_params;
  PinholeIntrinsics m_K0;
  int m_width, m_height;
  bool m_photometricCalibration;
  const OrbVocabulary *m_vocabulary; //!< null: no relocalisation index, no loop closer
  std::unique_ptr<KeyframeWindow> m_window;
  TrackingReference m_reference;
  std::unique_ptr<RelocalizationIndex> m_relocalization; //!< null without a vocabulary
  GlobalMapKeeper m_keeper;                              //!< outlives segments (clear() keeps it)
  //! Loop closure (slam mode with a vocabulary). clear() empties it (loops stay within a segment); its statistics
  //! count the whole run until reset().
  std::unique_ptr<LoopCloser> m_loop;
  std::vector<KeyframeState> m_marginalizedStates;     //!< keyframes that left since the last report
  double m_countedMarginalizedBytes = 0.;              //!< marginalizedMemoryBytes() at its last count
  size_t m_countedStoredKeyframes = 0;                 //!< stored keyframes at that count
  double m_countedRelocalizationBytesPerKeyframe = 0.; //!< the relocalisation index per keyframe at that count
  bool m_marginalizedCounted = false;
  std::atomic<bool> m_correctingLoop{false};
};
} // namespace hslam

#endif
