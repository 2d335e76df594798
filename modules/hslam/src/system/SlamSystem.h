/*
 * H-SLAM for ViSP.
 */
/*!
  \file SlamSystem.h
  \brief The conductor behind vpHSlam: it owns the components and the threads, and calls the components in order.
  It holds no algorithm of its own.

  Flow per frame (DSO FullSystem::addActiveFrame / deliverTrackedFrame):
  1. FramePreprocessor: rectify, photometric correction, pyramid.
  2. Localisation-only: MapLocalizer places the frame in the loaded map; nothing else runs.
  3. No map yet (new segment): MonocularInitializer makes a two-view attempt; on success LocalMapper::initialize()
     makes the first two keyframes (synchronously: nothing else to do then), the first tracking reference is adopted,
     and the frames seen meanwhile are tracked backwards (MonocularInitializer::backfill()).
  4. Initialised: the newest tracking reference the back end prepared is swapped in (FrameTracker), then
     TrackingStateMachine tracks the frame (FrameTracker, LostFrameRelocalizer) and says whether it is tracked, lost
     or ends the segment (declareLost()).
  5. Deliver a tracked frame: deterministic mode maps at once (LocalMapper::makeKeyframe or makeNonKeyframe);
     real-time mode queues it for the mapping thread (DSO mappingLoop): when frames pile up, non-keyframes are only
     traced or skipped, and a pending keyframe request is served by the newest frame.

  Components (tracking/ unless said): FramePreprocessor (system/), MonocularInitializer, FrameTracker, the
  HybridTracker they share (keypoints, indirect step), LostFrameRelocalizer, TrackingStateMachine, MapLocalizer, the
  LocalMapper (the back end), TrajectoryRecorder and RunStatistics (system/). The tracking components read the map
  through the TrackingMap interface, which this class implements with the locks below.

  Threading and ownership:
  - tracking thread (the caller of track()): owns the preprocessor and the tracking components.
  - mapping thread (real time) or the caller (deterministic): owns the LocalMapper (window, points) and the spare
    CoarseTracker it prepares for the tracking thread. m_mapperMutex is held while a job runs, so reset() and
    initialisation (caller's thread) never run concurrently with a job.
  - shared: the TrajectoryRecorder and RunStatistics (own mutexes), the job queue (m_queueMutex), the prepared
    tracking reference (m_referenceMutex; the tracking thread only try-locks it, so it never waits), the display
    snapshot (m_snapshotMutex), the last image (m_imageMutex).
*/
#ifndef HSLAM_SYSTEM_SLAM_SYSTEM_H
#define HSLAM_SYSTEM_SLAM_SYSTEM_H

#include "map/Frame.h"
#include "map/MapFile.h"
#include "map/MetricFrame.h"
#include "math/SE3.h"
#include "system/FramePreprocessor.h"
#include "system/LocalMapper.h"
#include "system/RunStatistics.h"
#include "system/TrajectoryRecorder.h"
#include "tracking/CoarseTracker.h"
#include "tracking/FrameTracker.h"
#include "tracking/HybridTracker.h"
#include "tracking/LostFrameRelocalizer.h"
#include "tracking/MapLocalizer.h"
#include "tracking/MonocularInitializer.h"
#include "tracking/TrackingMap.h"
#include "tracking/TrackingStateMachine.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamVocabulary.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace hslam
{
class VISP_EXPORT SlamSystem : private TrackingMap
{
public:
  SlamSystem(const vpHSlamCamera &camera, const vpHSlamParameters &parameters,
             const vpHSlamPhotometricCalibration &photometric);
  ~SlamSystem() override;
  SlamSystem(const SlamSystem &) = delete;
  SlamSystem &operator=(const SlamSystem &) = delete;

  vpHSlam::State track(const vpImage<unsigned char> &I, double timestamp, double exposure);

  vpHSlam::State state() const { return m_state.load(); }
  vpHomogeneousMatrix get_cMw() const;
  bool hasPose() const;
  std::vector<vpHSlam::Keyframe> keyframes() const;
  std::vector<vpColVector> activePoints(std::vector<double> *depths) const;
  std::vector<vpImagePoint> descriptorMatches() const { return m_frameTracker->descriptorMatches(); }
  std::vector<vpHSlam::MapPoint> mapPoints() const;
  std::vector<vpHSlam::GraphEdge> graphEdges() const;
  vpHSlamTrajectory trajectory(int segment) const
  {
    std::vector<unsigned int> segments;
    const vpHSlamTrajectory t = m_recorder.trajectory(segment, &segments);
    return m_metricFrame.toOutput(t, segments);
  }
  vpHSlamTrajectory keyframeTrajectory(int segment) const
  {
    std::vector<unsigned int> segments;
    const vpHSlamTrajectory t = m_recorder.keyframeTrajectory(segment, &segments);
    return m_metricFrame.toOutput(t, segments);
  }
  std::vector<unsigned int> trajectorySegments() const { return m_recorder.frameSegments(); }
  vpHSlam::Statistics statistics() const;
  void synchronize();
  //! synchronize(), then wait for a global bundle adjustment running in the background and write it back.
  void finishBackgroundWork();
  void reset();
  void saveMap(const std::string &path);
  void loadMap(const std::string &path);
  void setTag(const vpHSlamTag &tag);
  vpHSlamTag tag() const;
  vpHSlam::WorldFrame worldFrame() const;

  const FramePreprocessor &preprocessor() const { return m_preprocessor; }
  void rectifiedImage(vpImage<unsigned char> &I) const;
  const vpHSlamParameters &parameters() const { return m_params; }

private:
  //! A tracked frame handed to mapping.
  struct MappingJob {
    FramePtr frame;
    int referenceKeyframe = -1; //!< keyframe id the frame was tracked against
    SE3d refMc;                 //!< its pose relative to that keyframe
    bool needKeyframe = false;
    int seedKeyframe = -1;    //!< the frame seeds an emptied window: stored keyframe it was relocalised against
    bool relocalized = false; //!< the frame was relocalised into the map (LocalMapper::noteRelocalization())
  };

  // ---- tracking thread (SlamSystem.cpp)
  //! Localisation-only: MapLocalizer, then the frame recorded in the loaded map's coordinates.
  vpHSlam::State localize(const FramePtr &frame);
  //! Not initialised yet: one two-view attempt; on success the first map, the reference, the backfill.
  vpHSlam::State initialize(const FramePtr &frame, const vpImage<unsigned char> &I, double exposure);
  //! The map of a successful two-view attempt with \e frame; false when it gave too few points.
  bool makeFirstMap(const FramePtr &frame);
  //! The frames seen while initialising, tracked backwards and recorded against the second keyframe.
  void backfill(const TwoViewInitialization &init, int secondFrameId);
  vpHSlam::State trackInitialized(const FramePtr &frame);
  //! Swap in the reference the back end prepared, if it is ready and not being written.
  void adoptPreparedReference();
  //! Tracking is lost (or, with \e discardSegment, the segment's initialisation proved wrong): start a new segment.
  void declareLost(bool discardSegment = false);
  //! Forgets the prepared tracking reference and empties the published map snapshot (after the map was cleared).
  void dropPreparedReferenceAndSnapshot();
  /*!
    Back end, after keyframe \e keyframeId was recorded: the metric frame looks for the tag in it. In slam mode, once
    metric, the segment's sightings go to loop closure's pose graphs, and a tag seen again asks for a correction.
  */
  void observeTags(int keyframeId, const Frame &frame);
  //! The rectified camera, as map files record it.
  MapCamera mapCamera() const;
  //! Throws when the mode keeps no global map (vo-strict): \e operation names the call in the message.
  void requireGlobalMap(const std::string &path, const char *operation) const;
  //! Throws when a loaded \e map was made with another camera or vocabulary.
  void checkLoadedMap(const std::string &path, const MapSnapshot &map) const;

  // ---- TrackingMap, for the tracking components (SlamSystemThreads.cpp)
  SE3d keyframePose(int keyframeId) const override { return m_recorder.keyframePose(keyframeId); }
  bool framePose(int frameId, SE3d &wMc) const override { return m_recorder.framePose(frameId, wMc); }
  void waitForMapping() override { synchronize(); }
  bool indexesKeyframes() const override { return m_mapper->indexesKeyframes(); }
  std::vector<RelocalizationKeyframe> relocalizationCandidates(RelocalizationFrame &frame, int maxCandidates,
                                                               int preferred) override;
  std::vector<WindowView> windowViews() override;
  void localMapFeatures(int id, std::vector<ReferenceFeature> &features, std::vector<int> &keyframeIds) override;
  void localMapReference(const std::vector<int> &keyframeIds, const SE3d &refMw,
                         std::vector<CoarseTrackerPoint> &points) override;
  int closestKeyframe(const SE3d &cMw, const std::vector<int> &keyframeIds) override;

  // ---- back end (SlamSystemThreads.cpp): caller's thread in deterministic mode, mapping thread otherwise
  void deliver(MappingJob job);
  //! Map one tracked frame (m_mapperMutex held); returns the thread CPU time it took, milliseconds.
  double runJob(const MappingJob &job);
  //! After a keyframe (m_mapperMutex held): keyframe poses to the recorder, the next reference, the snapshot.
  void publishAfterKeyframe();
  //! The memory statistics into the snapshot: counted, or estimated between counts (LocalMapper), or \e exact.
  void publishMemory(bool exact);
  void mappingLoop();
  void stopMappingThread();
  void startMappingThread();

  vpHSlamParameters m_params;
  FramePreprocessor m_preprocessor;
  TrajectoryRecorder m_recorder;
  RunStatistics m_runStats;

  // ---- tracking thread components
  std::unique_ptr<MonocularInitializer> m_initializer;
  std::unique_ptr<FrameTracker> m_frameTracker;
  std::unique_ptr<HybridTracker> m_hybrid; //!< keypoints and indirect step (null in direct mode without relocalisation)
  std::unique_ptr<LostFrameRelocalizer> m_relocalizer; //!< with m_hybrid
  std::unique_ptr<TrackingStateMachine> m_tracking;
  std::unique_ptr<MapLocalizer> m_localizer;       //!< localisation-only
  std::unique_ptr<vpHSlamVocabulary> m_vocabulary; //!< loaded for relocalisation and loops, else null
  bool m_localizationReady = false;                //!< localisation-only: a map is loaded and indexed
  unsigned int m_segment = 0;
  SE3d m_segmentOrigin; //!< wMc given to the first keyframe of the current segment
  int m_nextFrameId = 0;
  double m_frameStartMs = 0.; //!< wall clock at the start of the current track() call, milliseconds
  double m_lastTimestamp = 0.;
  std::atomic<vpHSlam::State> m_state{vpHSlam::stateInitializing};
  std::atomic<unsigned int> m_frames{0}, m_trackedFrames{0}, m_lostFrames{0}, m_mappingSkipped{0};
  std::atomic<int> m_keyframeCount{0}; //!< keyframe ids handed out (the next id)
  mutable std::mutex m_imageMutex;
  vpImage<unsigned char> m_lastImage;             //!< rectified raw image of the last frame (display)
  std::atomic<unsigned int> m_segmentsStarted{0}; //!< segments that got a map (successful initialisations)
  std::atomic<unsigned int> m_relocAttempts{0}, m_relocSuccesses{0};
  std::atomic<bool> m_restartRequested{false}; //!< set by the back end when the initialisation looks wrong

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

  // ---- metric frame (setTag()): fed by the back end, read by the output getters
  MetricFrame m_metricFrame;
  //! Sightings stored when the mapper was last given them, 0 when it holds none (observeTags(), the back end's; reset()
  //! after synchronize()).
  unsigned int m_tagSightingsGiven = 0;

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
