/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamParameters.h
  \brief Every setting of the system, one struct per component, with defaults, YAML load/save and print.
*/
#ifndef VP_HSLAM_PARAMETERS_H
#define VP_HSLAM_PARAMETERS_H

#include <visp3/core/vpConfig.h>

#include <iosfwd>
#include <string>
#include <vector>

/*!
  \class vpHSlamParameters
  \ingroup group_hslam
  \brief All settings of H-SLAM: one struct per component (features, tracker, mapper, initializer, tracking, globalMap,
  system), each field documented with its unit and a default taken from DSO (direct part) or ORB-SLAM2 (indirect part)
  unless noted. The defaults run the whole system (mode slam) with fewer points, iterations and keyframes than DSO,
  the trade-off measured in docs/accuracy-and-speed.md, "Defaults"; data/hslam-dso.yaml restores DSO's values.

  What it is for: no threshold lives in algorithm code; everything a user may tune is here, can be written to and
  read from YAML (cv::FileStorage format, one section per component), and printed. Fields absent from a YAML file
  keep their defaults; unknown keys are an error (they are usually typos).

  Threading: a value type; the system copies it at construction.

  Adding a setting: declare it at the end of its struct with a default and a doc comment, add its one row (range,
  short doc) to the table of src/common/vpHSlamParameters.cpp, and regenerate data/hslam-default.yaml with
  HSLAM_REGENERATE_DEFAULT_YAML=1 ctest -R DefaultYamlMatchesDefaults. test_parameters fails until all three agree.

  \code
  vpHSlamParameters params;
  params.load("data/hslam-default.yaml");   // optional
  params.mapper.windowSize = 6;
  params.print(std::cout);
  params.save("used-settings.yaml");
  \endcode
*/
class VISP_EXPORT vpHSlamParameters
{
public:
  //! What the system keeps and optimises (ARCHITECTURE.md, "Modes").
  enum Mode {
    modeVoStrict, //!< window only, marginalised points discarded (DSO-like)
    modeVoReuse,  //!< global points re-used, no loop closure
    modeSlam      //!< vo-reuse + loop detection, Sim(3) verification, pose-graph correction, global inverse-depth BA
  };

  //! Which errors the pose of a new frame minimises (paper section 3.2; the ablations of section 4).
  enum TrackingMode {
    trackingDirect,   //!< photometric error only (DSO's coarse tracker; no descriptors are computed)
    trackingIndirect, //!< reprojection error of ORB matches only (the photometric side still estimates (a, b))
    trackingHybrid,   //!< both, weighted by the paper's eq. 4
    trackingAdaptive  //!< per frame: direct, or hybrid when the motion makes the photometric solution doubtful
  };

  //! Point selection on new keyframes (DSO PixelSelector; FAST corners come first in their cells).
  struct Features {
    int desiredPointDensity = 600;    //!< active points the window aims at (DSO 2000; docs/accuracy-and-speed.md)
    int desiredImmatureDensity = 500; //!< candidates selected per new keyframe (DSO 1500; docs/accuracy-and-speed.md)
    int selectionBlockSize = 32;      //!< side of the blocks of the region-adaptive gradient threshold, pixels
    double gradientThresholdAdd = 7.; //!< threshold = block median of |grad| + this, intensity units (DSO)
    double gradientThresholdLevelFactor = 0.75; //!< threshold multiplier per coarser selection level (DSO)
    int selectionLevels = 3;                    //!< pyramid levels used for selection (DSO: 3 "potential" sizes)
    int fastThreshold = 7;                      //!< FAST intensity threshold (ARCHITECTURE.md)
    int maxCorners = 1000;                      //!< FAST corners kept per keyframe
    double cornerMinDistance = 4.;              //!< non-maximum suppression radius between corners, pixels
    double cornerShare = 0.5; //!< hybrid: corners added per keyframe, at most this share of the gradient budget
  };

  //! Direct (and later joint) pose tracking against the newest keyframe.
  struct Tracker {
    int maxPyramidLevels = 6;            //!< upper bound on pyramid levels
    int minCoarsestPixels = 5000;        //!< a coarser level is added while the coarsest one has more pixels (DSO)
    double huberThreshold = 9.;          //!< Huber threshold on photometric residuals, intensity units (DSO)
    double gradientWeightC = 50.;        //!< gradient weight c^2/(c^2+|g|^2), c in intensity units (DSO)
    double outlierEnergyPerPixel = 144.; //!< residual^2 above which a pattern pixel is an outlier: 12^2 (DSO)
    std::vector<int> iterationsPerLevel = {10, 20, 50, 50, 50}; //!< Gauss-Newton iterations, finest level first (DSO)
    double retrackResidualFactor = 1.5;   //!< try other motion hypotheses when the residual exceeds this times the last
    double affinePriorA = 0.;             //!< prior weight on a (0 = free; DSO mode 1 without calibration)
    double affinePriorB = 0.;             //!< prior weight on b (0 = free)
    double affinePriorACalibrated = 1e12; //!< prior weight on a with photometric calibration (DSO: fixed)
    double affinePriorBCalibrated = 1e8;  //!< prior weight on b with photometric calibration (DSO)
    double maxShiftWeightT = 0.02;        //!< keyframe decision: translation flow weight, per (w+h) (DSO 0.04)
    double maxShiftWeightR = 0.0;         //!< keyframe decision: rotation flow weight, per (w+h) (DSO)
    double maxShiftWeightRT = 0.01;       //!< keyframe decision: rotation+translation flow weight, per (w+h) (DSO 0.02)
    double maxAffineWeight = 1.;          //!< keyframe decision: brightness change weight (DSO 2)
    double keyframeResidualFactor = 2.;   //!< keyframe when the RMSE exceeds this times the keyframe's first RMSE
    int maxFramesBetweenKeyframes = 0;    //!< force a keyframe after this many frames (0 = never)
    double coarseCutoffResidual = 20.;    //!< coarse tracking: single-pixel residuals above this are saturated (DSO 20)
  };

  //! Sliding-window photometric bundle adjustment, point management and marginalisation.
  struct Mapper {
    int windowSize = 6;                       //!< keyframes in the window (paper and DSO: 7)
    int minWindowSize = 4;                    //!< marginalisation keeps at least this many keyframes (DSO 5)
    int maxOptimizationIterations = 3;        //!< LM iterations per new keyframe (DSO 6)
    int minOptimizationIterations = 1;        //!< (DSO)
    double initialLambda = 1e-5;              //!< LM damping start (DSO)
    double stepConvergenceThreshold = 1e-5;   //!< stop when the scaled update norm is below this
    double minPointsFractionKept = 0.05;      //!< marginalise a keyframe keeping fewer of its points (DSO: 5 %)
    double maxAffineChangeMarginalize = 0.7;  //!< marginalise when |a_ji| changes beyond this log-ratio (DSO)
    double minIdepthHessianActivate = 100.;   //!< inverse-depth Hessian needed to keep a new point (DSO)
    double minIdepthHessianMarginalize = 50.; //!< below: drop a point instead of marginalising it (DSO)
    double activationMinDistance = 2.;        //!< initial distance-map radius for activation, pixels (adapted, DSO)
    double traceMinImprovementFactor = 2.;    //!< DSO setting_trace_minImprovementFactor
    double traceSlackInterval = 1.5;          //!< search interval slack, pixels (DSO)
    double traceStepSize = 1.;                //!< epipolar search step, pixels (DSO)
    int traceGaussNewtonIterations = 3;       //!< sub-pixel refinement iterations (DSO)
    double traceGaussNewtonThreshold = 0.1;   //!< stop refinement below this step, pixels (DSO)
    double traceExtraSlackOnThreshold = 1.2;  //!< outlier threshold slack for tracing (DSO)
    double minTraceQuality = 3.;              //!< quality (second best / best) required to activate (DSO)
    double maxTraceInterval = 8.;             //!< pixel length of the interval below which a point may activate (DSO)
    double outlierResidualFraction = 0.3;     //!< a point with more than this fraction of outlier residuals is removed
    double traceMaxPixelSearch = 0.027;       //!< longest epipolar segment searched, fraction of (width + height) (DSO)
    //! Camera turning in place: a candidate that fails the Hessian test because the translation from its host to
    //! the newest keyframe moves a point at the window's median depth by less than this (pixels at 640 px width,
    //! scaled with the image width) is kept, when its residuals agree and the window has fewer than
    //! features.desiredPointDensity points, on a weak prior at that median inverse depth (0: never; DSO drops such
    //! candidates, and a turn in place empties its window; docs/accuracy-and-speed.md, "Defaults", for the value)
    double rotationFlowPx = 4.;
  };

  //! Monocular initialisation (two-view from feature matches, then photometric refinement).
  struct Initializer {
    int minMatches = 50;             //!< ORB matches needed to attempt a two-view solution
    double minParallaxDeg = 1.0;     //!< median triangulation angle required, degrees
    double ransacThresholdPx = 1.0;  //!< RANSAC inlier threshold on the epipolar / homography error, pixels
    double ransacConfidence = 0.999; //!< RANSAC confidence
    int maxFramesToInitialize = 60;  //!< give up and restart with a new first frame after this many, frames
    double initialIdepth = 1.;       //!< scale: the median inverse depth of the first map is set to this, 1/m
    int orbFeatures = 1000;          //!< ORB features per frame while initialising (ORB-SLAM2 TUM/EuRoC: 1000)
  };

  /*!
    Hybrid pose tracking: descriptor sharing, ORB matching of the map into the new frame, joint photometric and
    geometric optimisation, relocalisation (paper sections 3.1, 3.2). Matching defaults are ORB-SLAM2's tracking
    values; the others were measured on the shared sequences (docs/hybrid-tracking.md).
    The default tracking mode is adaptive: the direct alignment, and the joint one when the motion makes the
    photometric solution doubtful (tracking/AdaptiveTracking.h). Under ordinary motion hybrid is no more accurate
    than direct at about 3x the cost; under large motion (skipped frames, a hand-held turn about a near pivot) it can
    be far better (docs/hybrid-tracking.md, tutorials/hslam-adaptive-benchmark.sh). Relocalisation needs descriptors:
    any mode but direct, or direct in vo-reuse and slam.
  */
  struct Tracking {
    TrackingMode mode = trackingAdaptive; //!< direct, indirect, hybrid or adaptive (see above why adaptive)
    int frameFeatures = 1000;             //!< FAST corners described per new frame for matching (ORB-SLAM2: 1000)
    int frameFastThreshold = 7;           //!< FAST threshold on new frames, intensity units (as features.fastThreshold)
    double matchRadiusPx = 15.;           //!< search radius around a predicted pixel, pixels (ORB-SLAM2: 15 at 640x480)
    int matchMaxDistance = 100;           //!< Hamming distance accepted at most (ORB-SLAM2 TH_HIGH)
    double matchRatio = 0.9;              //!< best distance must be below this times the second best (ORB-SLAM2)
    int minMatchesBeforeWidening = 20;    //!< fewer matches: search again with twice the radius (ORB-SLAM2: 20)
    int minGeometricInliers = 10;         //!< inliers the indirect step needs to give a pose (ORB-SLAM2: 10)
    //! Paper eq. 3: weigh each match of the joint optimisation by its point's inverse-depth information over the
    //! largest (hybrid tracking). Off: measured no better than equal weights (docs/hybrid-tracking.md)
    bool geometricDepthWeights = false;
    bool relocalize = true; //!< when tracking fails, relocalise in the same map before a new segment (hybrid or
                            //!< indirect tracking, or any tracking in vo-reuse and slam: it needs the keyframe
                            //!< database)
    double relocalizationTimeout = 1.;   //!< seconds of frames with features not relocalised before a new segment
    int relocalizationCandidates = 5;    //!< keyframes tried per lost frame, best BoW score first
    int relocalizationMinInliers = 30;   //!< PnP inliers after refinement to accept a relocalisation
    int relocalizationCheckInliers = 15; //!< ORB inliers of the joint alignment that confirm a relocalised pose (wrong
                                         //!< alignments measured with 0-3, right ones with 16-58)
    //! A pose found on the window's triangulated points is refused when its photometric alignment leaves fewer than
    //! this share of the reference's residuals below the cutoff (wrong poses measured at 0.52-0.59, right ones at
    //! 0.71-0.92; the frame after tries again)
    double relocalizationMinInlierRatio = 0.65;
    bool relocalizeInWindow = true; //!< also match a lost frame to ORB points triangulated between the window's
                                    //!< keyframes (found the camera after 40-frame covers where BoW candidates fail)
    bool seedFromStoredMap = true;  //!< a window left without points takes two agreeing PnP fixes in the stored map
                                    //!< and re-activates the stored points seen there (slam / vo-reuse modes)
    //! Adaptive tracking: a frame whose predicted motion moves the reference's points by more than this on average
    //! (pixels at 640 px width, scaled with the width) is tracked with the geometric term (docs/hybrid-tracking.md)
    double adaptiveMotionPx = 20.;
  };

  /*!
    Global map, re-use and hybrid connectivity graph (used from system.mode = vo-reuse on; vo-strict drops what
    leaves the window). Re-use matches corners by ORB: global points projected into a keyframe are matched within
    reuseRadiusPx with ORB-SLAM's strict distance (TH_LOW) and ratio; late fusion also asks the depths to agree within
    fusionSigmas standard deviations (paper sec. 3.3: 2).
  */
  struct GlobalMap {
    int covisibilityMinShared = 15;  //!< points two keyframes share to get a co-visibility edge (ORB-SLAM: 15)
    double cullObservedShare = 0.9;  //!< culling: share of points seen by cullMinObservers others (ORB-SLAM)
    int cullMinObservers = 3;        //!< culling: keyframes from outside the window that see a point (ORB-SLAM: 3)
    double reuseRadiusPx = 10.;      //!< search radius of a projected global point, pixels at 640 px width
    int reuseMaxDistance = 50;       //!< Hamming distance accepted at most (ORB-SLAM TH_LOW)
    double reuseRatio = 0.8;         //!< best distance below this times the second best (ORB-SLAM map search)
    int reuseMaxKeyframes = 10;      //!< stored keyframes searched per new keyframe (most overlapping first)
    double fusionSigmas = 2.;        //!< late fusion: projected depth within this many standard deviations
    bool reuse = true;               //!< re-use global points in the window (off: the map is kept, not re-used)
    double priorVarianceScale = 10.; //!< re-used depth variance factor (> 1: trust less; docs/global-map-and-loops.md)
    //! A re-used point is measured against its stored keyframe in the window (held fixed), which ties the window to
    //! the stored map (off: only an inverse-depth prior in its new host). Off by default: it registers later laps
    //! onto the first, but lost tracking more often (docs/global-map-and-loops.md).
    bool anchors = false;
    double anchorPixelWeight = 100.; //!< anchor energy per squared pixel, window units (grey levels squared)
    double anchorHuberPx = 2.;       //!< Huber threshold of an anchor's pixel residual
    int anchorMinForScale = 10;      //!< anchored points that make the window's scale observable (no scale gauge)
    double anchorMaxErrorPx = 4.;    //!< after an optimisation, anchors farther than this from their pixel are dropped
  };

  /*!
    Loop detection and verification (system.mode = slam): bag-of-words candidates consistent over several
    keyframes, ORB matching of the two sides' points, Sim(3) RANSAC (defaults: ORB-SLAM2's LoopClosing).
  */
  struct Loop {
    int consistency = 3;          //!< consecutive keyframes whose candidates agree before a loop is verified
    int minKeyframesBetween = 10; //!< keyframes after the map's start (or the last loop) before detecting
    int matchMaxDistance = 50;    //!< Hamming distance accepted at most (ORB-SLAM TH_LOW)
    double matchRatio = 0.75;     //!< best distance below this times the second best (ORB-SLAM loop search)
    int minMatches = 20;          //!< ORB matches needed to try the Sim(3) (ORB-SLAM: 20)
    //! Sim(3) inliers needed to accept a loop, after guided matching (ORB-SLAM: 40 after its projection search). 20
    //! let a wrong loop through on Tsukuba played there and back (25 inliers, 26 degrees); right ones had 67-552.
    int minInliers = 40;
    double ransacThresholdPx = 3.035;      //!< Sim(3) inlier reprojection error in both images, pixels (sqrt 9.21)
    double maxRotationCorrectionDeg = 30.; //!< a loop rotating the map more than this is refused (aliasing)
    //! ORB keypoints detected in each keyframe that leaves the window, for place recognition and verification (only
    //! those given a depth by the window are kept; loop/LoopFeatures.h). 0: no loop closure.
    int featuresPerKeyframe = 500;
    //! After a loop's pose graph, refine stored poses and depths (background). Off by default: its measurements are
    //! the window's own projections at marginalisation, so it adds little the pose graph has not used and partly
    //! undoes the correction (measured: docs/global-map-and-loops.md).
    bool globalBundleAdjustment = false;
    int globalBaIterations = 10;         //!< Levenberg-Marquardt iterations of the global bundle adjustment
    double globalBaHuberPx = 2.;         //!< Huber threshold of its reprojection errors, pixels
    int globalBaPointsPerKeyframe = 100; //!< points of each stored keyframe it adjusts (most observed; 0 = all)
  };

  /*!
    The metric frame from an AprilTag (vpHSlam::setTag(); docs/metric-tag-frame.md): how the tag's sightings in
    keyframes are fitted to the keyframes' poses (a similarity), and when the fit is trusted.
  */
  struct TagFrame {
    int minSightings = 3; //!< sightings (keyframes that saw the tag) kept by the fit before the output is metric
    //! Relative standard deviation of the fitted scale (from the fit's residuals and the sightings' spread) under
    //! which the output is metric. 1 %: the acceptance of the issue that asked for the tag frame.
    double maxScaleUncertainty = 0.01;
    //! A sighting whose rotation disagrees with the others' consensus by more than this is refused, degrees (the
    //! detector's orientation is good to 1-2 degrees; a flipped, ambiguous pose is off by tens).
    double outlierRotationDeg = 5.;
    //! A sighting whose camera position misses the fit by more than this share of its distance to the tag (or 3
    //! robust standard deviations, whichever is larger) is refused.
    double outlierDistanceShare = 0.03;
  };

  //! System-wide behaviour.
  struct System {
    Mode mode = modeSlam;                  //!< see Mode (docs/accuracy-and-speed.md, "Defaults": why slam)
    bool deterministic = false;            //!< map in the caller's thread: identical output run to run
    int workerThreads = 0;                 //!< threads for residual accumulation (0 = off, run in the caller)
    bool usePhotometricCalibration = true; //!< use G, V, exposure when the source has them
    int maxTrackingFailures = 3;           //!< failed alignments in a row (pose predicted, DSO) before tracking is lost
    bool localizationOnly = false;         //!< locate each frame in a loaded map (vpHSlam::loadMap), never change it
  };

  Features features;       //!< point selection
  Tracker tracker;         //!< pose tracking
  Mapper mapper;           //!< window optimisation and point management
  Initializer initializer; //!< monocular initialisation
  Tracking tracking;       //!< hybrid tracking and relocalisation
  GlobalMap globalMap;     //!< global map re-use and connectivity graph
  Loop loop;               //!< loop detection and verification
  TagFrame tagFrame;       //!< metric frame from an AprilTag (vpHSlam::setTag())
  System system;           //!< system-wide behaviour

  /*!
    Read settings from a YAML file written by save() (or by hand). Missing fields keep their values.

    Format (OpenCV FileStorage YAML, see data/hslam-default.yaml): line 1 is "%YAML:1.0"; one map per section
    (features, tracker, mapper, initializer, tracking, globalMap, loop, system) whose keys are the member names;
    booleans are true/false, the modes are their modeName() / trackingModeName(), vectors are [ 1, 2 ]. Comments go on
    their own line (OpenCV's reader keeps an end-of-line comment inside an unquoted word). The whole file is checked
    before anything is assigned: on error the object is unchanged. \exception vpHSlamException::fileNotFound, parseError
    (unknown section or key, repeated key, wrong type, malformed YAML), invalidArgument (value out of range), naming the
    file and the key.
  */
  void load(const std::string &path);
  //! Write every setting to a YAML file. \exception vpHSlamException::fileUnreadable when it cannot be written.
  void save(const std::string &path) const;
  //! Print every setting with its documentation line.
  void print(std::ostream &os) const;
  /*!
    Check every value is in range.
    \exception vpHSlamException::invalidArgument naming the field.
  */
  void validate() const;

  //! "vo-strict", "vo-reuse", "slam".
  static std::string modeName(Mode mode);
  //! Inverse of modeName(). \exception vpHSlamException::invalidArgument on an unknown name.
  static Mode parseMode(const std::string &name);
  //! "direct", "indirect", "hybrid".
  static std::string trackingModeName(TrackingMode mode);
  //! Inverse of trackingModeName(). \exception vpHSlamException::invalidArgument on an unknown name.
  static TrackingMode parseTrackingMode(const std::string &name);
};

#endif
