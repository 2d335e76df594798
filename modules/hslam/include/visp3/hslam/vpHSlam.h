/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlam.h
  \brief The monocular SLAM system: feed it images, read poses, keyframes, points, trajectory and statistics.
*/
#ifndef VP_HSLAM_H
#define VP_HSLAM_H

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamPhotometricCalibration.h>
#include <visp3/hslam/vpHSlamTag.h>
#include <visp3/hslam/vpHSlamTrajectory.h>

#include <memory>
#include <string>
#include <vector>

namespace hslam
{
class SlamSystem;
} // namespace hslam

/*!
  \class vpHSlam
  \ingroup group_hslam
  \brief H-SLAM, the monocular visual SLAM system: one grey image in, one camera pose out.

  What it is for: this is the object a program talks to. Built from the camera calibration (or directly from a
  vpHSlamImageSource), it rectifies each image to pinhole, applies the photometric calibration when there is one,
  tracks the camera against a sliding window of keyframes by direct image alignment (DSO, Engel et al. 2018) and
  maintains that window by photometric bundle adjustment. The first frames are used to initialise the map from
  two views (feature matches, essential matrix or homography); track() reports stateInitializing until then.

  Execution modes (vpHSlamParameters::System::deterministic):
  - deterministic: mapping runs inside track(), in the caller's thread, after tracking. A run on the same images
    gives bit-identical poses every time; benchmarks and tests use it.
  - real time (default): mapping runs in its own thread, fed by a queue. track() never waits for mapping; when
    mapping falls behind, frames are skipped FOR MAPPING (they are still tracked and still have a pose) and the
    newest frame is used for the next keyframe. synchronize() waits until mapping has consumed the queue. In slam
    mode the global bundle adjustment that follows a loop correction runs on a third thread (tracking and mapping go
    on); its result is written back at the next keyframe, or by synchronize(), which waits for it.

  Lost tracking: a frame whose direct alignment fails keeps the pose predicted by the motion model (as in DSO) but
  neither feeds mapping nor becomes a keyframe; after vpHSlamParameters::System::maxTrackingFailures such frames
  in a row (or a non-finite estimate), track() returns stateLost for that frame, which gets no pose. The next frames
  initialise a NEW map segment: its world frame is chained to the last tracked pose so the trajectory stays
  continuous (its scale is arbitrary, as for any monocular map), and the old segment's keyframes and trajectory
  are kept. Keyframe::segment and getTrajectory(segment) tell the segments apart. A segment whose first keyframes
  reveal a wrong initialisation (window residual too high, DSO's check) is discarded and initialised again.

  Initialisation: frames seen before the map exists are kept (raw) and, once it exists, tracked backwards from the
  second keyframe, so the trajectory starts at the first frames rather than where initialisation succeeded. Nothing in
  this class exits or crashes on bad input: wrong image sizes, empty images and misuse raise vpHSlamException.

  Trajectory: every frame with a pose is stored RELATIVE to its reference keyframe, so when the window
  optimisation moves a keyframe, getTrajectory() moves the frames tracked against it too.

  Threading and ownership: track(), reset() and the constructor/destructor must be called from one thread (the
  "tracking" thread). The getters (get_cMw(), getKeyframes(), getActivePoints(), getTrajectory(), getStatistics())
  are thread-safe snapshots and may be called from any thread, e.g. a viewer. The object owns its mapping thread;
  the destructor stops it once the frames still queued for mapping (a few at most) are processed.

  Metric poses from an AprilTag: after setTag(), keyframes are searched for the tag and, once its sightings fix the
  scale well enough (getWorldFrame()), every output (get_cMw(), getKeyframes(), getActivePoints(), getMapPoints(),
  getTrajectory(), getKeyframeTrajectory()) is in metres and, when the tag's id was given, in the tag's frame. Until
  then outputs are in the map's own frame and unit, and getWorldFrame().metric says so (docs/metric-tag-frame.md).

  Settings: the vpHSlamParameters defaults run the whole SLAM system (mode slam: global map, loop closure,
  relocalisation) with fewer points and keyframes than DSO and a 6-keyframe window, about 3x to 6x real time on one
  core on the shared 640x480 sequences (docs/accuracy-and-speed.md, "Defaults"); data/hslam-dso.yaml has DSO's settings.

  \code
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create("../shared/data/tsukuba_cg_000-149");
  vpHSlamParameters params;
  params.system.deterministic = true;
  vpHSlam slam(*source, params);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  while (source->acquire(I, frame)) {
    if (slam.track(I, frame.timestamp, frame.exposure) == vpHSlam::stateTracking) {
      vpHomogeneousMatrix cMw = slam.get_cMw();
    }
  }
  slam.getTrajectory().saveTum("trajectory.txt");
  \endcode
*/
class VISP_EXPORT vpHSlam
{
public:
  //! What track() achieved for the frame it was given.
  enum State {
    stateInitializing, //!< no map yet (or a new segment after a loss): the frame has no pose
    stateTracking,     //!< the frame was tracked and has a pose
    stateLost          //!< tracking failed for this frame: no pose; the next frames start a new segment
  };

  //! A keyframe as seen from outside (a copy).
  struct Keyframe {
    unsigned int id = 0;           //!< keyframe index, 0-based, over the whole run
    unsigned int frameIndex = 0;   //!< index of the frame among those given to track()
    double timestamp = 0.;         //!< seconds
    vpHomogeneousMatrix wMc;       //!< camera-to-world pose
    bool inWindow = false;         //!< still in the optimisation window (false once marginalised)
    unsigned int segment = 0;      //!< map segment (a new one starts after each loss of tracking)
    unsigned int activePoints = 0; //!< points it hosts that are active in the window
  };

  //! Counters and timings of the run so far.
  struct Statistics {
    unsigned int frames = 0;                //!< frames given to track()
    unsigned int trackedFrames = 0;         //!< frames with a pose
    unsigned int keyframes = 0;             //!< keyframes created
    unsigned int segments = 0;              //!< map segments (1 + losses that were followed by a new map)
    unsigned int lostFrames = 0;            //!< frames for which track() returned stateLost
    unsigned int mappingSkippedFrames = 0;  //!< frames tracked but not given to mapping (real-time mode only)
    unsigned int activePoints = 0;          //!< active points in the window now
    unsigned int immaturePoints = 0;        //!< candidate points being traced now
    double trackingMsMedian = 0.;           //!< per frame: preprocessing + tracking + keyframe decision, milliseconds
    double trackingMsP95 = 0.;              //!< 95th percentile of the same, milliseconds
    double trackingMsMax = 0.;              //!< largest, milliseconds
    double initializationMsMedian = 0.;     //!< per frame while initialising, milliseconds
    double mappingMsPerKeyframeMedian = 0.; //!< keyframe creation, optimisation and marginalisation, milliseconds
    double mappingMsPerKeyframeP95 = 0.;    //!< 95th percentile of the same, milliseconds
    double mappingMsPerFrameMedian = 0.;    //!< non-keyframes (epipolar tracing only), milliseconds
    double mapMemoryMb = 0.;                //!< estimated memory held by keyframes (images, points), MB
    double mapMemoryMbPerKeyframe = 0.;     //!< marginalizedMemoryMb per marginalised keyframe (window's if none)
    unsigned int keyframesHeld = 0;         //!< keyframes whose data is held (window + kept marginalised ones)
    double orbMatchesMedian = 0.;           //!< hybrid/indirect tracking: ORB matches per tracked frame, median
    double orbInliersMedian = 0.;           //!< the same, geometric inliers of the pose-only step, median
    double geometricWeightMedian = 0.;      //!< K of eq. 4 at the finest level, median over hybrid-tracked frames
    unsigned int geometricTermFrames = 0;   //!< frames whose pose used the geometric term (ORB matches)
    double geometricTermShare = 0.;         //!< their share of the frames posed (about 1 with hybrid tracking)
    //! Adaptive tracking: frames given the geometric term for a predicted motion above tracking.adaptiveMotionPx
    unsigned int adaptiveLargeMotionFrames = 0;
    //! Adaptive tracking: ... because the direct alignment had to leave the constant-velocity prediction
    unsigned int adaptivePredictionRefusedFrames = 0;
    unsigned int adaptiveDirectFailedFrames = 0; //!< Adaptive tracking: ... because the direct alignment failed
    unsigned int relocalizationsAttempted = 0;   //!< lost frames for which relocalisation was tried
    unsigned int relocalizationsSucceeded = 0;   //!< relocalisations after which tracking resumed in the same map
    double descriptorKbPerKeyframe = 0.;         //!< memory the descriptors add to a keyframe (points + BoW), KB
    double marginalizedMemoryMb = 0.;            //!< held for keyframes that left the window (global map, index), MB
    unsigned int marginalizedKeyframes = 0;      //!< keyframes kept in the global map (vo-reuse, slam)
    unsigned int culledKeyframes = 0;            //!< of which culled: pose node only, out of co-visibility and database
    unsigned int globalPoints = 0;               //!< points stored in the global map
    double reactivatedPointsPerKeyframe = 0.;    //!< global points re-activated by early adoption, per keyframe
    double fusedPointsPerKeyframe = 0.;          //!< global points absorbed by late fusion, per keyframe
    double windowShareFromGlobal = 0.;           //!< share of the window's active points that came from the global map
    unsigned int loopCandidatesVerified = 0;     //!< slam mode: consistent loop candidates given to the Sim(3) check
    unsigned int loopsDetected = 0;              //!< slam mode: loops accepted by the Sim(3) check
    unsigned int loopsCorrected = 0;             //!< slam mode: loops whose pose-graph correction was applied
    double lastLoopCorrectionMs = 0.;            //!< slam mode: wall time of the last correction, milliseconds
    double loopCorrectionMsMax = 0.;             //!< slam mode: longest correction (pose graph, map update), ms
    double loopDetectionMsMean = 0.;             //!< slam mode: loop detection per keyframe (query, verification), ms
    unsigned int loopDetections = 0;             //!< slam mode: keyframes that went through loop detection
    double loopVerificationMsMax = 0.;           //!< slam mode: longest verification of a candidate (Sim(3)), ms
    double loopVerificationMsMean = 0.;       //!< slam mode: of loopDetectionMsMean, the verification of candidates, ms
    unsigned int globalBundleAdjustments = 0; //!< slam mode: global bundle adjustments started (one per correction)
    unsigned int globalBundleAdjustmentsApplied = 0; //!< ... written back (not stopped by a newer loop, usable)
    double globalBundleAdjustmentSecondsMax = 0.;    //!< the longest of them, wall time, seconds
    double globalBundleAdjustmentRmsBeforePx = 0.;   //!< reprojection RMS of the last one applied, before, pixels
    double globalBundleAdjustmentRmsAfterPx = 0.;    //!< ... and after, pixels
    unsigned int framesDuringLoopCorrection = 0;     //!< real time: frames tracked while a correction ran
    double trackingMsMaxDuringLoopCorrection = 0.;   //!< real time: the longest of their tracking times, ms
    bool metric = false;                //!< outputs are in metres (a tag was described and its fit is trusted)
    unsigned int tagSightings = 0;      //!< tag sightings in keyframes (setTag())
    unsigned int tagSightingsUsed = 0;  //!< of which kept by the metric fit (its segment, not refused)
    unsigned int tagCorrections = 0;    //!< slam mode: pose-graph corrections applied because the tag was seen again
    double metricScale = 1.;            //!< metres per map unit of the fit (1 when none)
    double metricScaleUncertainty = 1.; //!< the fit's relative standard deviation of that scale (1 when none)
    double tagDetectionMsMean = 0.;     //!< tag detection per keyframe, milliseconds
  };

  //! The frame the outputs are expressed in (setTag()).
  struct WorldFrame {
    bool metric = false;            //!< outputs in metres (the tag's fit is trusted); false: the map's own unit
    bool tagFrame = false;          //!< ... and in the frame of the tag whose id was given (else the map's axes)
    double scale = 1.;              //!< metres per map unit of the current fit (1 when there is none)
    double scaleUncertainty = 1.;   //!< its relative standard deviation
    double rmsMetres = 0.;          //!< RMS camera-position residual of the fitted sightings, metres
    unsigned int sightings = 0;     //!< tag sightings in keyframes so far
    unsigned int sightingsUsed = 0; //!< kept by the fit
    /*!
      The similarity from the map's frame to the output frame as [R t; 0 1] and its scale: a map point X goes to
      scale * R X + t (identity and 1 while not metric).
    */
    vpHomogeneousMatrix oMw;
  };

  /*!
    Build the system for a camera.
    \param camera : geometric calibration of the images that will be given to track() (raw, distorted).
    \param parameters : every setting (copied; validated).
    \param photometric : photometric calibration of the raw images (empty: affine brightness is estimated).
    \exception vpHSlamException::invalidArgument when a parameter is out of range, or the rectification fails.
  */
  explicit vpHSlam(const vpHSlamCamera &camera, const vpHSlamParameters &parameters = vpHSlamParameters(),
                   const vpHSlamPhotometricCalibration &photometric = vpHSlamPhotometricCalibration());
  /*!
    Build the system for an image source: its camera and photometric calibration are used (the latter unless
    vpHSlamParameters::System::usePhotometricCalibration is false).
  */
  explicit vpHSlam(const vpHSlamImageSource &source, const vpHSlamParameters &parameters = vpHSlamParameters());
  ~vpHSlam();
  vpHSlam(const vpHSlam &) = delete;
  vpHSlam &operator=(const vpHSlam &) = delete;

  /*!
    Process one image.
    \param I : grey image of the camera's input size (vpHSlamCamera::getWidth() x getHeight()).
    \param timestamp : seconds, strictly increasing.
    \param exposure : exposure time (milliseconds, any consistent unit), <= 0 when unknown; NaN and infinity are
    taken as unknown too.
    \return the state for this frame.
    \exception vpHSlamException::invalidImage when I is empty or of the wrong size (both sizes are named);
    vpHSlamException::invalidTimestamps when the timestamp is not finite or does not increase. A frame refused
    this way leaves the system as it was: the next valid frame is tracked as if the refused one had not come.
  */
  State track(const vpImage<unsigned char> &I, double timestamp, double exposure = -1.);

  /*!
    Describe the AprilTag that gives the outputs metres (and, with its id, its frame): from the next keyframe on,
    keyframes are searched for it. A tag not set (vpHSlamTag()) turns this off. Sightings so far are forgotten.
    \exception vpHSlamException::unsupported when this ViSP has no AprilTag detector.
  */
  void setTag(const vpHSlamTag &tag);
  //! The tag described by setTag() (not set by default).
  vpHSlamTag getTag() const;
  //! True when the outputs are in metres (see WorldFrame).
  bool isMetric() const;
  //! The frame the outputs are in, and the fit behind it.
  WorldFrame getWorldFrame() const;

  //! State returned by the last track() (stateInitializing before the first).
  State getState() const;
  //! World-to-camera pose of the last frame that has a pose (identity before the first).
  vpHomogeneousMatrix get_cMw() const;
  //! True once at least one frame has a pose.
  bool hasPose() const;

  //! Every keyframe created so far (all segments), ordered by id, poses as currently estimated.
  std::vector<Keyframe> getKeyframes() const;
  /*!
    3D positions in the world frame (metres up to the monocular scale, 3-vectors) of the points active in the
    window, with their depth in the newest keyframe's camera (same order) when \e depths is not null.
  */
  std::vector<vpColVector> getActivePoints(std::vector<double> *depths = nullptr) const;
  /*!
    Pixels (rectified image of the last frame, see getRectifiedImage()) of the keypoints the last frame matched to
    map points by ORB descriptor and kept as geometric inliers (hybrid and indirect tracking, and adaptive tracking on
    the frames that used the geometric term; empty in direct mode, for a frame adaptive tracking kept direct, or when
    the frame was not tracked).
  */
  std::vector<vpImagePoint> getDescriptorMatches() const;

  //! A map point as seen from outside (a copy).
  struct MapPoint {
    vpColVector wX;      //!< world position (3), metres up to the monocular scale
    bool active = false; //!< in the optimisation window (else: marginalised, in the global map)
  };
  /*!
    Every map point: the window's (active, and those that left the window with their host still in it) and, in
    vo-reuse / slam mode, the global map's. Waits for the mapping thread's current keyframe, if any.
  */
  std::vector<MapPoint> getMapPoints() const;

  //! An edge of the hybrid connectivity graph (keyframe ids as in getKeyframes()).
  struct GraphEdge {
    unsigned int a = 0;        //!< first keyframe (pose-pose: the older, marginalised one)
    unsigned int b = 0;        //!< second keyframe
    bool covisibility = false; //!< co-visibility edge (else pose-pose: consecutive or shared residuals)
    unsigned int weight = 0;   //!< co-visibility: points seen by both; pose-pose: 0
  };
  //! The graph's edges so far (vo-reuse / slam mode; empty in vo-strict).
  std::vector<GraphEdge> getGraphEdges() const;

  /*!
    Trajectory of every frame that has a pose (camera-to-world), each frame expressed relative to its reference
    keyframe and composed with that keyframe's current pose.
    \param segment : only this map segment; -1 (default) for all segments in order.
  */
  vpHSlamTrajectory getTrajectory(int segment = -1) const;
  //! Keyframe poses only (camera-to-world), all segments or one.
  vpHSlamTrajectory getKeyframeTrajectory(int segment = -1) const;
  //! Segment of every pose of getTrajectory() (same order), for programs that write them apart.
  std::vector<unsigned int> getTrajectorySegments() const;

  //! Counters and timings so far.
  Statistics getStatistics() const;

  /*!
    Real-time mode: block until mapping has processed every queued frame and a global bundle adjustment running in
    the background has ended (its correction is then in getTrajectory()). Deterministic mode: no effect.
  */
  void synchronize();

  //! Forget everything (map, trajectory, statistics) and start again with the next frame.
  void reset();

  /*!
    Write the map to \e path (H-SLAM's versioned binary map file, format in the source's map/MapFile.h): every
    keyframe kept (pose, affine brightness, points in inverse-depth form with variance, ORB descriptor and
    observers), the pose-pose edges, the rectified camera and the vocabulary's fingerprint. The window's keyframes
    are written as if marginalised now; the running system is not changed. In real-time mode, waits for mapping
    first. The file is written to a temporary name and renamed, so an interrupted save leaves the old file whole.
    \exception vpHSlamException : invalidArgument in vo-strict mode (no map is kept) or before the first keyframe;
    fileUnreadable when the file cannot be written.
  */
  void saveMap(const std::string &path);

  /*!
    Read a map written by saveMap() and make it the global map, before the first frame (or right after reset()).
    The loaded keyframes keep their own map segments: the next frames start a new segment, which re-use and loop
    detection keep apart from the loaded coordinates; getMapPoints(), getGraphEdges() and a later saveMap() include
    the loaded map. (Tracking inside a loaded map, localisation-only, is not implemented yet.)
    \exception vpHSlamException : fileNotFound / fileUnreadable; parseError for a file that is not a map, truncated
    or corrupt (checksum); unsupported for another format version or a different vocabulary; invalidCalibration
    when the map was built with another rectified camera; invalidArgument in vo-strict mode or after frames were
    tracked.
  */
  void loadMap(const std::string &path);

  //! The pinhole camera of the rectified images the system works in.
  vpCameraParameters getCameraParameters() const;
  //! Rectified image width, pixels.
  unsigned int getWidth() const;
  //! Rectified image height, pixels.
  unsigned int getHeight() const;
  //! The last image given to track(), rectified (8-bit, photometrically raw), for display.
  void getRectifiedImage(vpImage<unsigned char> &I) const;
  //! The settings in use.
  const vpHSlamParameters &getParameters() const;
  //! "initializing", "tracking" or "lost".
  static std::string stateName(State state);

private:
  std::unique_ptr<hslam::SlamSystem> m_system;
};

#endif
