// Trajectory error metrics on associated pose lists: ATE, RPE and the TUM monoVO alignment error.
#ifndef HSLAM_EVAL_TRAJECTORY_METRICS_H
#define HSLAM_EVAL_TRAJECTORY_METRICS_H

#include "eval/TrajectoryAlignment.h"
#include "io/TrajectoryIo.h"

#include <visp3/core/vpConfig.h>

#include <vector>

namespace hslam
{
//! Summary of a list of non-negative errors.
struct ErrorStatistics {
  size_t count = 0;
  double rmse = 0.;
  double mean = 0.;
  double median = 0.; //!< mean of the two middle values for an even count
  double max = 0.;
  double min = 0.;
  double std = 0.; //!< population standard deviation around the mean (as numpy.std in the TUM scripts)
};

//! Statistics of \e errors (empty list: all zero).
VISP_EXPORT ErrorStatistics computeErrorStatistics(std::vector<double> errors);

//! Result of the absolute trajectory error.
struct AteResult {
  ErrorStatistics error;          //!< per-pair position error after alignment, metres
  SimilarityTransform gtTest;     //!< aligned estimate = gtTest(estimate)
  std::vector<double> pairErrors; //!< per matched pair, in the order of the inputs
};

/*!
  ATE on positions: align the estimate positions onto the ground-truth positions (Umeyama, \e mode), then the
  statistics of ||p_gt_i - T(p_est_i)||. Inputs are already associated: element i of both lists is a pair.
*/
VISP_EXPORT AteResult computeAte(const std::vector<StampedPose> &groundTruth, const std::vector<StampedPose> &estimate,
                                 AlignmentMode mode);

//! Result of the relative pose error.
struct RpeResult {
  ErrorStatistics translation; //!< metres
  ErrorStatistics rotationDeg; //!< degrees
};

/*!
  RPE (Sturm et al. 2012, TUM RGB-D benchmark): for each pair i, j = the first later pair whose time
  (byDistance = false) or ground-truth path length (byDistance = true) is at least \e delta further;
  E = (gt_i^-1 gt_j)^-1 (est_i^-1 est_j), errors ||trans(E)|| and angle(E). Estimate translations are multiplied by
  \e scale first (the Sim(3) scale of an alignment; rigid alignment does not change relative poses).
  Inputs are associated and sorted by time.
*/
VISP_EXPORT RpeResult computeRpe(const std::vector<StampedPose> &groundTruth, const std::vector<StampedPose> &estimate,
                                 double delta, bool byDistance, double scale);

//! TUM monoVO alignment error and drifts.
struct MonoAlignmentResult {
  double alignmentError = 0.;         //!< e_align, metres (ground-truth units)
  double translationDrift = 0.;       //!< translation norm of T_s T_e^-1, ground-truth units
  double rotationDriftDeg = 0.;       //!< angle of the drift rotation, degrees
  double scaleDrift = 1.;             //!< s_s / s_e (1 = no scale drift)
  size_t startCount = 0;              //!< matched poses in the start segment
  size_t endCount = 0;                //!< matched poses in the end segment
  SimilarityTransform startAlignment; //!< T_s: estimate to ground truth from the start segment
  SimilarityTransform endAlignment;   //!< T_e: estimate to ground truth from the end segment
};

/*!
  TUM monoVO alignment error (Engel, Usenko, Cremers 2016, "A Photometrically Calibrated Benchmark For Monocular
  Visual Odometry", section 4): align the start segment and the end segment separately with Sim(3), T_s and T_e;
  e_align = sqrt(1/n sum_i ||T_s p_i - T_e p_i||^2) over ALL n estimate positions \e allEstimate (tracked frames).
  Segments: the associated pairs within \e segmentLength seconds of the first, resp. last, associated time. The
  benchmark's ground truth only covers such segments (10-20 s of motion capture at start and end), hence seconds
  rather than a frame count; with a complete ground truth any length works, overlap included.
  Drift: T_drift = T_s T_e^-1 (a ground-truth point taken into the estimate by the end alignment, then back by the
  start alignment; identity without drift): translationDrift is its translation norm, rotationDriftDeg its
  rotation angle, scaleDrift its scale s_s / s_e.
  \throw vpHSlamException (invalidArgument) when a segment has fewer than 3 pairs.
*/
VISP_EXPORT MonoAlignmentResult computeMonoAlignmentError(const std::vector<StampedPose> &groundTruth,
                                                          const std::vector<StampedPose> &estimate,
                                                          const std::vector<StampedPose> &allEstimate,
                                                          double segmentLength);
} // namespace hslam

#endif
