/*
 * H-SLAM for ViSP.
 */
/*!
  \file ParameterTable.h
  \brief THE table of vpHSlamParameters: one row per setting (section, key, member, valid range, one-line doc) and
  the order relations between settings. Private to vpHSlamParameters.cpp, which reads, writes, prints and checks
  every setting through it; adding a field to vpHSlamParameters.h means adding its row here.
*/
#ifndef HSLAM_COMMON_PARAMETER_TABLE_H
#define HSLAM_COMMON_PARAMETER_TABLE_H

#include <visp3/hslam/vpHSlamParameters.h>

#include <limits>
#include <variant>
#include <vector>

namespace hslam
{
namespace parameter_table
{
using Params = vpHSlamParameters;

//! Where one setting lives inside a vpHSlamParameters; the alternative says its type (and so its YAML form).
using FieldRef = std::variant<int *, double *, bool *, std::vector<int> *, Params::Mode *, Params::TrackingMode *>;

constexpr double kInf = std::numeric_limits<double>::infinity();

//! Interval a number (or every element of a vector) must lie in. Bools and modes ignore it.
struct Range {
  double lo;
  double hi;
  bool loOpen;
  bool hiOpen;
};

constexpr Range anyValue()
{
  return {-kInf, kInf, false, false};
}
constexpr Range atLeast(double lo)
{
  return {lo, kInf, false, false};
}
constexpr Range positive()
{
  return {0., kInf, true, false};
}
constexpr Range between(double lo, double hi)
{
  return {lo, hi, false, false};
}
constexpr Range openInterval(double lo, double hi)
{
  return {lo, hi, true, true};
}

//! Address of p.*Section.*Member, for any field type of the table.
template <auto Section, auto Member> FieldRef refOf(Params &p)
{
  return &((p.*Section).*Member);
}

//! One row of the table: everything load, save, print and validate need to know about a setting.
struct Field {
  const char *section; //!< YAML top-level map, also the name of the member of vpHSlamParameters
  const char *key;     //!< YAML key, also the name of the member of the section struct
  FieldRef (*ref)(Params &);
  Range range;
  const char *doc; //!< one line, printed after the value
};

// The section and key strings come from the same tokens as the member pointer, so a row can never read one member
// and save it under another's name.
#define HSLAM_PARAM(section, member, range, doc)                                                                       \
  Field                                                                                                                \
  {                                                                                                                    \
#section, #member, &refOf < &Params::section, &decltype(Params::section)::member>, range, doc                      \
  }

// THE table: one row per field of vpHSlamParameters, in header order. Adding a field = adding one row here.
// clang-format off
inline const Field kFields[] = {
  HSLAM_PARAM(features, desiredPointDensity, atLeast(1), "target number of active points in the window"),
  HSLAM_PARAM(features, desiredImmatureDensity, atLeast(1), "candidates selected per new keyframe"),
  HSLAM_PARAM(features, selectionBlockSize, atLeast(1), "block side of the adaptive gradient threshold, pixels"),
  HSLAM_PARAM(features, gradientThresholdAdd, atLeast(0.), "threshold = block median |grad| + this, intensity"),
  HSLAM_PARAM(features, gradientThresholdLevelFactor, positive(), "threshold multiplier per coarser level"),
  HSLAM_PARAM(features, selectionLevels, atLeast(1), "pyramid levels used for point selection"),
  HSLAM_PARAM(features, fastThreshold, between(1, 255), "FAST intensity threshold"),
  HSLAM_PARAM(features, maxCorners, atLeast(0), "FAST corners kept per keyframe"),
  HSLAM_PARAM(features, cornerMinDistance, atLeast(0.), "non-maximum suppression radius of corners, pixels"),
  HSLAM_PARAM(features, cornerShare, between(0., 1.), "hybrid: corners added, at most this share of the budget"),

  HSLAM_PARAM(tracker, maxPyramidLevels, atLeast(1), "upper bound on pyramid levels"),
  HSLAM_PARAM(tracker, minCoarsestPixels, atLeast(1), "a level is added only while it keeps this many pixels"),
  HSLAM_PARAM(tracker, huberThreshold, positive(), "Huber threshold on photometric residuals, intensity"),
  HSLAM_PARAM(tracker, gradientWeightC, positive(), "c of the gradient weight c^2/(c^2+|g|^2), intensity"),
  HSLAM_PARAM(tracker, outlierEnergyPerPixel, positive(), "residual^2 above which a pattern pixel is an outlier"),
  HSLAM_PARAM(tracker, iterationsPerLevel, atLeast(0), "Gauss-Newton iterations per level, finest first"),
  HSLAM_PARAM(tracker, retrackResidualFactor, positive(), "try other motions when residual > this * last"),
  HSLAM_PARAM(tracker, affinePriorA, atLeast(0.), "prior weight on a without calibration (0 = free)"),
  HSLAM_PARAM(tracker, affinePriorB, atLeast(0.), "prior weight on b without calibration (0 = free)"),
  HSLAM_PARAM(tracker, affinePriorACalibrated, atLeast(0.), "prior weight on a with photometric calibration"),
  HSLAM_PARAM(tracker, affinePriorBCalibrated, atLeast(0.), "prior weight on b with photometric calibration"),
  HSLAM_PARAM(tracker, maxShiftWeightT, atLeast(0.), "keyframe: translation flow weight, per (w+h)"),
  HSLAM_PARAM(tracker, maxShiftWeightR, atLeast(0.), "keyframe: rotation flow weight, per (w+h)"),
  HSLAM_PARAM(tracker, maxShiftWeightRT, atLeast(0.), "keyframe: rotation+translation flow weight, per (w+h)"),
  HSLAM_PARAM(tracker, maxAffineWeight, atLeast(0.), "keyframe: brightness change weight"),
  HSLAM_PARAM(tracker, keyframeResidualFactor, positive(), "keyframe when RMSE > this * keyframe's first RMSE"),
  HSLAM_PARAM(tracker, maxFramesBetweenKeyframes, atLeast(0), "force a keyframe after this many frames (0 = never)"),
  HSLAM_PARAM(tracker, coarseCutoffResidual, positive(), "coarse tracking: residuals above this are saturated"),

  HSLAM_PARAM(mapper, windowSize, atLeast(2), "keyframes in the window"),
  HSLAM_PARAM(mapper, minWindowSize, atLeast(2), "marginalisation keeps at least this many keyframes"),
  HSLAM_PARAM(mapper, maxOptimizationIterations, atLeast(1), "LM iterations per new keyframe, at most"),
  HSLAM_PARAM(mapper, minOptimizationIterations, atLeast(0), "LM iterations per new keyframe, at least"),
  HSLAM_PARAM(mapper, initialLambda, atLeast(0.), "initial LM damping"),
  HSLAM_PARAM(mapper, stepConvergenceThreshold, atLeast(0.), "stop when the scaled update norm is below this"),
  HSLAM_PARAM(mapper, minPointsFractionKept, between(0., 1.), "marginalise a keyframe keeping fewer of its points"),
  HSLAM_PARAM(mapper, maxAffineChangeMarginalize, positive(), "marginalise when |a_ji| changes beyond this"),
  HSLAM_PARAM(mapper, minIdepthHessianActivate, atLeast(0.), "inverse-depth Hessian needed to keep a new point"),
  HSLAM_PARAM(mapper, minIdepthHessianMarginalize, atLeast(0.), "below: drop a point instead of marginalising"),
  HSLAM_PARAM(mapper, activationMinDistance, atLeast(0.), "initial distance-map radius for activation, pixels"),
  HSLAM_PARAM(mapper, traceMinImprovementFactor, positive(), "DSO setting_trace_minImprovementFactor"),
  HSLAM_PARAM(mapper, traceSlackInterval, atLeast(0.), "epipolar search interval slack, pixels"),
  HSLAM_PARAM(mapper, traceStepSize, positive(), "epipolar search step, pixels"),
  HSLAM_PARAM(mapper, traceGaussNewtonIterations, atLeast(0), "sub-pixel refinement iterations"),
  HSLAM_PARAM(mapper, traceGaussNewtonThreshold, positive(), "stop refinement below this step, pixels"),
  HSLAM_PARAM(mapper, traceExtraSlackOnThreshold, positive(), "outlier threshold slack for tracing"),
  HSLAM_PARAM(mapper, minTraceQuality, positive(), "quality (second best / best) required to activate"),
  HSLAM_PARAM(mapper, maxTraceInterval, positive(), "interval length below which a point may activate, pixels"),
  HSLAM_PARAM(mapper, outlierResidualFraction, between(0., 1.), "remove a point with more outlier residuals"),
  HSLAM_PARAM(mapper, traceMaxPixelSearch, positive(), "longest epipolar segment searched, per (w+h)"),
  HSLAM_PARAM(mapper, rotationFlowPx, atLeast(0.), "flow below this (px, 640 wide): new point kept on a depth prior"),

  HSLAM_PARAM(initializer, minMatches, atLeast(8), "ORB matches needed to attempt a two-view solution"),
  HSLAM_PARAM(initializer, minParallaxDeg, between(0., 90.), "median triangulation angle required, degrees"),
  HSLAM_PARAM(initializer, ransacThresholdPx, positive(), "RANSAC inlier threshold, pixels"),
  HSLAM_PARAM(initializer, ransacConfidence, openInterval(0., 1.), "RANSAC confidence"),
  HSLAM_PARAM(initializer, maxFramesToInitialize, atLeast(1), "restart with a new first frame after this many"),
  HSLAM_PARAM(initializer, initialIdepth, positive(), "median inverse depth of the first map, 1/m"),
  HSLAM_PARAM(initializer, orbFeatures, atLeast(8), "ORB features per frame while initialising"),

  HSLAM_PARAM(tracking, mode, anyValue(), "direct, indirect, hybrid or adaptive pose tracking"),
  HSLAM_PARAM(tracking, frameFeatures, atLeast(0), "FAST corners described per new frame for matching"),
  HSLAM_PARAM(tracking, frameFastThreshold, between(1, 255), "FAST threshold on new frames"),
  HSLAM_PARAM(tracking, matchRadiusPx, positive(), "ORB search radius around a predicted pixel, pixels"),
  HSLAM_PARAM(tracking, matchMaxDistance, between(0, 256), "Hamming distance accepted at most"),
  HSLAM_PARAM(tracking, matchRatio, openInterval(0., 1.), "best match below this * second best"),
  HSLAM_PARAM(tracking, minMatchesBeforeWidening, atLeast(0), "fewer matches: search again, twice the radius"),
  HSLAM_PARAM(tracking, minGeometricInliers, atLeast(4), "inliers the indirect step needs to give a pose"),
  HSLAM_PARAM(tracking, geometricDepthWeights, anyValue(), "joint step: matches weighted by depth information (eq. 3)"),
  HSLAM_PARAM(tracking, relocalize, anyValue(), "relocalise in the same map before starting a new segment"),
  HSLAM_PARAM(tracking, relocalizationTimeout, atLeast(0.), "seconds seeing features unplaced before a new segment"),
  HSLAM_PARAM(tracking, relocalizationCandidates, atLeast(1), "keyframes tried per lost frame"),
  HSLAM_PARAM(tracking, relocalizationMinInliers, atLeast(6), "PnP inliers needed to accept a relocalisation"),
  HSLAM_PARAM(tracking, relocalizationCheckInliers, atLeast(6), "ORB inliers confirming a relocalised pose"),
  HSLAM_PARAM(tracking, relocalizationMinInlierRatio, between(0., 1.),
              "window relocalisation: share of photometric residuals below the cutoff"),
  HSLAM_PARAM(tracking, relocalizeInWindow, anyValue(), "also relocalise on ORB points triangulated in the window"),
  HSLAM_PARAM(tracking, seedFromStoredMap, anyValue(), "an emptied window is seeded again from the stored map"),
  HSLAM_PARAM(tracking, adaptiveMotionPx, positive(), "adaptive: predicted motion (px at 640) for the geometric term"),

  HSLAM_PARAM(globalMap, covisibilityMinShared, atLeast(1), "points shared for a co-visibility edge"),
  HSLAM_PARAM(globalMap, cullObservedShare, between(0., 1.), "culling: share of points seen by enough others"),
  HSLAM_PARAM(globalMap, cullMinObservers, atLeast(1), "culling: other keyframes that must see a point"),
  HSLAM_PARAM(globalMap, reuseRadiusPx, positive(), "search radius of a projected global point, px at 640 wide"),
  HSLAM_PARAM(globalMap, reuseMaxDistance, between(0, 256), "Hamming distance accepted at most for re-use"),
  HSLAM_PARAM(globalMap, reuseRatio, openInterval(0., 1.), "re-use: best match below this * second best"),
  HSLAM_PARAM(globalMap, reuseMaxKeyframes, atLeast(1), "stored keyframes searched per new keyframe"),
  HSLAM_PARAM(globalMap, fusionSigmas, positive(), "late fusion: depths agree within this many sigmas"),
  HSLAM_PARAM(globalMap, reuse, anyValue(), "re-use global points in the window (off: kept, not re-used)"),
  HSLAM_PARAM(globalMap, priorVarianceScale, positive(), "global depth variances times this when re-used"),
  HSLAM_PARAM(globalMap, anchors, anyValue(), "re-used points measured against their stored keyframe"),
  HSLAM_PARAM(globalMap, anchorPixelWeight, atLeast(0.), "anchor energy per squared pixel (grey levels^2)"),
  HSLAM_PARAM(globalMap, anchorHuberPx, positive(), "Huber threshold of an anchor's pixel residual"),
  HSLAM_PARAM(globalMap, anchorMinForScale, atLeast(1), "anchored points that fix the window's scale"),
  HSLAM_PARAM(globalMap, anchorMaxErrorPx, positive(), "anchors farther than this after optimising are dropped"),

  HSLAM_PARAM(loop, consistency, atLeast(1), "consecutive keyframes agreeing on a loop candidate"),
  HSLAM_PARAM(loop, minKeyframesBetween, atLeast(0), "keyframes after the start or the last loop first"),
  HSLAM_PARAM(loop, matchMaxDistance, between(0, 256), "Hamming distance accepted at most for loop matches"),
  HSLAM_PARAM(loop, matchRatio, openInterval(0., 1.), "loop matches: best below this * second best"),
  HSLAM_PARAM(loop, minMatches, atLeast(3), "ORB matches needed to try a Sim(3)"),
  HSLAM_PARAM(loop, minInliers, atLeast(3), "Sim(3) inliers needed to accept a loop"),
  HSLAM_PARAM(loop, ransacThresholdPx, positive(), "Sim(3) inlier reprojection error, pixels"),
  HSLAM_PARAM(loop, maxRotationCorrectionDeg, between(0., 180.), "loops rotating the map more are refused, deg"),
  HSLAM_PARAM(loop, featuresPerKeyframe, atLeast(0), "ORB keypoints per stored keyframe for loops (0 = off)"),
  HSLAM_PARAM(loop, globalBundleAdjustment, anyValue(), "refine stored poses and depths after a loop correction"),
  HSLAM_PARAM(loop, globalBaIterations, atLeast(1), "iterations of the global bundle adjustment"),
  HSLAM_PARAM(loop, globalBaHuberPx, positive(), "Huber threshold of the global bundle adjustment, pixels"),
  HSLAM_PARAM(loop, globalBaPointsPerKeyframe, atLeast(0), "points per stored keyframe it adjusts (0 = all)"),

  HSLAM_PARAM(tagFrame, minSightings, atLeast(2), "tag sightings the fit keeps before the output is metric"),
  HSLAM_PARAM(tagFrame, maxScaleUncertainty, positive(), "relative scale uncertainty under which it is metric"),
  HSLAM_PARAM(tagFrame, outlierRotationDeg, between(0., 180.), "sightings off the rotation consensus are refused, deg"),
  HSLAM_PARAM(tagFrame, outlierDistanceShare, positive(), "sightings missing the fit by this share of range refused"),

  HSLAM_PARAM(system, mode, anyValue(), "vo-strict, vo-reuse or slam"),
  HSLAM_PARAM(system, deterministic, anyValue(), "map in the caller's thread: identical output run to run"),
  HSLAM_PARAM(system, workerThreads, atLeast(0), "threads for residual accumulation (0 = caller only)"),
  HSLAM_PARAM(system, usePhotometricCalibration, anyValue(), "use G, V, exposure when the source has them"),
  HSLAM_PARAM(system, maxTrackingFailures, atLeast(0), "failed alignments in a row before tracking is lost"),
  HSLAM_PARAM(system, localizationOnly, anyValue(), "locate frames in a loaded map (loadMap), never change it"),
};
// clang-format on
#undef HSLAM_PARAM

//! Relations between two settings of the table: lower <= upper, both named "section.key".
struct Order {
  const char *lower;
  const char *upper;
};
inline const Order kOrders[] = {
    {"mapper.minWindowSize", "mapper.windowSize"},
    {"mapper.minOptimizationIterations", "mapper.maxOptimizationIterations"},
};
} // namespace parameter_table
} // namespace hslam

#endif
