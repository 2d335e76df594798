/*
 * H-SLAM for ViSP.
 */
/*!
  \file SlamSystem.h
  \brief The system behind vpHSlam: front end (preprocessing, initialisation, direct tracking, keyframe decision),
  hand-over to the back end (LocalMapper) in the caller's thread or a mapping thread, trajectory and statistics.

  Flow per frame (DSO FullSystem::addActiveFrame / deliverTrackedFrame, with a two-view initializer):
  1. FramePreprocessor: rectify, photometric correction, pyramid.
  2. Not initialised: TwoViewInitializer on the rectified 8-bit image; on success LocalMapper::initialize() makes
     the first two keyframes (synchronously: nothing else to do then) and the first tracking reference.
  3. Initialised: swap in the newest tracking reference if the mapper prepared one, track against it with motion
     hypotheses (CoarseTracker::trackWithHypotheses), record the pose relative to the reference keyframe, decide
     whether the frame becomes a keyframe (DSO's flow / brightness / residual rule).
  Frames seen between the two initial keyframes are tracked backwards against the new map once it exists, so
     the trajectory covers the sequence from its first frame (kept as raw images meanwhile, at most
     Initializer::maxFramesToInitialize of them).
  4. Deliver: deterministic mode maps at once (makeKeyframe or makeNonKeyframe); real-time mode queues the frame
     for the mapping thread (DSO mappingLoop): when frames pile up, non-keyframes are only traced or skipped, and
     a pending keyframe request is served by the newest frame.

  Threading and ownership:
  - tracking thread (the caller of track()): owns the preprocessor, the initializer, the active CoarseTracker,
    the motion history.
  - mapping thread (real time) or the caller (deterministic): owns the LocalMapper (window, points) and the spare
    CoarseTracker it prepares for the tracking thread. m_mapperMutex is held while a job runs, so reset() and
    initialisation (caller's thread) never run concurrently with a job.
  - shared: the TrajectoryRecorder and RunStatistics (own mutexes), the job queue (m_queueMutex), the prepared
    tracking reference (m_referenceMutex; the tracking thread only try-locks it, so it never waits), the display
    snapshot (m_snapshotMutex).
*/
#ifndef HSLAM_SYSTEM_SLAM_SYSTEM_H
#define HSLAM_SYSTEM_SLAM_SYSTEM_H

#include "map/Frame.h"
#include "map/MapFile.h"
#include "math/SE3.h"
#include "system/FramePreprocessor.h"
#include "system/LocalMapper.h"
#include "system/RunStatistics.h"
#include "system/TrajectoryRecorder.h"
#include "tracking/CoarseTracker.h"
#include "tracking/HybridTracker.h"
#include "tracking/WindowRelocalization.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamVocabulary.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace hslam
{
// LocalMapper: included for LocalMapper::ReuseStatistics in the snapshot.
class TwoViewInitializer;
struct RelocalizationResult;

class VISP_EXPORT SlamSystem
{
public:
  SlamSystem(const vpHSlamCamera &camera, const vpHSlamParameters &parameters,
             const vpHSlamPhotometricCalibration &photometric);
  ~SlamSystem();
  SlamSystem(const SlamSystem &) = delete;
  SlamSystem &operator=(const SlamSystem &) = delete;

  vpHSlam::State track(const vpImage<unsigned char> &I, double timestamp, double exposure);

  vpHSlam::State state() const { return m_state.load(); }
  vpHomogeneousMatrix get_cMw() const;
  bool hasPose() const;
  std::vector<vpHSlam::Keyframe> keyframes() const;
  std::vector<vpColVector> activePoints(std::vector<double> *depths) const;
  std::vector<vpImagePoint> descriptorMatches() const;
  std::vector<vpHSlam::MapPoint> mapPoints() const;
  std::vector<vpHSlam::GraphEdge> graphEdges() const;
  vpHSlamTrajectory trajectory(int segment) const { return m_recorder.trajectory(segment); }
  vpHSlamTrajectory keyframeTrajectory(int segment) const { return m_recorder.keyframeTrajectory(segment); }
  std::vector<unsigned int> trajectorySegments() const { return m_recorder.frameSegments(); }
  vpHSlam::Statistics statistics() const;
  void synchronize();
  //! synchronize(), then wait for a global bundle adjustment running in the background and write it back.
  void finishBackgroundWork();
  void reset();
  void saveMap(const std::string &path);
  void loadMap(const std::string &path);

  const FramePreprocessor &preprocessor() const { return m_preprocessor; }
  void rectifiedImage(vpImage<unsigned char> &I) const;
  const vpHSlamParameters &parameters() const { return m_params; }

private:
  //! localisation-only: the frame placed in the loaded map by relocalisation against its keyframes (no map change).
  vpHSlam::State localizeInLoadedMap(const FramePtr &frame);
  /*!
    Localisation-only: refine \e cMw by the photometric alignment against the last located frame (pose \e wMlast),
    whose inverse depths come from the stored points, jointly with the reprojection error of \e matches (the
    indirect step's inliers, world coordinates; null: photometric only). False (cMw unchanged) without a last
    located frame or when the alignment fails.
  */
  bool refineInLoadedMap(const FramePtr &frame, const SE3d &wMlast, const GeometricTerm *matches, SE3d &cMw);
  /*!
    Localisation-only: whether the points around the keyframe of \e r's near miss (a PnP pose on too few inliers),
    matched by projection from that pose, place the frame with twice tracking.relocalizationMinInliers inliers,
    within a frame's motion of that pose and without the search's prediction-free recovery; then \e cMw and
    \e inliers are theirs. The local map gathered for that keyframe replaces the one held (m_localMapFeatures).
  */
  bool confirmInLoadedMap(const RelocalizationResult &r, SE3d &cMw, int &inliers);
  //! The rectified camera, as map files record it.
  MapCamera mapCamera() const;
  //! Throws when the mode keeps no global map (vo-strict): \e operation names the call in the message.
  void requireGlobalMap(const std::string &path, const char *operation) const;

  //! A tracked frame handed to mapping.
  struct MappingJob {
    FramePtr frame;
    int referenceKeyframe = -1; //!< keyframe id the frame was tracked against
    SE3d refMc;                 //!< its pose relative to that keyframe
    bool needKeyframe = false;
    int seedKeyframe = -1;    //!< the frame seeds an emptied window: stored keyframe it was relocalised against
    bool relocalized = false; //!< the frame was relocalised into the map (LocalMapper::noteRelocalization())
  };

  //! Not initialised yet: one two-view attempt (SlamSystemInitialization.cpp, like the backfill below).
  vpHSlam::State initialize(const FramePtr &frame, const vpImage<unsigned char> &I, double exposure);
  //! After initialisation: give poses to the frames between the two initial keyframes (tracked backwards).
  void backfillInitializationFrames(const SE3d &c2Mc1, int firstFrameId, int secondFrameId);
  vpHSlam::State trackInitialized(const FramePtr &frame);
  /*!
    Pose of \e frame against the current reference: direct (DSO hypotheses), indirect (ORB matches, pose-only) or
    hybrid (indirect step, then the joint optimisation seeded by it), per Tracking::mode.
  */
  bool estimatePose(const FramePtr &frame, CoarseMotionHistory history, SE3d &newMref, AffineBrightness &affine,
                    CoarseTrackingResult &result);
  /*!
    Relocalisation of a lost frame (SlamSystemRelocalization.cpp): BoW candidates, ORB matching, PnP RANSAC and
    pose-only refinement; on success \e history holds the pose (no motion) for the joint refinement that follows.
    \e described: the frame had features to match (false for a black frame).
  */
  bool relocalizePose(const FramePtr &frame, CoarseMotionHistory &history, bool &described);
  /*!
    Place recognition for \e frame (described as \e features): the bag-of-words candidates of the map (\e preferred
    first when it is one), ORB matching and PnP RANSAC with tracking.relocalizationMinInliers; logged at debug level.
  */
  RelocalizationResult relocalizeByPlaceRecognition(const FramePtr &frame, RelocalizationFrame &features,
                                                    int preferred = -1);
  //! Keep \e r (a bag-of-words relocalisation of \e frame) as m_storedMapFix and say whether it agrees with the
  //! previous frame's.
  void recordStoredMapFix(const FramePtr &frame, const RelocalizationResult &r);
  /*!
    Whether a lost frame's alignment (\e aligned, pose \e cMwAligned) holds against the map: enough ORB inliers of
    the indirect step, or enough of the relocalisation's own matches within reach (see the implementation).
    \e attempt is appended to the debug message.
  */
  bool relocalizationConfirmed(const FramePtr &frame, bool aligned, const SE3d &cMwAligned,
                               const CoarseTrackingResult &result, const char *attempt) const;
  /*!
    Steps of the last two tracked frames' motion from the last one to frame \e frameId (frame ids count the frames
    given, black ones included), for continueMotion(); 0 without two tracked frames.
  */
  double lostSteps(int frameId) const;
  void adoptPreparedReference();
  bool keyframeNeeded(const FramePtr &frame, const CoarseTrackingResult &result);
  void deliver(MappingJob job);
  //! Tracking is lost (or, with \e discardSegment, the segment's initialisation proved wrong): start a new segment.
  void declareLost(bool discardSegment = false);
  //! Forgets the prepared tracking reference and empties the published map snapshot (after the map was cleared).
  void dropPreparedReferenceAndSnapshot();

  // Back end (caller's thread in deterministic mode, mapping thread otherwise), with m_mapperMutex held.
  //! Map one tracked frame; returns the thread CPU time it took, milliseconds.
  double runJob(const MappingJob &job);
  void publishAfterKeyframe();
  void mappingLoop();
  void stopMappingThread();
  void startMappingThread();

  vpHSlamParameters m_params;
  FramePreprocessor m_preprocessor;
  TrajectoryRecorder m_recorder;
  RunStatistics m_runStats;

  // ---- tracking thread state
  std::unique_ptr<TwoViewInitializer> m_initializer;
  FramePtr m_initFirstFrame; //!< the initializer's current first frame
  //! A frame seen while initialising, kept as its raw input (cheap) to be tracked once the map exists.
  struct PendingFrame {
    vpImage<unsigned char> I;
    double timestamp = 0.;
    double exposure = -1.;
    int id = -1;
  };
  //! Frames after m_initFirstFrame, oldest first. A deque: the oldest leaves by pop_front, never by moving the others
  //! (a vector's erase assigns vpImages, and ViSP 3.5's vpImage assignment leaked their buffers: LeakSanitizer).
  std::deque<PendingFrame> m_pendingFrames;
  std::unique_ptr<CoarseTracker> m_backfillTracker;
  std::unique_ptr<HybridTracker> m_hybrid;                      //!< keypoints and indirect step (null in direct mode)
  std::unique_ptr<WindowRelocalization> m_windowRelocalization; //!< with m_hybrid: the window's triangulated ORB
  //! Matches of the last relocalisation that found a pose (world point, pixel): they can confirm the aligned pose.
  std::vector<ReprojectionObservation> m_relocalizationEvidence;
  //! A lost frame placed by bag-of-words + PnP in the stored map (SlamSystemRelocalization.cpp): two consecutive
  //! ones that agree may seed an emptied window again.
  struct StoredMapFix {
    int frameId = -1;
    SE3d cMw;
    int keyframeId = -1;             //!< the stored keyframe PnP placed it against
    bool agreesWithPrevious = false; //!< the previous frame had a fix too, and the two agree (compareFixes)
  };
  StoredMapFix m_storedMapFix; //!< the last lost frame's fix (frameId -1: none)
  //! Relocalised where the camera's motion continued (checkContinuedMotion()): that motion per frame
  //! (last_M_prelast), the velocity of the frame after it. Empty otherwise.
  std::optional<SE3d> m_continuedMotion;
  IndirectStepResult m_indirect; //!< the current frame's indirect step (its term is used by m_tracker)
  std::unique_ptr<CoarseTracker> m_tracker;
  int m_trackerRefKeyframe = -1;       //!< keyframe id of m_tracker's reference
  AffineBrightness m_trackerRefAffine; //!< brightness of the reference when it was set
  double m_trackerRefExposure = 1.;
  AffineBrightness m_lastAffine; //!< (a, b) of the last tracked frame
  int m_framesSinceKeyframeRequest = 0;
  int m_forcedKeyframes = 0; //!< frames still made keyframes whatever their flow (after a relocalisation)
  int m_consecutiveFailures = 0;
  bool m_localizationReady = false; //!< localisation-only: a map is loaded and indexed
  int m_localizedKeyframe = -1;     //!< localisation-only: keyframe that placed the last located frame
  int m_localMapKeyframe = -1;      //!< localisation-only: keyframe m_localMapFeatures were gathered around
  std::vector<ReferenceFeature> m_localMapFeatures;     //!< its stored points and its neighbours', world coordinates
  std::vector<int> m_localMapKeyframes;                 //!< the keyframes they come from
  FramePtr m_localizedFrame;                            //!< localisation-only: the last located frame (its image)
  std::unique_ptr<CoarseTracker> m_localizationTracker; //!< localisation-only: joint refinement against it
  bool m_relocalizing = false; //!< tracking failed: lost frames try relocalisation until it works or times out
  double m_lostSince = 0.;     //!< timestamp of the first frame of the current relocalisation attempt, seconds
  bool m_initialized = false;
  unsigned int m_segment = 0;
  SE3d m_segmentOrigin;                          //!< wMc given to the first keyframe of the current segment
  int m_lastFrameId = -1, m_prelastFrameId = -1; //!< last two frames with a pose in this segment
  int m_nextFrameId = 0;
  double m_frameStartMs = 0.; //!< wall clock at the start of the current track() call, milliseconds
  double m_lastTimestamp = 0.;
  std::atomic<vpHSlam::State> m_state{vpHSlam::stateInitializing};
  std::atomic<unsigned int> m_frames{0}, m_trackedFrames{0}, m_lostFrames{0}, m_mappingSkipped{0};
  std::atomic<int> m_keyframeCount{0}; //!< keyframe ids handed out (the next id)
  mutable std::mutex m_imageMutex;
  vpImage<unsigned char> m_lastImage;             //!< rectified raw image of the last frame (display)
  std::vector<vpImagePoint> m_lastMatches;        //!< descriptor-matched inlier pixels of the last frame (display)
  std::atomic<unsigned int> m_segmentsStarted{0}; //!< segments that got a map (successful initialisations)
  std::atomic<unsigned int> m_relocAttempts{0}, m_relocSuccesses{0};
  std::unique_ptr<vpHSlamVocabulary> m_vocabulary; //!< loaded for relocalisation (hybrid / indirect), else null
  std::atomic<bool> m_restartRequested{false};     //!< set by the back end when the initialisation looks wrong

  // ---- back end
  std::unique_ptr<LocalMapper> m_mapper;
  mutable std::mutex m_mapperMutex;
  std::unique_ptr<CoarseTracker> m_preparedTracker; //!< filled by the back end, swapped by the tracking thread
  int m_preparedRefKeyframe = -1;
  AffineBrightness m_preparedRefAffine;
  double m_preparedRefExposure = 1.;
  bool m_preparedReady = false;
  std::mutex m_referenceMutex;

  // ---- real-time mapping thread
  std::thread m_mappingThread;
  std::deque<MappingJob> m_queue;
  std::mutex m_queueMutex;
  std::condition_variable m_queueChanged; //!< a job was queued, or stop was requested
  std::condition_variable m_jobDone;      //!< the mapping thread finished a job
  bool m_stopMapping = false;
  bool m_mappingBusy = false;
  int m_pendingKeyframeRef = -1;        //!< newest reference keyframe of a frame that asked for a keyframe, -1: none
  int m_pendingSeedKeyframe = -1;       //!< a queued frame seeds the window from this stored keyframe (see MappingJob)
  bool m_pendingRelocalization = false; //!< a queued frame was relocalised (see MappingJob)

  // ---- CPU profile (thread CPU time, ms), logged at debug level when the system is destroyed
  double m_cpuPreprocess = 0., m_cpuInitialize = 0., m_cpuTrack = 0.; //!< tracking thread
  double m_cpuMapKeyframes = 0., m_cpuMapFrames = 0.;                 //!< back end (under m_mapperMutex)
  double m_cpuLastJob = 0.; //!< deterministic mode: CPU of this frame's back-end job (excluded from tracking)

  // ---- display snapshot
  mutable std::mutex m_snapshotMutex;
  std::vector<Eigen::Vector3d> m_snapshotPoints; //!< active points, world
  unsigned int m_snapshotImmature = 0;
  double m_snapshotMemoryMb = 0.;
  unsigned int m_snapshotKeyframesHeld = 0;
  double m_snapshotDescriptorKb = 0.;
  double m_snapshotMarginalizedMb = 0.;            //!< memory held for keyframes that left the window
  LocalMapper::ReuseStatistics m_snapshotReuse;    //!< global map counters
  LocalMapper::LoopStatistics m_snapshotLoopStats; //!< loops (slam mode)
};
} // namespace hslam

#endif
