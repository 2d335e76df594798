#include "eval/TrajectoryMetrics.h"

#include <visp3/hslam/vpHSlamException.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <string>

namespace hslam
{
namespace
{
//! Stamps and path lengths are sums of doubles: 1e-9 s / m of slack keeps "delta = 5 steps" at 5 steps.
constexpr double kDeltaSlack = 1e-9;
constexpr size_t kMinSegmentPairs = 3;
constexpr double kRadToDeg = 180. / M_PI;

void checkSameSize(const std::vector<StampedPose> &groundTruth, const std::vector<StampedPose> &estimate,
                   const char *who)
{
  if (groundTruth.size() != estimate.size()) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string(who) + ": " + std::to_string(estimate.size()) + " estimate poses for " +
                               std::to_string(groundTruth.size()) + " ground-truth poses (must be associated pairs)");
  }
}

std::vector<Eigen::Vector3d> positions(const std::vector<StampedPose> &poses)
{
  std::vector<Eigen::Vector3d> p;
  p.reserve(poses.size());
  for (const StampedPose &pose : poses) {
    p.push_back(pose.wtc);
  }
  return p;
}

//! Rotation angle of a (near) rotation matrix, robust for small angles (through the quaternion).
double rotationAngle(const Eigen::Matrix3d &R)
{
  return Eigen::AngleAxisd(Eigen::Quaterniond(R).normalized()).angle();
}
} // namespace

ErrorStatistics computeErrorStatistics(std::vector<double> errors)
{
  ErrorStatistics stats;
  stats.count = errors.size();
  if (errors.empty()) {
    return stats;
  }
  const double n = static_cast<double>(errors.size());
  double sum = 0.;
  double sumSquares = 0.;
  for (double e : errors) {
    sum += e;
    sumSquares += e * e;
  }
  stats.mean = sum / n;
  stats.rmse = std::sqrt(sumSquares / n);
  double sumDeviation = 0.;
  for (double e : errors) {
    sumDeviation += (e - stats.mean) * (e - stats.mean);
  }
  stats.std = std::sqrt(sumDeviation / n);
  std::sort(errors.begin(), errors.end());
  stats.min = errors.front();
  stats.max = errors.back();
  const size_t mid = errors.size() / 2;
  stats.median = (errors.size() % 2 == 1) ? errors[mid] : 0.5 * (errors[mid - 1] + errors[mid]);
  return stats;
}

AteResult computeAte(const std::vector<StampedPose> &groundTruth, const std::vector<StampedPose> &estimate,
                     AlignmentMode mode)
{
  checkSameSize(groundTruth, estimate, "computeAte");
  if (groundTruth.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "computeAte: no associated pose pair");
  }
  AteResult result;
  result.gtTest = alignUmeyama(positions(estimate), positions(groundTruth), mode);
  result.pairErrors.reserve(estimate.size());
  for (size_t i = 0; i < estimate.size(); ++i) {
    result.pairErrors.push_back((groundTruth[i].wtc - result.gtTest.apply(estimate[i].wtc)).norm());
  }
  result.error = computeErrorStatistics(result.pairErrors);
  return result;
}

RpeResult computeRpe(const std::vector<StampedPose> &groundTruth, const std::vector<StampedPose> &estimate,
                     double delta, bool byDistance, double scale)
{
  checkSameSize(groundTruth, estimate, "computeRpe");
  if (!(delta > 0.)) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "computeRpe: delta must be > 0");
  }
  const size_t n = groundTruth.size();
  // Abscissa along which delta is measured: time, or ground-truth path length.
  std::vector<double> abscissa(n, 0.);
  for (size_t i = 0; i < n; ++i) {
    if (byDistance) {
      abscissa[i] = (i == 0) ? 0. : abscissa[i - 1] + (groundTruth[i].wtc - groundTruth[i - 1].wtc).norm();
    } else {
      abscissa[i] = groundTruth[i].timestamp;
    }
  }
  std::vector<double> translationErrors;
  std::vector<double> rotationErrors;
  size_t j = 0;
  for (size_t i = 0; i < n; ++i) {
    j = std::max(j, i + 1);
    // The abscissa is non-decreasing, so j only moves forward: O(n) overall.
    while (j < n && abscissa[j] - abscissa[i] < delta - kDeltaSlack) {
      ++j;
    }
    if (j >= n) {
      break;
    }
    // c1Mc2 = wMc1^-1 wMc2, for the ground truth and the (scaled) estimate.
    const Eigen::Matrix3d gtR = groundTruth[i].wRc.transpose() * groundTruth[j].wRc;
    const Eigen::Vector3d gtT = groundTruth[i].wRc.transpose() * (groundTruth[j].wtc - groundTruth[i].wtc);
    const Eigen::Matrix3d estR = estimate[i].wRc.transpose() * estimate[j].wRc;
    const Eigen::Vector3d estT = scale * (estimate[i].wRc.transpose() * (estimate[j].wtc - estimate[i].wtc));
    // E = gt^-1 est.
    const Eigen::Matrix3d errR = gtR.transpose() * estR;
    const Eigen::Vector3d errT = gtR.transpose() * (estT - gtT);
    translationErrors.push_back(errT.norm());
    rotationErrors.push_back(rotationAngle(errR) * kRadToDeg);
  }
  RpeResult result;
  result.translation = computeErrorStatistics(translationErrors);
  result.rotationDeg = computeErrorStatistics(rotationErrors);
  return result;
}

MonoAlignmentResult computeMonoAlignmentError(const std::vector<StampedPose> &groundTruth,
                                              const std::vector<StampedPose> &estimate,
                                              const std::vector<StampedPose> &allEstimate, double segmentLength)
{
  checkSameSize(groundTruth, estimate, "computeMonoAlignmentError");
  if (groundTruth.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "computeMonoAlignmentError: no associated pose pair");
  }
  const double tFirst = groundTruth.front().timestamp;
  const double tLast = groundTruth.back().timestamp;
  std::vector<Eigen::Vector3d> startEst, startGt, endEst, endGt;
  for (size_t i = 0; i < groundTruth.size(); ++i) {
    if (groundTruth[i].timestamp <= tFirst + segmentLength) {
      startEst.push_back(estimate[i].wtc);
      startGt.push_back(groundTruth[i].wtc);
    }
    if (groundTruth[i].timestamp >= tLast - segmentLength) {
      endEst.push_back(estimate[i].wtc);
      endGt.push_back(groundTruth[i].wtc);
    }
  }
  if (startEst.size() < kMinSegmentPairs || endEst.size() < kMinSegmentPairs) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "alignment error: the start/end segments of " + std::to_string(segmentLength) + " s hold " +
                               std::to_string(startEst.size()) + "/" + std::to_string(endEst.size()) +
                               " associated poses, at least 3 each are needed");
  }
  MonoAlignmentResult result;
  result.startCount = startEst.size();
  result.endCount = endEst.size();
  result.startAlignment = alignUmeyama(startEst, startGt, AlignmentMode::sim3);
  result.endAlignment = alignUmeyama(endEst, endGt, AlignmentMode::sim3);
  const SimilarityTransform &Ts = result.startAlignment;
  const SimilarityTransform &Te = result.endAlignment;

  double sumSquares = 0.;
  for (const StampedPose &pose : allEstimate) {
    sumSquares += (Ts.apply(pose.wtc) - Te.apply(pose.wtc)).squaredNorm();
  }
  result.alignmentError = allEstimate.empty() ? 0. : std::sqrt(sumSquares / static_cast<double>(allEstimate.size()));

  // T_s T_e^-1: x -> s_s R_s (R_e^T (x - t_e) / s_e) + t_s.
  const double driftScale = Ts.scale / Te.scale;
  const Eigen::Matrix3d driftR = Ts.R * Te.R.transpose();
  const Eigen::Vector3d driftT = Ts.t - driftScale * driftR * Te.t;
  result.scaleDrift = driftScale;
  result.rotationDriftDeg = rotationAngle(driftR) * kRadToDeg;
  result.translationDrift = driftT.norm();
  return result;
}
} // namespace hslam
