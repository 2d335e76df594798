#include "map/MetricFit.h"

#include "math/SO3.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
// Fewest residual coordinates minus unknowns (3 per view, 7 of the similarity) the residual sigma is computed from.
constexpr int kMinResidualDof = 1;
// The residual sigma is at least this share of the mean range to the tag: the detector's position precision.
constexpr double kDetectorPrecisionShare = 0.003;
constexpr int kPositionRounds = 3;
// Joint refinement (step 4): Gauss-Newton iterations, and the standard deviation given to a sighting's orientation
// against its camera position's (kDetectorPrecisionShare of its range): the detector's measured accuracies on a
// 45-60 pixel tag (test_tag_detector: 0.3-0.4 % of the range, 1-1.3 degrees).
constexpr int kRefineIterations = 5;
constexpr double kRotationSigmaRad = 1.5 * M_PI / 180.;
// The tag's depth in the map is trusted to no better than this relative standard deviation (the points' own
// inverse-depth noise, averaged).
constexpr double kDepthScaleFloor = 0.003;
constexpr double kRadToDeg = 180. / M_PI;

//! Rotation consensus (step 1): marks inliers, returns their mean rotation.
Eigen::Quaterniond rotationConsensus(const std::vector<Eigen::Quaterniond> &proposals, double thresholdRad,
                                     std::vector<bool> &inlier)
{
  const size_t n = proposals.size();
  size_t best = 0;
  int bestCount = -1;
  double bestSpread = 0.;
  for (size_t i = 0; i < n; ++i) {
    int count = 0;
    double spread = 0.;
    for (size_t j = 0; j < n; ++j) {
      const double a = proposals[i].angularDistance(proposals[j]);
      if (a <= thresholdRad) {
        ++count;
        spread += a;
      }
    }
    if (count > bestCount || (count == bestCount && spread < bestSpread)) {
      best = i;
      bestCount = count;
      bestSpread = spread;
    }
  }
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  for (size_t j = 0; j < n; ++j) {
    inlier[j] = proposals[best].angularDistance(proposals[j]) <= thresholdRad;
    if (inlier[j]) {
      const double sign = proposals[best].dot(proposals[j]) < 0. ? -1. : 1.;
      sum += sign * proposals[j].coeffs();
    }
  }
  Eigen::Quaterniond mean;
  mean.coeffs() = sum.normalized();
  return mean;
}

//! What the sightings say, prepared once: rotation proposals, camera centres in the map and in the tag's frame.
struct Evidence {
  std::vector<Eigen::Quaterniond> proposals; //!< R_i = tRc_i wRc_i^T
  std::vector<Eigen::Vector3d> p, q;         //!< camera centres, map (units) and tag's frame (metres)
  std::vector<double> range;                 //!< distance to the tag, metres
  explicit Evidence(const std::vector<TagView> &views)
  {
    for (const TagView &v : views) {
      const SE3d tMc = v.cMt.inverse();
      proposals.push_back((tMc.unitQuaternion() * v.wMc.unitQuaternion().conjugate()).normalized());
      p.push_back(v.wMc.translation());
      q.push_back(tMc.translation());
      range.push_back(tMc.translation().norm());
    }
  }
};

//! The tag's depth in the map: robust mean of the kept sightings' depth scales, and its relative sigma (0, 0: none).
struct DepthScale {
  double scale = 0.;
  double sigma = 0.;
};

DepthScale depthScaleConsensus(const std::vector<TagView> &views, const std::vector<bool> &inlier, double share)
{
  std::vector<double> samples;
  for (size_t i = 0; i < views.size(); ++i) {
    if (inlier[i] && views[i].depthScale > 0.) {
      samples.push_back(views[i].depthScale);
    }
  }
  const double mid = upperMedian(samples);
  double sum = 0., sq = 0.;
  int m = 0;
  for (double d : samples) {
    if (std::fabs(d / mid - 1.) <= share) {
      sum += d;
      sq += d * d;
      ++m;
    }
  }
  DepthScale depth;
  if (m >= 2) {
    depth.scale = sum / m;
    const double var = std::max(0., sq / m - depth.scale * depth.scale);
    depth.sigma = std::max(kDepthScaleFloor, std::sqrt(var / (m - 1)) / depth.scale);
  }
  return depth;
}

/*!
  Step 3: s (held at \e depthScale when > 0) and t with R held, refusing the sightings that miss and fitting again.
  False when fewer than two sightings are left, or the scale cannot be told (no depth scale and no motion).
*/
bool fitPositions(const Evidence &e, const Eigen::Matrix3d &R, double depthScale, double share,
                  std::vector<bool> &inlier, double &s, Eigen::Vector3d &t)
{
  const size_t count = inlier.size();
  s = depthScale > 0. ? depthScale : 1.;
  t = Eigen::Vector3d::Zero();
  for (int round = 0; round < kPositionRounds; ++round) {
    Eigen::Vector3d pMean = Eigen::Vector3d::Zero(), qMean = Eigen::Vector3d::Zero();
    int n = 0;
    for (size_t i = 0; i < count; ++i) {
      if (inlier[i]) {
        pMean += e.p[i];
        qMean += e.q[i];
        ++n;
      }
    }
    if (n < 2) {
      return false;
    }
    pMean /= n;
    qMean /= n;
    double num = 0., den = 0.;
    for (size_t i = 0; i < count; ++i) {
      if (inlier[i]) {
        const Eigen::Vector3d rp = R * (e.p[i] - pMean);
        num += rp.dot(e.q[i] - qMean);
        den += rp.squaredNorm();
      }
    }
    if (depthScale <= 0.) {
      if (!(den > 0.) || !(num > 0.)) {
        return false; // the keyframes did not move (or moved against the tag's evidence): no scale
      }
      s = num / den;
    }
    t = qMean - s * R * pMean;
    std::vector<double> residuals;
    for (size_t i = 0; i < count; ++i) {
      if (inlier[i]) {
        residuals.push_back((s * R * e.p[i] + t - e.q[i]).norm());
      }
    }
    const double robustSigma = 1.4826 * upperMedian(residuals);
    bool changed = false;
    for (size_t i = 0; i < count; ++i) {
      const double limit = std::max(3. * robustSigma, share * e.range[i]);
      const bool keep = inlier[i] && (s * R * e.p[i] + t - e.q[i]).norm() <= limit;
      changed = changed || keep != inlier[i];
      inlier[i] = keep;
    }
    if (!changed) {
      break;
    }
  }
  return true;
}

//! Step 4's state: the similarity, and the sightings' information and chi-square at it (n sightings).
struct Refinement {
  Eigen::Quaterniond Rq;
  double s = 1.;
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 7, 7> H = Eigen::Matrix<double, 7, 7>::Zero(); //!< positions and orientations only
  Eigen::Matrix<double, 7, 1> g = Eigen::Matrix<double, 7, 1>::Zero();
  double chi2 = 0.;
  int n = 0;
};

//! The sightings' normal equations at \e r (its H, g, chi2 and n).
void linearize(const Evidence &e, const std::vector<bool> &inlier, Refinement &r)
{
  const Eigen::Matrix3d R = r.Rq.toRotationMatrix();
  r.H.setZero();
  r.g.setZero();
  r.chi2 = 0.;
  r.n = 0;
  for (size_t i = 0; i < inlier.size(); ++i) {
    if (!inlier[i]) {
      continue;
    }
    ++r.n;
    const double sigma = kDetectorPrecisionShare * e.range[i];
    const Eigen::Vector3d sRp = r.s * (R * e.p[i]);
    const Eigen::Vector3d res = (sRp + r.t - e.q[i]) / sigma;
    Eigen::Matrix<double, 3, 7> J;
    J.block<3, 3>(0, 0) = -so3Hat(sRp) / sigma;
    J.block<3, 3>(0, 3) = Eigen::Matrix3d::Identity() / sigma;
    J.col(6) = sRp / sigma;
    r.H += J.transpose() * J;
    r.g += J.transpose() * res;
    r.chi2 += res.squaredNorm();
    // Orientation: log(R_i R^T) with R <- exp(d) R gives d(-log) ~ -d.
    const Eigen::AngleAxisd aa(e.proposals[i] * r.Rq.conjugate());
    const Eigen::Vector3d f = aa.angle() * aa.axis() / kRotationSigmaRad;
    r.H.block<3, 3>(0, 0) += Eigen::Matrix3d::Identity() / (kRotationSigmaRad * kRotationSigmaRad);
    r.g.head<3>() -= f / kRotationSigmaRad;
    r.chi2 += f.squaredNorm();
  }
}

//! Step 4: Gauss-Newton from \e r, the depth scale a prior on log s; \e r ends linearised at the result.
void refineJointly(const Evidence &e, const std::vector<bool> &inlier, const DepthScale &depth, Refinement &r)
{
  for (int iteration = 0; iteration <= kRefineIterations; ++iteration) {
    linearize(e, inlier, r);
    if (r.n < 2 || iteration == kRefineIterations) {
      return;
    }
    Eigen::Matrix<double, 7, 7> H = r.H;
    Eigen::Matrix<double, 7, 1> g = r.g;
    if (depth.scale > 0.) {
      const double information = 1. / (depth.sigma * depth.sigma);
      H(6, 6) += information;
      g(6) += std::log(r.s / depth.scale) * information;
    }
    const Eigen::Matrix<double, 7, 1> dx = H.ldlt().solve(-g);
    if (!dx.allFinite()) {
      return;
    }
    const Eigen::Vector3d dTheta = dx.head<3>();
    const double angle = dTheta.norm();
    if (angle > 0.) {
      r.Rq = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, dTheta / angle)) * r.Rq).normalized();
    }
    r.t += dx.segment<3>(3);
    r.s *= std::exp(dx(6));
  }
}

void logFit(const std::vector<TagView> &views, const Evidence &e, const std::vector<bool> &inlier, const Refinement &r,
            const DepthScale &depth, const MetricFit &fit)
{
  for (size_t i = 0; i < views.size(); ++i) {
    VP_HSLAM_LOG(vpHSlamLog::debug, "tag sighting "
                                        << i << (inlier[i] ? "" : " (refused)") << ": range " << e.range[i]
                                        << " m, position residual " << (r.s * (r.Rq * e.p[i]) + r.t - e.q[i]).norm()
                                        << " m, rotation " << r.Rq.angularDistance(e.proposals[i]) * kRadToDeg
                                        << " deg, depth scale " << views[i].depthScale << " (" << views[i].depthPoints
                                        << " points)");
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "metric fit: " << r.n << " of " << views.size() << " sightings, scale " << r.s
                                                 << " +- " << 100. * fit.scaleUncertainty
                                                 << " % (tag depth in the map: " << depth.scale << " +- "
                                                 << 100. * depth.sigma << " %), rms " << fit.rmsMetres
                                                 << " m, rotation spread " << fit.rotationSpreadDeg << " deg");
}
} // namespace

double upperMedian(std::vector<double> v)
{
  if (v.empty()) {
    return 0.;
  }
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(mid), v.end());
  return v[mid];
}

MetricFit fitMetricFrame(const std::vector<TagView> &views, bool tagFrame, const vpHSlamParameters::TagFrame &options)
{
  MetricFit fit;
  fit.tagFrame = tagFrame;
  fit.sightings = static_cast<unsigned int>(views.size());
  fit.inlier.assign(views.size(), false);
  if (views.size() < 2) {
    return fit;
  }
  const Evidence e(views);
  std::vector<bool> &inlier = fit.inlier;
  Refinement r;
  r.Rq = rotationConsensus(e.proposals, options.outlierRotationDeg / kRadToDeg, inlier);
  const DepthScale depth = depthScaleConsensus(views, inlier, options.outlierDistanceShare);
  fit.depthScale = depth.scale;
  if (!fitPositions(e, r.Rq.toRotationMatrix(), depth.scale, options.outlierDistanceShare, inlier, r.s, r.t)) {
    return fit;
  }
  refineJointly(e, inlier, depth, r);
  if (r.n < 2) {
    return fit;
  }
  // Step 5: the sightings' own noise, from their residuals (at least the detector's); the depth has its own spread.
  double sq = 0., angles = 0.;
  for (size_t i = 0; i < views.size(); ++i) {
    if (inlier[i]) {
      sq += (r.s * (r.Rq * e.p[i]) + r.t - e.q[i]).squaredNorm();
      angles += std::pow(r.Rq.angularDistance(e.proposals[i]), 2);
    }
  }
  const int dof = std::max(kMinResidualDof, 6 * r.n - 7);
  const double inflation = std::max(1., std::sqrt(r.chi2 / dof));
  Eigen::Matrix<double, 7, 7> information = r.H / (inflation * inflation);
  if (depth.scale > 0.) {
    information(6, 6) += 1. / (depth.sigma * depth.sigma);
  }
  const Eigen::Matrix<double, 7, 7> covariance = information.inverse();
  fit.kept = static_cast<unsigned int>(r.n);
  fit.scale = r.s;
  fit.rmsMetres = std::sqrt(sq / r.n);
  fit.rotationSpreadDeg = std::sqrt(angles / r.n) * kRadToDeg;
  // Relative standard deviation of s = that of log s.
  fit.scaleUncertainty = covariance(6, 6) > 0. && std::isfinite(covariance(6, 6)) ? std::sqrt(covariance(6, 6)) : 1.;
  fit.mSw = tagFrame ? Sim3d(r.Rq, r.t, r.s) : Sim3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), r.s);
  fit.metric = r.n >= options.minSightings && fit.scaleUncertainty <= options.maxScaleUncertainty;
  logFit(views, e, inlier, r, depth, fit);
  return fit;
}
} // namespace hslam
