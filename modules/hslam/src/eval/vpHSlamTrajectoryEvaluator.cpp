#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

#include "eval/TrajectoryAssociation.h"
#include "eval/TrajectoryMetrics.h"
#include "io/TrajectoryConversion.h"

namespace
{
//! Fewest pairs each alignment needs (Umeyama: 3 non-coincident points; none: 1 pair to measure anything).
constexpr size_t kMinPairsAligned = 3;
constexpr size_t kMinPairsUnaligned = 1;

hslam::AlignmentMode toMode(vpHSlamTrajectoryEvaluator::Alignment alignment)
{
  switch (alignment) {
  case vpHSlamTrajectoryEvaluator::alignNone:
    return hslam::AlignmentMode::none;
  case vpHSlamTrajectoryEvaluator::alignSE3:
    return hslam::AlignmentMode::se3;
  case vpHSlamTrajectoryEvaluator::alignSim3:
    return hslam::AlignmentMode::sim3;
  }
  return hslam::AlignmentMode::sim3;
}

vpHSlamTrajectoryEvaluator::Statistics toStatistics(const hslam::ErrorStatistics &s)
{
  vpHSlamTrajectoryEvaluator::Statistics out;
  out.count = s.count;
  out.rmse = s.rmse;
  out.mean = s.mean;
  out.median = s.median;
  out.max = s.max;
  out.min = s.min;
  out.std = s.std;
  return out;
}

//! Associated pairs as two index-aligned lists.
void matchedPoses(const vpHSlamTrajectory &groundTruth, const vpHSlamTrajectory &estimate,
                  const std::vector<std::pair<size_t, size_t>> &matches, std::vector<hslam::StampedPose> &gt,
                  std::vector<hslam::StampedPose> &est)
{
  gt.clear();
  est.clear();
  gt.reserve(matches.size());
  est.reserve(matches.size());
  for (const auto &m : matches) {
    est.push_back(hslam::toStampedPose(estimate.getTimestamp(m.first), estimate.get_wMc(m.first)));
    gt.push_back(hslam::toStampedPose(groundTruth.getTimestamp(m.second), groundTruth.get_wMc(m.second)));
  }
}
} // namespace

vpHSlamTrajectoryEvaluator::vpHSlamTrajectoryEvaluator(const vpHSlamTrajectory &groundTruth,
                                                       const vpHSlamTrajectory &estimate, double maxTimeDifference)
    : m_groundTruth(groundTruth), m_estimate(estimate), m_maxTimeDifference(maxTimeDifference)
{
  if (!(maxTimeDifference >= 0.)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "trajectory evaluation: max time difference must be >= 0");
  }
  m_matches =
      hslam::associateTimestamps(m_estimate.getTimestamps(), m_groundTruth.getTimestamps(), m_maxTimeDifference);
}

vpHSlamTrajectoryEvaluator::AteResult vpHSlamTrajectoryEvaluator::computeAte(Alignment alignment) const
{
  const size_t needed = alignment == alignNone ? kMinPairsUnaligned : kMinPairsAligned;
  if (m_matches.size() < needed) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "ATE: " + std::to_string(m_matches.size()) + " of " + std::to_string(m_estimate.size()) +
                               " estimate timestamps lie within " + std::to_string(m_maxTimeDifference) +
                               " s of a ground-truth timestamp, at least " + std::to_string(needed) +
                               " are needed (check that both files use seconds and the same clock)");
  }
  std::vector<hslam::StampedPose> gt, est;
  matchedPoses(m_groundTruth, m_estimate, m_matches, gt, est);
  const hslam::AteResult ate = hslam::computeAte(gt, est, toMode(alignment));
  AteResult result;
  result.alignment = alignment;
  result.error = toStatistics(ate.error);
  result.scale = ate.gtTest.scale;
  hslam::StampedPose rigid;
  rigid.wRc = ate.gtTest.R;
  rigid.wtc = ate.gtTest.t;
  result.gMe = hslam::toHomogeneousMatrix(rigid);
  return result;
}

vpHSlamTrajectoryEvaluator::RpeResult vpHSlamTrajectoryEvaluator::computeRpe(double delta, bool byDistance,
                                                                             Alignment alignment) const
{
  RpeResult result;
  result.delta = delta;
  result.byDistance = byDistance;
  result.scale = alignment == alignSim3 ? computeAte(alignSim3).scale : 1.;
  std::vector<hslam::StampedPose> gt, est;
  matchedPoses(m_groundTruth, m_estimate, m_matches, gt, est);
  const hslam::RpeResult rpe = hslam::computeRpe(gt, est, delta, byDistance, result.scale);
  result.translation = toStatistics(rpe.translation);
  result.rotationDeg = toStatistics(rpe.rotationDeg);
  return result;
}

vpHSlamTrajectoryEvaluator::AlignmentErrorResult
vpHSlamTrajectoryEvaluator::computeAlignmentError(double segmentLength) const
{
  std::vector<hslam::StampedPose> gt, est;
  matchedPoses(m_groundTruth, m_estimate, m_matches, gt, est);
  const hslam::MonoAlignmentResult mono =
      hslam::computeMonoAlignmentError(gt, est, hslam::toStampedPoses(m_estimate), segmentLength);
  AlignmentErrorResult result;
  result.segmentLength = segmentLength;
  result.alignmentError = mono.alignmentError;
  result.translationDrift = mono.translationDrift;
  result.rotationDriftDeg = mono.rotationDriftDeg;
  result.scaleDrift = mono.scaleDrift;
  result.startCount = mono.startCount;
  result.endCount = mono.endCount;
  return result;
}

vpHSlamTrajectory vpHSlamTrajectoryEvaluator::getAlignedEstimate(const AteResult &ate) const
{
  std::vector<hslam::StampedPose> poses = hslam::toStampedPoses(m_estimate);
  const hslam::StampedPose gMe = hslam::toStampedPose(0., ate.gMe);
  for (hslam::StampedPose &pose : poses) {
    // A similarity applied to a pose: the camera axes rotate, its centre moves by s R p + t.
    pose.wtc = ate.scale * (gMe.wRc * pose.wtc) + gMe.wtc;
    pose.wRc = gMe.wRc * pose.wRc;
  }
  return hslam::toTrajectory(poses);
}

vpHSlamTrajectoryEvaluator::Alignment vpHSlamTrajectoryEvaluator::alignmentFromString(const std::string &name)
{
  if (name == "none") {
    return alignNone;
  }
  if (name == "se3") {
    return alignSE3;
  }
  if (name == "sim3") {
    return alignSim3;
  }
  throw vpHSlamException(vpHSlamException::invalidArgument,
                         "unknown alignment '" + name + "' (expected sim3, se3 or none)");
}

std::string vpHSlamTrajectoryEvaluator::alignmentToString(Alignment alignment)
{
  switch (alignment) {
  case alignNone:
    return "none";
  case alignSE3:
    return "se3";
  case alignSim3:
    return "sim3";
  }
  return "sim3";
}
