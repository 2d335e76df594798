/*
 * H-SLAM for ViSP.
 */
/*!
  \file LoopCloser.h
  \brief Loop closure as a component (paper sec. 3.4): place recognition over the stored keyframes, Sim(3)
  verification, and the pose-graph correction it hands back to the mapper.

  What it owns: every stored keyframe's loop features (LoopFeatures.h: multi-scale ORB keypoints with a depth from
  the window), their bag-of-words database (its own: the relocalisation index keeps the window points' vectors),
  the consistency groups of the last queries, the loop edges accepted so far, and the statistics.

  What it is given: each keyframe that leaves the window (addKeyframe(): its image and the window's inverse depths,
  once they are final), and at detect() the global map (poses, co-visibility) with the keyframes the caller counts as
  connected to the present (the window and the keyframes lending it re-used points). A culled keyframe is removed
  (removeKeyframe()).

  What it hands back: detect() returns an accepted loop (the keyframe that asked, the candidate, the measured
  similarity), and correct() the corrected similarity of every stored keyframe of the segment (the window held
  fixed): the mapper moves its keyframes and points, and tells this component of the scales (rescale()).

  Detection (ORB-SLAM2's LoopClosing rules on our graph): a keyframe is queried once it is stored and once loop
  .minKeyframesBetween keyframes have passed since the segment's start or the last loop; candidates score at
  least its lowest score with its co-visible stored keyframes, are not connected, and must agree over
  loop.consistency consecutive queries; then LoopVerification.h decides, and a correction rotating the map by more
  than loop.maxRotationCorrectionDeg is refused (aliasing).

  Landmarks seen in metres (tags, setLandmarkSightings()) are constraints of every correction's pose graph, and a
  landmark seen again after the camera went away asks for a correction of its own (correctLandmarks(),
  queueLandmarkCorrection(); loop/LoopCorrection.h), applied by the mapper as a loop's.

  Threading. Deterministic runs: not thread-safe; the mapping thread (the caller) owns it, and detection and
  correction run there after each keyframe (detect(), correct()), in order. Real time (startThread()): the
  component works on a thread of its own. The mapper's calls (handOver(), removeKeyframe(), queueQuery()) only queue
  work; the thread makes the loop features, queries the database, verifies candidates and solves the pose graph on a
  copy of the map's graph (GlobalMap::graphCopy()), and the mapper collects the solution (takeCorrection()) and
  applies it to the map. A query whose copy predates a correction not yet applied is skipped (its keyframes are
  queried with the next one), so a solution never undoes another. The global bundle adjustment after a correction
  runs on a third thread (runInBackground()) on a copy of the map; the mapper collects it (takeBackgroundJob()).
*/
#ifndef HSLAM_LOOP_LOOP_CLOSER_H
#define HSLAM_LOOP_LOOP_CLOSER_H

#include "loop/GlobalBundleJob.h"
#include "loop/KeyframeDatabase.h"
#include "loop/LandmarkSightings.h"
#include "loop/LoopDetector.h"
#include "loop/LoopFeatures.h"
#include "loop/LoopVerification.h"
#include "loop/PoseGraph.h"
#include "map/GlobalMap.h"
#include "map/Keyframe.h"
#include "math/Sim3.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace hslam
{
class OrbVocabulary;

//! A verified loop.
struct LoopRecord {
  int keyframe = -1;            //!< the stored keyframe that closed it (it asked the database)
  int candidate = -1;           //!< the stored keyframe it closed with
  int inliers = 0;              //!< Sim(3) inliers
  double scale = 1.;            //!< scale of the measured S_keyframe_candidate
  double translationDrift = 0.; //!< |translation part of the correction| (map units)
};

//! What the mapper applied of loop closure: correction times and global bundle adjustments.
struct LoopApplyStatistics {
  int corrected = 0;               //!< loops whose pose-graph correction was applied to the map
  int landmarkCorrected = 0;       //!< corrections asked by a landmark seen again, applied to the map
  double lastCorrectionMs = 0.;    //!< wall time of the last correction (pose graph, map update)
  double correctionMsMax = 0.;     //!< longest correction
  int globalBaStarted = 0;         //!< global bundle adjustments started (one after each correction)
  int globalBaApplied = 0;         //!< ... and written back
  double globalBaSecondsMax = 0.;  //!< longest of them, wall time, seconds
  double globalBaRmsBeforePx = 0.; //!< reprojection RMS of the last one applied, before and after, pixels
  double globalBaRmsAfterPx = 0.;
};

//! Counters of loop closure since the start.
struct LoopStatistics {
  int candidatesVerified = 0;      //!< consistent candidates given to the Sim(3) verification
  std::vector<LoopRecord> loops;   //!< loops accepted
  int refusedImplausible = 0;      //!< verified loops refused for a rotation correction above the limit
  int detections = 0;              //!< keyframes checked for a loop (database queried)
  double detectionMsTotal = 0.;    //!< their wall time: query, consistency, verification (correction excluded)
  double verificationMsMax = 0.;   //!< longest verification of one candidate (matching, Sim(3) RANSAC, refinement)
  double verificationMsTotal = 0.; //!< of detectionMsTotal, the verifications' wall time (the rest: the query)
  LoopApplyStatistics applied;     //!< what the mapper applied
};

//! A loop that detect() accepted.
struct DetectedLoop {
  int keyframe = -1;        //!< stored keyframe that asked
  int candidate = -1;       //!< stored keyframe it closed with
  Sim3d SkeyframeCandidate; //!< measured: maps the candidate's camera into the keyframe's
};

class VISP_EXPORT LoopCloser
{
public:
  //! A correction solved on the loop closer's thread, for the mapper to apply.
  struct Correction {
    DetectedLoop loop;                           //!< for a landmark's correction: keyframe, the one that saw it
    bool landmark = false;                       //!< asked by a landmark seen again, not by a loop
    std::vector<std::pair<int, Sim3d>> solution; //!< the new S_iw of every stored keyframe of the segment
    double solveMs = 0.;                         //!< wall time of the pose graph on the thread
  };

  //! \e vocabulary must outlive the component.
  LoopCloser(const vpHSlamParameters::Loop &params, const PinholeIntrinsics &K, const OrbVocabulary &vocabulary);
  //! Stops the thread (its queued work is dropped).
  ~LoopCloser();
  LoopCloser(const LoopCloser &) = delete;
  LoopCloser &operator=(const LoopCloser &) = delete;

  //! Real time: from now on the work runs on the component's own thread (see the class comment).
  void startThread();
  bool threaded() const { return m_thread.joinable(); }

  /*!
    Hand-over: keyframe \e id left the window. Its loop features are made from \e image and \e samples (the
    window's points in its camera, final inverse depths) and it joins the database; it is queried at the next
    detect(). \e segment: its map segment.
  */
  void addKeyframe(int id, int segment, const vpImage<unsigned char> &image, const std::vector<IdepthSample> &samples);
  /*!
    Hand-over of \e kf, leaving \e window now (it is still in it): its image, and as depth samples its own points
    (final now) and the window's active points seen from it (then addKeyframe(), queued when threaded).
  */
  void handOver(const Keyframe &kf, int segment, const std::vector<KeyframePtr> &window);
  /*!
    Threaded: query the keyframes handed over so far against \e graph (GlobalMap::graphCopy() of the map now), with
    \e connected (connectedTo()) and the window's poses, held fixed by a correction.
  */
  void queueQuery(GlobalMap graph, std::set<int> connected, std::map<int, SE3d> windowPoses);
  /*!
    Threaded: a correction the thread solved, to apply now (false when none). With \e wait, the work queued so far
    is finished first.
  */
  bool takeCorrection(Correction &correction, bool wait);
  /*!
    Keyframes connected to the present, never loop candidates: the window and the keyframes whose points the window
    re-uses now.
  */
  static std::set<int> connectedTo(const std::vector<KeyframePtr> &window);

  /*!
    Query the keyframes handed over since the last call, oldest first, until one closes a loop. \e map gives poses
    and co-visibility, \e connected the keyframes connected to the present (never candidates). Returns false when
    no loop was accepted.
  */
  bool detect(const GlobalMap &map, const std::set<int> &connected, DetectedLoop &loop);

  /*!
    The pose graph of \e loop's segment (stored keyframes free, \e windowPoses fixed: pose-pose edges, strong
    co-visibility, every loop edge so far and the new loop's connections). On success \e solution holds the new
    similarity S_iw of every stored keyframe of the segment and true is returned; the loop features follow their
    keyframes' scales, the map is not changed here (the caller applies the solution).
  */
  bool correct(const DetectedLoop &loop, const GlobalMap &map, const std::map<int, SE3d> &windowPoses,
               std::vector<std::pair<int, Sim3d>> &solution);
  /*!
    The landmarks seen in metres so far in the current segment (every correction's graph holds them from now on;
    queued when threaded, in order with the other work).
  */
  void setLandmarkSightings(LandmarkSightings landmarks);
  /*!
    A landmark seen from keyframe \e keyframe (in the window) was seen before from stored keyframes: the pose graph
    of its segment with the landmarks' sightings and no new loop (solveLandmarkCorrection()). On success \e solution
    holds the new S_iw of every stored keyframe of the segment, as correct() gives it.
  */
  bool correctLandmarks(int keyframe, const GlobalMap &map, const std::map<int, SE3d> &windowPoses,
                        std::vector<std::pair<int, Sim3d>> &solution);
  //! The pose graph \e correction asks for (a landmark's, correctLandmarks(), or its loop's, correct()) into its
  //! solution.
  bool solve(Correction &correction, const GlobalMap &map, const std::map<int, SE3d> &windowPoses);
  //! Threaded: correctLandmarks() on \e graph (GlobalMap::graphCopy()); the mapper collects it (takeCorrection()).
  void queueLandmarkCorrection(int keyframe, GlobalMap graph, std::map<int, SE3d> windowPoses);
  /*!
    The global bundle adjustment after a correction (loop.globalBundleAdjustment): the problem of \e segment's stored
    keyframes and points (\e windowPoses held fixed), to run in order or in the background.
  */
  std::unique_ptr<GlobalBundleJob> makeGlobalBundleJob(const GlobalMap &map, int segment,
                                                       const std::map<int, SE3d> &windowPoses);
  //! Real time: run \e job on the component's own thread (a job still running is cancelled first).
  void runInBackground(std::unique_ptr<GlobalBundleJob> job) { m_globalBa.start(std::move(job)); }
  //! The background job if it has ended (or, with \e wait, once it ends); null when none.
  std::unique_ptr<GlobalBundleJob> takeBackgroundJob(bool wait);
  //! Stop the background job (a correction would make its result stale).
  void cancelBackgroundJob() { m_globalBa.cancel(); }
  //! A culled keyframe leaves the database (queued when threaded).
  void removeKeyframe(int id);
  //! A new map segment: queries start again (stored keyframes stay; candidates come from the same segment only).
  void newSegment();
  //! Drop every keyframe and loop, and a background job (a new segment's mapper, vpHSlam::reset()); the statistics
  //! stay.
  void clear();

  //! Bytes held: the loop features, the database and the loop edges (threaded: after the last work done).
  double memoryBytes() const;
  //! Counters since the start (threaded: after the last work done).
  LoopStatistics statistics() const;
  //! The mapper applied a correction (\e landmark: a landmark's) in \e ms (on the thread, plus the pose graph's time).
  void recordCorrectionApplied(double ms, bool landmark = false);
  //! The mapper wrote back (\e applied) or not a global bundle adjustment.
  void recordGlobalBundleAdjustment(const GlobalBundleSummary &summary, bool applied);
  void resetStatistics();

private:
  struct Entry {
    LoopKeyframe features;
    int segment = 0;
  };
  //! Work queued for the thread: a hand-over, a removal, a query, new landmark sightings or a landmark's correction.
  struct Work {
    enum Kind { handOver, remove, query, newSightings, landmarkCorrection } kind = handOver;
    int id = -1; //!< the keyframe handed over, removed, or that saw the landmark again
    LandmarkSightings landmarks;
    int segment = 0;
    vpImage<unsigned char> image;
    std::vector<IdepthSample> samples;
    GlobalMap graph;
    std::set<int> connected;
    std::map<int, SE3d> windowPoses;
    int correctionsApplied = 0; //!< corrections the mapper had applied when it copied \e graph
  };
  void run();
  //! One piece of work on the thread; true when it solved a correction (\e correction).
  bool process(Work &work, Correction &correction);
  void enqueue(Work work);
  //! Threaded: wait until the queue is empty and the thread idle.
  void waitIdle(std::unique_lock<std::mutex> &lock);
  //! Keyframe \e id's map was divided by \e scale (a correction solved): its loop features follow.
  void rescale(int id, double scale);
  void dropKeyframe(int id);
  double heldBytes() const;
  bool query(int id, const GlobalMap &map, const std::set<int> &connected, DetectedLoop &loop);
  bool verifyCandidate(int id, int candidate, const GlobalMap &map, DetectedLoop &loop);
  //! A side of the verification: \e id and its best co-visible keyframes that hold loop features, not \e excluded.
  std::vector<LoopSideKeyframe> side(int id, size_t neighbours, const GlobalMap &map,
                                     const std::set<int> &excluded) const;

  vpHSlamParameters::Loop m_params;
  PinholeIntrinsics m_K;
  const OrbVocabulary &m_vocabulary;
  LoopFeatureExtractor m_extractor;
  KeyframeDatabase m_database;
  std::map<int, Entry> m_keyframes;
  std::vector<int> m_pending; //!< handed over, not queried yet
  LoopConsistency m_consistency;
  int m_segment = 0;            //!< segment of the keyframes being queried
  int m_keyframesInSegment = 0; //!< handed over in this segment
  int m_keyframeOfLastLoop = 0; //!< m_keyframesInSegment at the last loop (or the segment's start)
  //! Every corrected loop's edges (the measured one and its connections), kept for the next corrections.
  std::vector<PoseGraphEdge> m_loopConstraints;
  LandmarkSightings m_landmarks; //!< setLandmarkSightings()
  LoopStatistics m_stats;        //!< detection and correction counters (the thread's when threaded)
  //! What the mapper applied (correction times, global bundle adjustments); the mapper's thread only.
  LoopApplyStatistics m_applied;
  //! Real time: the global bundle adjustment's thread.
  BackgroundBundleAdjustment m_globalBa;

  // ---- real time: the component's thread. m_queueMutex guards the queue, the corrections, the counters below and
  // the published statistics; the rest of the state is the thread's while it runs.
  std::thread m_thread;
  mutable std::mutex m_queueMutex;
  std::condition_variable m_wake; //!< work queued, or stop
  std::condition_variable m_idle; //!< the queue emptied
  std::deque<Work> m_queue;
  std::deque<Correction> m_corrections; //!< solved, not taken yet
  bool m_busy = false;
  bool m_stop = false;
  int m_correctionsSolved = 0;  //!< by the thread (the segment's)
  int m_correctionsTaken = 0;   //!< by the mapper (the segment's)
  LoopStatistics m_published;   //!< m_stats after the last work done
  double m_publishedBytes = 0.; //!< heldBytes() after the last work done
};
} // namespace hslam

#endif
