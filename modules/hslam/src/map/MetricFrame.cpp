#include "map/MetricFrame.h"

#include "math/ViSPConversions.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

namespace hslam
{
namespace
{
// Fewest residual coordinates minus unknowns (3 per view, 7 of the similarity) the residual sigma is computed from.
constexpr int kMinResidualDof = 1;
// The residual sigma is at least this share of the mean range to the tag: the detector's position precision.
constexpr double kDetectorPrecisionShare = 0.003;
constexpr int kPositionRounds = 3;
// Joint refinement (step 3): Gauss-Newton iterations, and the standard deviation given to a sighting's orientation
// against its camera position's (kDetectorPrecisionShare of its range): the detector's measured accuracies on a
// 45-60 pixel tag (test_tag_detector: 0.3-0.4 % of the range, 1-1.3 degrees).
constexpr int kRefineIterations = 5;
constexpr double kRotationSigmaRad = 1.5 * M_PI / 180.;
// The tag's depth in the map is trusted to no better than this relative standard deviation (the points' own
// inverse-depth noise, averaged).
constexpr double kDepthScaleFloor = 0.003;
constexpr double kRadToDeg = 180. / M_PI;

double median(std::vector<double> v)
{
  if (v.empty()) {
    return 0.;
  }
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(mid), v.end());
  return v[mid];
}

Eigen::Matrix3d skew(const Eigen::Vector3d &v)
{
  Eigen::Matrix3d S;
  S << 0., -v.z(), v.y(), v.z(), 0., -v.x(), -v.y(), v.x(), 0.;
  return S;
}

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
} // namespace

MetricFit fitMetricFrame(const std::vector<TagView> &views, bool tagFrame, const vpHSlamParameters::TagFrame &options)
{
  MetricFit fit;
  fit.tagFrame = tagFrame;
  fit.sightings = static_cast<unsigned int>(views.size());
  fit.inlier.assign(views.size(), false);
  if (views.size() < 2) {
    return fit;
  }
  // Step 1: rotation.
  std::vector<Eigen::Quaterniond> proposals;
  std::vector<Eigen::Vector3d> p, q;
  std::vector<double> range;
  for (const TagView &v : views) {
    const SE3d tMc = v.cMt.inverse();
    proposals.push_back((tMc.unitQuaternion() * v.wMc.unitQuaternion().conjugate()).normalized());
    p.push_back(v.wMc.translation());
    q.push_back(tMc.translation());
    range.push_back(tMc.translation().norm());
  }
  std::vector<bool> &inlier = fit.inlier;
  const Eigen::Quaterniond Rq0 = rotationConsensus(proposals, options.outlierRotationDeg / kRadToDeg, inlier);
  const Eigen::Matrix3d R = Rq0.toRotationMatrix();

  // The tag's depth in the map (TagView::depthScale): a robust mean over the rotation inliers that have one.
  double depthScale = 0., depthSigma = 0.; // relative standard deviation of depthScale
  {
    std::vector<double> samples;
    for (size_t i = 0; i < views.size(); ++i) {
      if (inlier[i] && views[i].depthScale > 0.) {
        samples.push_back(views[i].depthScale);
      }
    }
    const double mid = median(samples);
    double sum = 0., sq = 0.;
    int m = 0;
    for (double d : samples) {
      if (std::fabs(d / mid - 1.) <= options.outlierDistanceShare) {
        sum += d;
        sq += d * d;
        ++m;
      }
    }
    if (m >= 2) {
      depthScale = sum / m;
      const double var = std::max(0., sq / m - depthScale * depthScale);
      depthSigma = std::max(kDepthScaleFloor, std::sqrt(var / (m - 1)) / depthScale);
    }
  }
  fit.depthScale = depthScale;

  // Step 2: scale and translation with R held (the scale too when the map gave the tag's depth); refuse the
  // sightings that miss, fit again.
  double s = depthScale > 0. ? depthScale : 1.;
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (int round = 0; round < kPositionRounds; ++round) {
    Eigen::Vector3d pMean = Eigen::Vector3d::Zero(), qMean = Eigen::Vector3d::Zero();
    int n = 0;
    for (size_t i = 0; i < views.size(); ++i) {
      if (inlier[i]) {
        pMean += p[i];
        qMean += q[i];
        ++n;
      }
    }
    if (n < 2) {
      return fit;
    }
    pMean /= n;
    qMean /= n;
    double num = 0., den = 0.;
    for (size_t i = 0; i < views.size(); ++i) {
      if (inlier[i]) {
        const Eigen::Vector3d rp = R * (p[i] - pMean);
        num += rp.dot(q[i] - qMean);
        den += rp.squaredNorm();
      }
    }
    if (depthScale <= 0.) {
      if (!(den > 0.) || !(num > 0.)) {
        return fit; // the keyframes did not move (or moved against the tag's evidence): no scale
      }
      s = num / den;
    }
    t = qMean - s * R * pMean;
    std::vector<double> residuals;
    for (size_t i = 0; i < views.size(); ++i) {
      if (inlier[i]) {
        residuals.push_back((s * R * p[i] + t - q[i]).norm());
      }
    }
    const double robustSigma = 1.4826 * median(residuals);
    bool changed = false;
    for (size_t i = 0; i < views.size(); ++i) {
      const double limit = std::max(3. * robustSigma, options.outlierDistanceShare * range[i]);
      const bool keep = inlier[i] && (s * R * p[i] + t - q[i]).norm() <= limit;
      changed = changed || keep != inlier[i];
      inlier[i] = keep;
    }
    if (!changed) {
      break;
    }
  }

  // Step 3: every kept sighting's position and orientation together (Gauss-Newton on R (left increment), t and
  // log s), each weighted by the detector's precision; the scale's uncertainty from the resulting information,
  // inflated when the residuals are larger than those precisions say.
  Eigen::Quaterniond Rq = Rq0;
  Eigen::Matrix<double, 7, 7> H = Eigen::Matrix<double, 7, 7>::Zero(); // positions and orientations
  double chi2 = 0.;
  int n = 0;
  for (int iteration = 0; iteration <= kRefineIterations; ++iteration) {
    const Eigen::Matrix3d R = Rq.toRotationMatrix();
    H.setZero();
    Eigen::Matrix<double, 7, 1> g = Eigen::Matrix<double, 7, 1>::Zero();
    chi2 = 0.;
    n = 0;
    // The tag's depth in the map, on log s.
    double depthInformation = 0., depthGradient = 0.;
    if (depthScale > 0.) {
      depthInformation = 1. / (depthSigma * depthSigma);
      depthGradient = std::log(s / depthScale) * depthInformation;
    }
    for (size_t i = 0; i < views.size(); ++i) {
      if (!inlier[i]) {
        continue;
      }
      ++n;
      const double sigma = kDetectorPrecisionShare * range[i];
      const Eigen::Vector3d sRp = s * (R * p[i]);
      const Eigen::Vector3d e = (sRp + t - q[i]) / sigma;
      Eigen::Matrix<double, 3, 7> J;
      J.block<3, 3>(0, 0) = -skew(sRp) / sigma;
      J.block<3, 3>(0, 3) = Eigen::Matrix3d::Identity() / sigma;
      J.col(6) = sRp / sigma;
      H += J.transpose() * J;
      g += J.transpose() * e;
      chi2 += e.squaredNorm();
      // Orientation: log(R_i R^T) with R <- exp(d) R gives d(-log) ~ -d.
      const Eigen::AngleAxisd aa(proposals[i] * Rq.conjugate());
      const Eigen::Vector3d f = aa.angle() * aa.axis() / kRotationSigmaRad;
      H.block<3, 3>(0, 0) += Eigen::Matrix3d::Identity() / (kRotationSigmaRad * kRotationSigmaRad);
      g.head<3>() -= f / kRotationSigmaRad;
      chi2 += f.squaredNorm();
    }
    if (n < 2 || iteration == kRefineIterations) {
      break;
    }
    Eigen::Matrix<double, 7, 7> Hall = H;
    Hall(6, 6) += depthInformation;
    g(6) += depthGradient;
    const Eigen::Matrix<double, 7, 1> dx = Hall.ldlt().solve(-g);
    if (!dx.allFinite()) {
      break;
    }
    const Eigen::Vector3d dTheta = dx.head<3>();
    const double angle = dTheta.norm();
    if (angle > 0.) {
      Rq = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, dTheta / angle)) * Rq).normalized();
    }
    t += dx.segment<3>(3);
    s *= std::exp(dx(6));
  }
  if (n < 2) {
    return fit;
  }
  double sq = 0., angles = 0.;
  for (size_t i = 0; i < views.size(); ++i) {
    if (inlier[i]) {
      sq += (s * (Rq * p[i]) + t - q[i]).squaredNorm();
      angles += std::pow(Rq.angularDistance(proposals[i]), 2);
    }
  }
  // The sightings' own noise, from their residuals (at least the detector's); the depth has its own spread.
  const int dof = std::max(kMinResidualDof, 6 * n - 7);
  const double inflation = std::max(1., std::sqrt(chi2 / dof));
  Eigen::Matrix<double, 7, 7> information = H / (inflation * inflation);
  if (depthScale > 0.) {
    information(6, 6) += 1. / (depthSigma * depthSigma);
  }
  const Eigen::Matrix<double, 7, 7> covariance = information.inverse();
  fit.kept = static_cast<unsigned int>(n);
  fit.scale = s;
  fit.rmsMetres = std::sqrt(sq / n);
  fit.rotationSpreadDeg = std::sqrt(angles / n) * kRadToDeg;
  // Relative standard deviation of s = that of log s.
  fit.scaleUncertainty = covariance(6, 6) > 0. && std::isfinite(covariance(6, 6)) ? std::sqrt(covariance(6, 6)) : 1.;
  fit.mSw = tagFrame ? Sim3d(Rq, t, s) : Sim3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), s);
  fit.metric = n >= options.minSightings && fit.scaleUncertainty <= options.maxScaleUncertainty;
  for (size_t i = 0; i < views.size(); ++i) {
    VP_HSLAM_LOG(vpHSlamLog::debug, "tag sighting " << i << (inlier[i] ? "" : " (refused)") << ": range " << range[i]
                                                    << " m, position residual " << (s * (Rq * p[i]) + t - q[i]).norm()
                                                    << " m, rotation " << Rq.angularDistance(proposals[i]) * kRadToDeg
                                                    << " deg, depth scale " << views[i].depthScale << " ("
                                                    << views[i].depthPoints << " points)");
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "metric fit: " << n << " of " << views.size() << " sightings, scale " << s << " +- "
                                                 << 100. * fit.scaleUncertainty
                                                 << " % (tag depth in the map: " << depthScale << " +- "
                                                 << 100. * depthSigma << " %), rms " << fit.rmsMetres
                                                 << " m, rotation spread " << fit.rotationSpreadDeg << " deg");
  return fit;
}

SE3d outputPose(const MetricFit &fit, const SE3d &wMc)
{
  if (!fit.metric) {
    return wMc;
  }
  return SE3d(fit.mSw.unitQuaternion() * wMc.unitQuaternion(), fit.mSw * wMc.translation());
}

Eigen::Vector3d outputPoint(const MetricFit &fit, const Eigen::Vector3d &pw)
{
  return fit.metric ? Eigen::Vector3d(fit.mSw * pw) : pw;
}

MapMetricFrame toMapMetricFrame(const MetricFit &fit)
{
  MapMetricFrame m;
  m.present = fit.metric;
  if (fit.metric) {
    m.tagFrame = fit.tagFrame;
    m.segment = static_cast<int>(fit.segment);
    m.oMw = SE3d(fit.mSw.unitQuaternion(), fit.mSw.translation());
    m.scale = fit.mSw.scale();
    m.scaleUncertainty = fit.scaleUncertainty;
  }
  return m;
}

MetricFit fromMapMetricFrame(const MapMetricFrame &frame)
{
  MetricFit fit;
  if (frame.present) {
    fit.metric = true;
    fit.tagFrame = frame.tagFrame;
    fit.segment = static_cast<unsigned int>(frame.segment);
    fit.mSw = Sim3d(frame.oMw.unitQuaternion(), frame.oMw.translation(), frame.scale);
    fit.scale = frame.scale;
    fit.scaleUncertainty = frame.scaleUncertainty;
  }
  return fit;
}

MetricFrame::MetricFrame(const vpHSlamTag &tag, const vpHSlamParameters::TagFrame &options)
    : m_tag(tag), m_options(options)
{
}

void MetricFrame::setTag(const vpHSlamTag &tag, const vpHSlamParameters::TagFrame &options, const vpCameraParameters &K)
{
  std::lock_guard<std::mutex> detectorLock(m_detectorMutex);
  m_detector.reset(tag.isSet() ? new TagDetector(tag, K) : nullptr);
  std::lock_guard<std::mutex> lock(m_mutex);
  m_tag = tag;
  m_options = options;
  m_K = K;
  m_sightings.clear();
  m_fit = MetricFit();
  m_detectionMsTotal = 0.;
  m_detections = 0;
}

vpHSlamTag MetricFrame::tag() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_tag;
}

bool MetricFrame::enabled() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_tag.isSet();
}

void MetricFrame::observeKeyframe(int keyframeId, unsigned int segment, const vpImage<unsigned char> &image,
                                  const PoseLookup &keyframePose, const PointLookup &windowPoints)
{
  {
    std::lock_guard<std::mutex> detectorLock(m_detectorMutex);
    if (!m_detector) {
      return;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<TagSighting> sightings = m_detector->detect(image);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    addSightings(keyframeId, segment, sightings);
    std::lock_guard<std::mutex> lock(m_mutex);
    m_detectionMsTotal += ms;
    ++m_detections;
  }
  refit(keyframePose, windowPoints);
}

double MetricFrame::detectionMsMean() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_detections > 0 ? m_detectionMsTotal / m_detections : 0.;
}

vpHSlamTrajectory MetricFrame::toOutput(const vpHSlamTrajectory &trajectory) const
{
  const MetricFit fit = current();
  if (!fit.metric) {
    return trajectory;
  }
  vpHSlamTrajectory out;
  for (size_t i = 0; i < trajectory.size(); ++i) {
    out.add(trajectory.getTimestamp(i), toVpHomogeneousMatrix(outputPose(fit, toSE3(trajectory.get_wMc(i)))));
  }
  return out;
}

void MetricFrame::addSightings(int keyframeId, unsigned int segment, const std::vector<TagSighting> &sightings)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  for (const TagSighting &s : sightings) {
    m_sightings.push_back(Stored{keyframeId, segment, s.id, s.cMt, s.corners, 0., 0});
  }
}

bool MetricFrame::measureDepthScale(const Stored &sighting, const SE3d &wMc, const std::vector<Eigen::Vector3d> &points,
                                    double &scale, int &count) const
{
  const SE3d cMw = wMc.inverse();
  // The tag plane in the camera: normal n through the tag's centre c (metres).
  const Eigen::Vector3d n = sighting.cMt.rotationMatrix().col(2), c = sighting.cMt.translation();
  const double nc = n.dot(c);
  const double px = m_K.get_px(), py = m_K.get_py(), u0 = m_K.get_u0(), v0 = m_K.get_v0();
  std::vector<double> ratios;
  for (const Eigen::Vector3d &pw : points) {
    const Eigen::Vector3d pc = cMw * pw;
    if (pc.z() <= 0.) {
      continue;
    }
    const Eigen::Vector2d uv(u0 + px * pc.x() / pc.z(), v0 + py * pc.y() / pc.z());
    // Inside the (convex) quad: the same side of its four edges.
    int positive = 0, negative = 0;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d &a = sighting.corners[static_cast<size_t>(k)];
      const Eigen::Vector2d &b = sighting.corners[static_cast<size_t>((k + 1) % 4)];
      const double cross = (b - a).x() * (uv - a).y() - (b - a).y() * (uv - a).x();
      (cross >= 0. ? positive : negative) += 1;
    }
    if (positive != 4 && negative != 4) {
      continue;
    }
    const Eigen::Vector3d ray((uv.x() - u0) / px, (uv.y() - v0) / py, 1.);
    const double nr = n.dot(ray);
    if (std::fabs(nr) < 1e-6) {
      continue;
    }
    const double metricDepth = nc / nr;
    if (metricDepth > 0.) {
      ratios.push_back(metricDepth / pc.z());
    }
  }
  count = static_cast<int>(ratios.size());
  if (count < kMinDepthPoints) {
    return false;
  }
  scale = median(ratios);
  return true;
}

void MetricFrame::refit(const PoseLookup &keyframePose, const PointLookup &windowPoints)
{
  std::vector<Stored> sightings;
  bool tagFrame = false;
  vpHSlamParameters::TagFrame options;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    sightings = m_sightings;
    tagFrame = m_tag.hasId();
    options = m_options;
  }
  // The newest segment with a sighting; in it, one fit per tag id, the best trusted.
  MetricFit best;
  if (!sightings.empty()) {
    unsigned int segment = 0;
    for (const Stored &s : sightings) {
      segment = std::max(segment, s.segment);
    }
    std::vector<Eigen::Vector3d> points;
    if (windowPoints) {
      windowPoints(points);
    }
    std::map<int, std::vector<TagView>> byTag;
    std::vector<std::pair<size_t, std::pair<double, int>>> measured;
    for (size_t i = 0; i < sightings.size(); ++i) {
      Stored &s = sightings[i];
      SE3d wMc;
      if (s.segment != segment || !keyframePose(s.keyframeId, wMc)) {
        continue;
      }
      double scale = 0.;
      int count = 0;
      if (!points.empty() && measureDepthScale(s, wMc, points, scale, count)) {
        s.depthScale = scale;
        s.depthPoints = count;
        measured.push_back({i, {scale, count}});
      }
      TagView view{wMc, s.cMt};
      view.depthScale = s.depthScale;
      view.depthPoints = s.depthPoints;
      byTag[s.tagId].push_back(view);
    }
    bool first = true;
    best.segment = segment;
    for (const auto &entry : byTag) {
      const MetricFit fit = fitMetricFrame(entry.second, tagFrame, options);
      if (first || (fit.metric && !best.metric) ||
          (fit.metric == best.metric && fit.scaleUncertainty < best.scaleUncertainty)) {
        best = fit;
        best.segment = segment;
        first = false;
      }
    }
    std::lock_guard<std::mutex> lock(m_mutex);
    for (const auto &m : measured) {
      if (m.first < m_sightings.size()) { // the sightings are only appended to (or cleared) meanwhile
        m_sightings[m.first].depthScale = m.second.first;
        m_sightings[m.first].depthPoints = m.second.second;
      }
    }
  }
  std::lock_guard<std::mutex> lock(m_mutex);
  m_fit = best;
}

MetricFit MetricFrame::current() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_fit.metric || !m_loaded.metric ? m_fit : m_loaded;
}

void MetricFrame::setLoaded(const MetricFit &fit)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_loaded = fit;
}

unsigned int MetricFrame::sightingCount() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return static_cast<unsigned int>(m_sightings.size());
}

void MetricFrame::clear()
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_sightings.clear();
  m_fit = MetricFit();
  m_loaded = MetricFit();
}
} // namespace hslam
