/*
 * H-SLAM for ViSP.
 */
#include "mapping/KeyframeWindow.h"

#include "mapping/AnchorResidual.h"
#include "mapping/InitializationCheck.h"
#include "mapping/SparseIdepthInterpolator.h"
#include "mapping/TwoViewInitializer.h"

#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace hslam
{
namespace
{
//! DSO optimizeImmaturePoint: Gauss-Newton iterations on a point's inverse depth at activation.
constexpr int kActivationIterations = 3;
//! Inlier residuals a candidate needs to be kept on a depth prior while the window is short of points (rotation).
constexpr int kMinRotationPointInliers = 2;
/*!
  DSO makeKeyFrame: window RMSE above which keyframes 2, 3, 4 reveal a failed initialisation. These are DSO's bounds
  for its cameras; the image noise of the first keyframe is added to them in quadrature (initRmseLimit()).
*/
constexpr double kInitRmseLimits[] = {20., 13., 9.};
constexpr int kFirstCheckedKeyframe = 2;

/*!
  The bound on the window RMSE of an early keyframe: DSO's \e limit with the noise of both images a residual compares
  (2 sigma^2) added in quadrature. A correct initialisation on a noisy camera has an RMSE near sqrt(2) sigma from the
  noise alone: with the bare bounds, the synthetic room at noise 4 had every correct initialisation refused and did
  not start before frame 324. For a low-noise camera (sigma 1-2) the bounds move by 1-5 %.
*/
double initRmseLimit(double limit, double noiseSigma)
{
  return std::sqrt(limit * limit + 2. * noiseSigma * noiseSigma);
}
//! Initial points: the interpolated inverse depth is searched over +-this many standard deviations in frame 2.
constexpr double kInitialIntervalSigmas = 2.;
//! ... and at least over +-this fraction of it (interpolation between sparse corners is rough).
constexpr double kInitialIntervalMinRelative = 0.5;
//! Initial points whose interval runs out of the second image: narrowed by this factor, at most this many tries.
constexpr double kInitialIntervalShrink = 0.5;
constexpr int kInitialIntervalAttempts = 3;
//! Interpolation of the two-view points: neighbours used and relative sigma floor (SparseIdepthInterpolator).
constexpr int kInitialNeighbours = 8;
constexpr double kInitialMinRelativeSigma = 0.1;
//! Fewer initial points than this: the initialisation is refused (the tracker needs texture to hold on to).
constexpr int kMinInitialPoints = 100;
//! Seed of a keyframe's pixel selection: its frame id plus this fixed offset (any constant: runs stay reproducible).
constexpr unsigned int kSelectionSeedOffset = 7919u;
} // namespace

KeyframeWindow::KeyframeWindow(const vpHSlamParameters &params, const PinholeIntrinsics &K0, int width, int height,
                               bool photometricCalibration, bool withDescriptors)
    : m_params(params), m_K0(K0), m_width(width), m_height(height), m_tracer(params.mapper, params.tracker),
      m_activation(params.mapper), m_selector(params.features, withDescriptors), m_optimizer(params)
{
  m_optimizer.setPhotometricallyCalibrated(photometricCalibration);
}

// ------------------------------------------------------------------------------------------------ initialisation

bool KeyframeWindow::initialize(const FramePtr &first, int firstKeyframeId, const FramePtr &second,
                                int secondKeyframeId, const TwoViewInitialization &init, const SE3d &wMfirst)
{
  if (init.points.empty()) {
    return false;
  }
  first->cMw = wMfirst.inverse();
  first->affine = AffineBrightness();
  first->keyframeId = firstKeyframeId;
  second->cMw = init.c2Mc1 * first->cMw;
  second->affine = AffineBrightness();
  const std::vector<ImmaturePoint> candidates = traceInitialPoints(*first, *second, init);

  KeyframePtr kf0 = std::make_shared<Keyframe>();
  kf0->frame = first;
  m_optimizer.addKeyframe(kf0);
  KeyframePtr kf1 = std::make_shared<Keyframe>();
  second->keyframeId = secondKeyframeId;
  kf1->frame = second;
  m_optimizer.addKeyframe(kf1);
  for (const ImmaturePoint &pt : candidates) {
    const double idepth = PointActivation::initialIdepth(pt);
    const PointActivationResult r = m_optimizer.optimizeNewPoint(firstKeyframeId, pt.u, pt.v, idepth, pt.patch,
                                                                 pt.patchWeight, kActivationIterations);
    if (!r.accepted) {
      continue;
    }
    MapPoint mp = PointActivation::makeMapPoint(pt);
    mp.idepth = r.idepth;
    mp.idepthVar = 1. / r.idepthHessian;
    kf0->points.push_back(mp);
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "initialisation: " << m_selected.size() << " pixels selected, " << candidates.size()
                                                     << " traced, " << kf0->points.size() << " activated");
  if (static_cast<int>(kf0->points.size()) < kMinInitialPoints) {
    return false;
  }
  m_window.push_back(kf0);
  m_window.push_back(kf1);
  m_keyframesInSegment = 2;
  m_initNoiseSigma = estimateNoiseSigma(first->pyramid.level(0));
  VP_HSLAM_LOG(vpHSlamLog::debug, "initialisation: image noise sigma " << m_initNoiseSigma);
  return true;
}

std::vector<ImmaturePoint> KeyframeWindow::traceInitialPoints(const Frame &first, const Frame &second,
                                                              const TwoViewInitialization &init)
{
  // Inverse-depth prior for any pixel of the first frame from the triangulated matches.
  std::vector<IdepthSample> samples;
  samples.reserve(init.points.size());
  for (const InitialPoint &p : init.points) {
    samples.push_back({p.u, p.v, p.idepth});
  }
  const SparseIdepthInterpolator interpolator(samples, m_width, m_height, kInitialNeighbours, kInitialMinRelativeSigma);
  // Gradient pixels only among the first keyframe's initial points with direct and hybrid tracking (descriptors
  // are still computed). Corners here, high-contrast, first raised the RMSE of DSO's check of the first windows
  // (7scenes_redkitchen_000-299 fed every 6th frame: three correct initialisations in a row refused), and they made
  // five synthetic system tests worse (a two-lap loop 0.027 against 0.019 m median; docs/map-files.md, "Corners of
  // the first keyframe"). Indirect tracking has nothing else to follow, so it gets its corners from the start.
  const bool cornersFirst = m_params.tracking.mode == vpHSlamParameters::trackingIndirect;
  m_selector.select(first.raw, first.pyramid, m_params.features.desiredPointDensity,
                    static_cast<unsigned int>(first.id) + kSelectionSeedOffset, m_selected, m_selectedCorner,
                    cornersFirst ? SharedPointSelector::cornersAndGradients : SharedPointSelector::gradientsOnly);
  // Each selected pixel is searched along its epipolar segment in the second frame around its prior (the tracer
  // does DSO's discrete search + Gauss-Newton), then refined by the window's point optimiser.
  double aji = 1., bji = 0.;
  AffineBrightness::transfer(first.exposure, first.affine, second.exposure, second.affine, aji, bji);
  const TraceContext context = m_tracer.makeContext(first, second, init.c2Mc1, aji, bji, m_K0);
  std::vector<ImmaturePoint> candidates;
  candidates.reserve(m_selected.size());
  TraceStatistics traceStats;
  for (size_t s = 0; s < m_selected.size(); ++s) {
    const SelectedPixel &px = m_selected[s];
    ImmaturePoint pt;
    if (!m_tracer.createImmaturePoint(first, static_cast<float>(px.u), static_cast<float>(px.v), px.level, pt)) {
      continue;
    }
    pt.isCorner = m_selectedCorner[s];
    const IdepthPrior prior = interpolator.query(px.u, px.v);
    double halfWidth =
        std::max(kInitialIntervalSigmas * std::sqrt(prior.idepthVar), kInitialIntervalMinRelative * prior.idepth);
    // The tracer refuses an interval whose near end leaves the second image (DSO: out of bounds); under forward
    // motion that is often only the wide prior's end, so the interval is narrowed around the prior and retried.
    for (int attempt = 0; attempt < kInitialIntervalAttempts; ++attempt, halfWidth *= kInitialIntervalShrink) {
      pt.idepthMin = static_cast<float>(std::max(0., prior.idepth - halfWidth));
      pt.idepthMax = static_cast<float>(prior.idepth + halfWidth);
      pt.lastStatus = TraceStatus::uninitialized;
      if (m_tracer.trace(pt, context) != TraceStatus::outOfBounds) {
        break;
      }
    }
    traceStats.add(pt.lastStatus);
    if (pt.lastStatus != TraceStatus::good && pt.lastStatus != TraceStatus::skipped &&
        pt.lastStatus != TraceStatus::badCondition) {
      continue;
    }
    candidates.push_back(pt);
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "initialisation traces: good "
                                      << traceStats.good << ", skipped " << traceStats.skipped << ", bad condition "
                                      << traceStats.badCondition << ", outlier " << traceStats.outlier
                                      << ", out of bounds " << traceStats.outOfBounds);
  describe(first, candidates, 0);
  return candidates;
}

void KeyframeWindow::addFirstKeyframeCorners()
{
  if (m_params.tracking.mode == vpHSlamParameters::trackingIndirect || m_window.empty()) {
    return; // indirect tracking: the first keyframe has its corners already
  }
  // The first keyframe gets its corners now, as immature points that later frames trace, never activate, and that
  // go into the global map with the keyframe when their depth has converged (marginalize()). Without them its
  // descriptors all sat on edge pixels, which a returning camera's FAST corners rarely meet: a real-time map was
  // relocalised at its start with 21-23 PnP inliers (30 needed) in 8 of 19 runs. Activated like any keyframe's
  // corners they made three synthetic system tests fail (docs/map-files.md, "Corners of the first keyframe").
  Keyframe &kf0 = *m_window.front();
  makeNewImmaturePoints(kf0, /*cornersOnly=*/true);
  for (ImmaturePoint &pt : kf0.immature) {
    pt.descriptorOnly = true;
  }
}

// ------------------------------------------------------------------------------------------------ per keyframe

void KeyframeWindow::trace(const Frame &frame)
{
  for (const KeyframePtr &kf : m_window) {
    if (!kf->immature.empty()) {
      m_tracer.traceAll(kf->immature, *kf->frame, frame);
    }
  }
}

KeyframePtr KeyframeWindow::insertKeyframe(const FramePtr &frame, int keyframeId)
{
  frame->keyframeId = keyframeId;
  KeyframePtr kf = std::make_shared<Keyframe>();
  kf->frame = frame;
  m_optimizer.addKeyframe(kf);
  m_window.push_back(kf);
  ++m_keyframesInSegment;
  activatePoints(*kf);
  return kf;
}

void KeyframeWindow::activatePoints(const Keyframe &newest)
{
  // DSO activatePointsMT: adapt the minimum distance to the active count, distance map over the newest keyframe.
  const int activeCount = activePointCount();
  m_activation.adaptMinDistance(activeCount, m_params.features.desiredPointDensity);
  m_activation.buildDistanceMap(m_window, newest);
  const ActivationPlan plan = m_activation.selectPoints(m_window, newest);
  std::vector<ImmaturePointRef> erase = plan.drop;
  erase.reserve(plan.drop.size() + plan.activate.size());
  // A camera turning in place measures no depth: every candidate fails the Hessian test and the window empties.
  // Then candidates whose residuals agree are kept on a weak prior (mapper.rotationFlowPx).
  const double medianIdepth = m_params.mapper.rotationFlowPx > 0. && activeCount < m_params.features.desiredPointDensity
                                  ? medianActiveIdepth()
                                  : 0.;
  int keptOnPrior = 0;
  for (const ActivationCandidate &c : plan.activate) {
    Keyframe &host = *m_window[static_cast<size_t>(c.ref.windowIndex)];
    const ImmaturePoint &pt = host.immature[static_cast<size_t>(c.ref.pointIndex)];
    PointActivationResult r =
        m_optimizer.optimizeNewPoint(host.id(), pt.u, pt.v, c.idepth, pt.patch, pt.patchWeight, kActivationIterations);
    double priorIdepth = 0., priorWeight = 0.;
    const bool onPrior =
        !r.accepted && activateOnDepthPrior(newest, host, c, medianIdepth, r, priorIdepth, priorWeight);
    if (r.accepted) {
      MapPoint mp = PointActivation::makeMapPoint(pt);
      mp.idepth = r.idepth;
      mp.idepthVar = 1. / r.idepthHessian;
      if (onPrior) {
        mp.idepthPrior = priorIdepth;
        mp.idepthPriorWeight = priorWeight;
        mp.depthFromPrior = true;
        ++keptOnPrior;
      }
      host.points.push_back(mp);
      erase.push_back(c.ref);
    } else if (r.inlierResiduals == 0) {
      erase.push_back(c.ref); // DSO: no good residual at all, the candidate is hopeless
    }
  }
  PointActivation::eraseImmaturePoints(m_window, erase);
  if (keptOnPrior > 0) {
    VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << newest.id() << ": " << keptOnPrior
                                                << " points activated on a depth prior (no baseline)");
  }
}

bool KeyframeWindow::activateOnDepthPrior(const Keyframe &newest, const Keyframe &host, const ActivationCandidate &c,
                                          double medianIdepth, PointActivationResult &r, double &priorIdepth,
                                          double &priorWeight) const
{
  if (!(medianIdepth > 0.) || r.inlierResiduals < kMinRotationPointInliers) {
    return false;
  }
  // The prior: the window's median inverse depth, inside the interval the traces left, one standard deviation the
  // median's size. Only when even that depth would move less than rotationFlowPx from host to newest.
  const double idepth =
      std::min(std::max(medianIdepth, static_cast<double>(c.idepthMin)), static_cast<double>(c.idepthMax));
  const double flowPx = m_K0.fx * (newest.frame->cMw * host.frame->cMw.inverse()).translation().norm() * idepth;
  // The threshold is given at 640 px width: the same motion gives the same decision at any resolution.
  const double maxFlowPx = m_params.mapper.rotationFlowPx * m_width / kReferenceWidthPx;
  if (!(idepth > 0.) || flowPx >= maxFlowPx) {
    return false;
  }
  const ImmaturePoint &pt = host.immature[static_cast<size_t>(c.ref.pointIndex)];
  const double weight = 1. / (medianIdepth * medianIdepth);
  PointActivationResult withPrior = m_optimizer.optimizeNewPoint(host.id(), pt.u, pt.v, idepth, pt.patch,
                                                                 pt.patchWeight, kActivationIterations, idepth, weight);
  if (!std::isfinite(withPrior.energy) || !(withPrior.idepth > 0.) ||
      withPrior.inlierResiduals < kMinRotationPointInliers) {
    return false; // r stays as it was: a refused candidate with inliers is traced on
  }
  withPrior.accepted = true;
  r = withPrior;
  priorIdepth = idepth;
  priorWeight = weight;
  return true;
}

bool KeyframeWindow::segmentMotionConfirmed() const
{
  // Every pair of the young segment's keyframes, newest first, may give its opinion: consecutive keyframes far apart
  // (KITTI every 4th frame) often share too few matches, close ones (Tsukuba every 3rd frame) too little parallax.
  // Not the first two keyframes together: their motion is the initialisation's own two-view result.
  const size_t inSegment = std::min(m_window.size(), static_cast<size_t>(std::max(m_keyframesInSegment, 0)));
  const size_t first = m_window.size() - inSegment;
  int measured = 0;
  for (size_t j = m_window.size() - 1; j > first; --j) {
    for (size_t i = j; i-- > first;) {
      if (i == first && j == first + 1) {
        continue;
      }
      const Frame &a = *m_window[i]->frame, &b = *m_window[j]->frame;
      const TwoViewPoseCheck check = checkPoseByTwoViews(m_params, m_K0, a, b, b.cMw * a.cMw.inverse());
      if (!check.measured) {
        VP_HSLAM_LOG(vpHSlamLog::debug, "keyframes " << m_window[i]->id() << "-" << m_window[j]->id()
                                                     << ": not measured (two-view outcome " << check.outcome << ")");
        continue;
      }
      ++measured;
      VP_HSLAM_LOG(vpHSlamLog::debug, "keyframes " << m_window[i]->id() << "-" << m_window[j]->id()
                                                   << ": two-view geometry " << check.rotationErrorDeg
                                                   << " deg in rotation and " << check.directionErrorDeg
                                                   << " deg in direction from the window's");
      if (!check.agrees) {
        return false;
      }
    }
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << m_window.back()->id()
                                              << ": residual above DSO's initialisation bound, " << measured
                                              << " keyframe pairs measured by their two-view geometry"
                                              << (measured > 0 ? ", all agree: the map is kept" : ""));
  return measured > 0;
}

double KeyframeWindow::medianActiveIdepth() const
{
  std::vector<double> idepths;
  for (const KeyframePtr &kf : m_window) {
    for (const MapPoint &p : kf->points) {
      if (p.status == PointStatus::active && p.idepth > 0.) {
        idepths.push_back(p.idepth);
      }
    }
  }
  if (idepths.empty()) {
    return 0.;
  }
  auto mid = idepths.begin() + static_cast<std::ptrdiff_t>(idepths.size() / 2);
  std::nth_element(idepths.begin(), mid, idepths.end());
  return *mid;
}

void KeyframeWindow::optimize(const Keyframe &kf, const GlobalMap &stored, const std::vector<int> &leaving,
                              bool keepPairs)
{
  refreshAnchors(stored);
  const OptimizationSummary summary = m_optimizer.optimize(m_params.mapper.maxOptimizationIterations);
  const int anchorOutliers = dropAnchorOutliers();
  const double rmse =
      summary.inlierResiduals > 0
          ? std::sqrt(summary.finalPhotometricEnergy / (static_cast<double>(summary.inlierResiduals) * kPatternSize))
          : 0.;
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << kf.id() << ": " << summary.activePoints << " points, "
                                              << summary.iterations << " LM iterations (" << summary.acceptedSteps
                                              << " accepted), rmse " << rmse << ", " << summary.outlierPoints
                                              << " outlier points, " << anchorOutliers << " anchors dropped, "
                                              << summary.totalMs << " ms");
  // DSO makeKeyFrame: a high window RMSE on keyframes 2-4 means the initialisation was wrong, unless the segment's
  // keyframe pairs' own two-view geometry confirms the window's motion (InitializationCheck.h says why).
  const int checked = m_keyframesInSegment - kFirstCheckedKeyframe;
  if (!m_relocalizedInSegment && checked >= 0 &&
      checked < static_cast<int>(sizeof(kInitRmseLimits) / sizeof(kInitRmseLimits[0])) &&
      rmse > initRmseLimit(kInitRmseLimits[checked], m_initNoiseSigma)) {
    m_initializationFailed = !segmentMotionConfirmed();
  }
  m_pendingPairs.clear();
  if (keepPairs) {
    // Pose-pose links of the keyframes about to leave, from this optimisation's linearisation (free now).
    for (int id : leaving) {
      m_pendingPairs[id] = m_optimizer.pairInformation(id);
    }
  }
}

void KeyframeWindow::dropPointsOutOfView(const Keyframe &newest)
{
  // DSO flagPointsForRemoval: a point that no longer projects into the newest keyframe will not be seen again by
  // the window; it leaves the optimisation (its status change releases it from the optimiser).
  const PyramidLevel &level0 = newest.frame->pyramid.level(0);
  for (const KeyframePtr &host : m_window) {
    if (host.get() == &newest) {
      continue;
    }
    const SE3d newMhost = newest.frame->cMw * host->frame->cMw.inverse();
    const Eigen::Matrix3d R = newMhost.rotationMatrix();
    const Eigen::Vector3d t = newMhost.translation();
    for (MapPoint &p : host->points) {
      if (p.status != PointStatus::active) {
        continue;
      }
      if (!(p.idepth > 0.)) {
        p.status = PointStatus::outlier;
        continue;
      }
      const Eigen::Vector3d ray((p.u - m_K0.cx) / m_K0.fx, (p.v - m_K0.cy) / m_K0.fy, 1.);
      const Eigen::Vector3d q = R * ray + t * p.idepth;
      if (!(q.z() > 0.)) {
        p.status = leavingStatus(p);
        continue;
      }
      const double u = m_K0.fx * q.x() / q.z() + m_K0.cx;
      const double v = m_K0.fy * q.y() / q.z() + m_K0.cy;
      if (!level0.isInside(static_cast<float>(u), static_cast<float>(v), static_cast<float>(kPatternPadding))) {
        p.status = leavingStatus(p);
      }
    }
  }
}

void KeyframeWindow::makeNewImmaturePoints(Keyframe &kf, bool cornersOnly)
{
  m_selector.select(kf.frame->raw, kf.frame->pyramid, m_params.features.desiredImmatureDensity,
                    static_cast<unsigned int>(kf.frame->id) + kSelectionSeedOffset, m_selected, m_selectedCorner,
                    cornersOnly ? SharedPointSelector::cornersOnly : SharedPointSelector::cornersAndGradients);
  const size_t begin = kf.immature.size();
  kf.immature.reserve(begin + m_selected.size());
  ImmaturePoint pt;
  for (size_t s = 0; s < m_selected.size(); ++s) {
    const SelectedPixel &px = m_selected[s];
    if (m_tracer.createImmaturePoint(*kf.frame, static_cast<float>(px.u), static_cast<float>(px.v), px.level, pt)) {
      pt.isCorner = m_selectedCorner[s];
      kf.immature.push_back(pt);
    }
  }
  describe(*kf.frame, kf.immature, begin);
}

void KeyframeWindow::describe(const Frame &frame, std::vector<ImmaturePoint> &points, size_t begin)
{
  if (!m_selector.withDescriptors() || begin >= points.size()) {
    return;
  }
  m_describePixels.clear();
  for (size_t i = begin; i < points.size(); ++i) {
    m_describePixels.emplace_back(points[i].u, points[i].v);
  }
  m_selector.describe(frame.raw, m_describePixels, m_describeOut, m_describeValid, m_describeAngles);
  for (size_t i = begin; i < points.size(); ++i) {
    const size_t k = i - begin;
    points[i].hasOrb = m_describeValid[k];
    points[i].orb = m_describeOut[k];
    points[i].orbAngleDeg = m_describeAngles[k];
  }
}

// ------------------------------------------------------------------------------------------------ leaving

KeyframePtr KeyframeWindow::find(int id) const
{
  auto it = std::find_if(m_window.begin(), m_window.end(), [id](const KeyframePtr &kf) { return kf->id() == id; });
  return it == m_window.end() ? nullptr : *it;
}

std::vector<PairInformation> KeyframeWindow::leavingPairs(int id)
{
  auto pending = m_pendingPairs.find(id);
  return pending != m_pendingPairs.end() ? pending->second : m_optimizer.pairInformation(id);
}

void KeyframeWindow::marginalize(int id)
{
  KeyframePtr kf = find(id);
  if (!kf) {
    return;
  }
  m_optimizer.marginalizeKeyframe(id);
  // Descriptor-only immature points whose depth converged become marginalised points (the keyframe leaves now).
  const float minQuality = static_cast<float>(m_params.mapper.minTraceQuality);
  for (const ImmaturePoint &pt : kf->immature) {
    if (pt.descriptorOnly && pt.hasOrb && hasConvergedDepth(pt, minQuality)) {
      MapPoint p = PointActivation::makeMapPoint(pt);
      p.status = PointStatus::marginalized;
      kf->points.push_back(std::move(p));
    }
  }
}

void KeyframeWindow::erase(int id)
{
  m_window.erase(
      std::remove_if(m_window.begin(), m_window.end(), [id](const KeyframePtr &kf) { return kf->id() == id; }),
      m_window.end());
}

PointActivationResult KeyframeWindow::refineNewPoint(int hostId, const ImmaturePoint &pt, double idepth,
                                                     double priorIdepth, double priorWeight) const
{
  return m_optimizer.optimizeNewPoint(hostId, pt.u, pt.v, idepth, pt.patch, pt.patchWeight, kActivationIterations,
                                      priorIdepth, priorWeight);
}

// ------------------------------------------------------------------------------------------------ anchors

int KeyframeWindow::dropAnchorOutliers()
{
  if (!m_params.globalMap.anchors) {
    return 0; // no point carries an anchor
  }
  const double maxError = m_params.globalMap.anchorMaxErrorPx;
  int dropped = 0;
  for (const KeyframePtr &kf : m_window) {
    for (MapPoint &p : kf->points) {
      if (p.anchorKeyframeId < 0 || p.status != PointStatus::active) {
        continue;
      }
      if (!(anchorPixelError(m_K0, kf->frame->cMw, p.u, p.v, p.idepth, p.anchorCMw, p.anchorU, p.anchorV) <=
            maxError)) {
        p.anchorKeyframeId = -1;
        ++dropped;
      }
    }
  }
  return dropped;
}

void KeyframeWindow::refreshAnchors(const GlobalMap &stored)
{
  if (!m_params.globalMap.anchors) {
    return;
  }
  for (const KeyframePtr &kf : m_window) {
    for (MapPoint &p : kf->points) {
      if (p.anchorKeyframeId < 0 || p.status != PointStatus::active) {
        continue;
      }
      const GlobalKeyframe *g = stored.find(p.anchorKeyframeId);
      if (g) {
        p.anchorCMw = g->cMw;
      } else {
        p.anchorKeyframeId = -1;
      }
    }
  }
}

// ------------------------------------------------------------------------------------------------ counts

int KeyframeWindow::activePointCount() const
{
  int n = 0;
  for (const KeyframePtr &kf : m_window) {
    for (const MapPoint &p : kf->points) {
      n += p.status == PointStatus::active ? 1 : 0;
    }
  }
  return n;
}

int KeyframeWindow::immaturePointCount() const
{
  int n = 0;
  for (const KeyframePtr &kf : m_window) {
    n += static_cast<int>(kf->immature.size());
  }
  return n;
}

double KeyframeWindow::memoryBytes() const
{
  double bytes = 0.;
  for (const KeyframePtr &kf : m_window) {
    const ImagePyramid &pyr = kf->frame->pyramid;
    for (int l = 0; l < pyr.numLevels(); ++l) {
      const PyramidLevel &level = pyr.level(l);
      bytes += static_cast<double>(level.color.capacity() * sizeof(Eigen::Vector3f) +
                                   level.gradSq.capacity() * sizeof(float));
    }
    bytes += static_cast<double>(kf->frame->raw.getSize());
    bytes +=
        static_cast<double>(kf->points.capacity() * sizeof(MapPoint) + kf->immature.capacity() * sizeof(ImmaturePoint));
  }
  return bytes;
}

void KeyframeWindow::pointsWorld(std::vector<Eigen::Vector3d> &points, std::vector<int> *status, bool activeOnly) const
{
  for (const KeyframePtr &kf : m_window) {
    const SE3d wMc = kf->frame->cMw.inverse();
    for (const MapPoint &p : kf->points) {
      const bool active = p.status == PointStatus::active;
      if (!(p.idepth > 0.) || p.status == PointStatus::outlier || (activeOnly && !active)) {
        continue;
      }
      const Eigen::Vector3d cX((p.u - m_K0.cx) / m_K0.fx / p.idepth, (p.v - m_K0.cy) / m_K0.fy / p.idepth,
                               1. / p.idepth);
      points.push_back(wMc * cX);
      if (status) {
        status->push_back(active ? 0 : 1);
      }
    }
  }
}
} // namespace hslam
