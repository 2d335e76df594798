/*
 * H-SLAM for ViSP.
 */
#include "system/LocalMapper.h"

#include "system/LocalMapperImpl.h"

#include "features/SharedPointSelector.h"
#include "mapping/ImmaturePointTracer.h"
#include "mapping/PointActivation.h"
#include "mapping/SparseIdepthInterpolator.h"
#include "mapping/TwoViewInitializer.h"
#include "mapping/WindowOptimizer.h"
#include "system/RunStatistics.h"
#include "tracking/CoarseTracker.h"
#include "tracking/RelocalizationIndex.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <vector>

namespace hslam
{
namespace
{
//! DSO optimizeImmaturePoint: Gauss-Newton iterations on a point's inverse depth at activation.
constexpr int kActivationIterations = 3;
//! Inlier residuals a candidate needs to be kept on a depth prior while the window is short of points (rotation).
constexpr int kMinRotationPointInliers = 2;
//! DSO makeCoarseDepthL0: a point's weight in the tracking reference is sqrt(1e-3 * H_idepth).
constexpr double kTrackingWeightScale = 1e-3;
//! Floor on a point's inverse-depth variance when turned into a tracking weight (a zero variance = unknown).
constexpr double kMinIdepthVariance = 1e-12;
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

GlobalMap::Options globalMapOptions(const vpHSlamParameters &params)
{
  const vpHSlamParameters::GlobalMap &g = params.globalMap;
  GlobalMap::Options o;
  o.covisibilityMinShared = g.covisibilityMinShared;
  o.cullObservedShare = g.cullObservedShare;
  o.cullMinObservers = g.cullMinObservers;
  o.windowSize = params.mapper.windowSize;
  return o;
}
} // namespace

LocalMapper::LocalMapper(const vpHSlamParameters &params, const PinholeIntrinsics &K0, int width, int height,
                         bool photometricCalibration, const OrbVocabulary *vocabulary)
    : m_impl(new Impl(params, K0, width, height, photometricCalibration, vocabulary)),
      m_photometricCalibration(photometricCalibration), m_globalMap(globalMapOptions(params))
{
  if (vocabulary && params.system.mode == vpHSlamParameters::modeSlam) {
    m_loop = std::make_unique<LoopCloser>(params.loop, K0, *vocabulary);
  }
}

LocalMapper::~LocalMapper() = default;

void LocalMapper::clear()
{
  // A fresh optimiser and activation state: a new segment shares nothing with the old one.
  std::unique_ptr<Impl> fresh(new Impl(m_impl->params, m_impl->K0, m_impl->width, m_impl->height,
                                       m_photometricCalibration, m_impl->vocabulary));
  m_impl.swap(fresh);
  m_window.clear();
  m_initializationFailed = false;
  if (m_loop) {
    m_loop->clear(); // loops stay within a segment: the old one's features are of no further use
  }
  ++m_segment; // the global map keeps what the old segment stored; re-use stays within a segment
}

// ------------------------------------------------------------------------------------------------ initialisation

bool LocalMapper::initialize(const FramePtr &first, int firstKeyframeId, const FramePtr &second, int secondKeyframeId,
                             const TwoViewInitialization &init, const SE3d &wMfirst)
{
  Impl &m = *m_impl;
  if (init.points.empty()) {
    return false;
  }
  first->cMw = wMfirst.inverse();
  first->affine = AffineBrightness();
  first->keyframeId = firstKeyframeId;
  second->cMw = init.c2Mc1 * first->cMw;
  second->affine = AffineBrightness();

  // Inverse-depth prior for any pixel of the first frame from the triangulated matches.
  std::vector<IdepthSample> samples;
  samples.reserve(init.points.size());
  for (const InitialPoint &p : init.points) {
    samples.push_back({p.u, p.v, p.idepth});
  }
  const SparseIdepthInterpolator interpolator(samples, m.width, m.height, kInitialNeighbours, kInitialMinRelativeSigma);

  KeyframePtr kf0 = std::make_shared<Keyframe>();
  kf0->frame = first;
  // Gradient pixels only among the first keyframe's initial points with direct and hybrid tracking (descriptors
  // are still computed). Corners here, high-contrast, first raised the RMSE of DSO's check of the first windows
  // (7scenes_redkitchen_000-299 fed every 6th frame: three correct initialisations in a row refused), and they made
  // five synthetic system tests worse (a two-lap loop 0.027 against 0.019 m median; docs/map-files.md, "Corners of
  // the first keyframe"). Indirect tracking has nothing else to follow, so it gets its corners from the start.
  const bool cornersFirst = m.params.tracking.mode == vpHSlamParameters::trackingIndirect;
  m.selector.select(first->raw, first->pyramid, m.params.features.desiredPointDensity,
                    static_cast<unsigned int>(first->id) + kSelectionSeedOffset, m.selected, m.selectedCorner,
                    cornersFirst ? SharedPointSelector::cornersAndGradients : SharedPointSelector::gradientsOnly);
  // Each selected pixel is searched along its epipolar segment in the second frame around its prior (the tracer
  // does DSO's discrete search + Gauss-Newton), then refined by the window's point optimiser below.
  const SE3d secondMfirst = init.c2Mc1;
  double aji = 1., bji = 0.;
  AffineBrightness::transfer(first->exposure, first->affine, second->exposure, second->affine, aji, bji);
  const TraceContext context = m.tracer.makeContext(*first, *second, secondMfirst, aji, bji, m.K0);
  std::vector<ImmaturePoint> candidates;
  candidates.reserve(m.selected.size());
  TraceStatistics traceStats;
  for (size_t s = 0; s < m.selected.size(); ++s) {
    const SelectedPixel &px = m.selected[s];
    ImmaturePoint pt;
    if (!m.tracer.createImmaturePoint(*first, static_cast<float>(px.u), static_cast<float>(px.v), px.level, pt)) {
      continue;
    }
    pt.isCorner = m.selectedCorner[s];
    const IdepthPrior prior = interpolator.query(px.u, px.v);
    double halfWidth =
        std::max(kInitialIntervalSigmas * std::sqrt(prior.idepthVar), kInitialIntervalMinRelative * prior.idepth);
    // The tracer refuses an interval whose near end leaves the second image (DSO: out of bounds); under forward
    // motion that is often only the wide prior's end, so the interval is narrowed around the prior and retried.
    for (int attempt = 0; attempt < kInitialIntervalAttempts; ++attempt, halfWidth *= kInitialIntervalShrink) {
      pt.idepthMin = static_cast<float>(std::max(0., prior.idepth - halfWidth));
      pt.idepthMax = static_cast<float>(prior.idepth + halfWidth);
      pt.lastStatus = TraceStatus::uninitialized;
      if (m.tracer.trace(pt, context) != TraceStatus::outOfBounds) {
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
  m.describe(*first, candidates, 0);

  m.optimizer.addKeyframe(kf0);
  KeyframePtr kf1 = std::make_shared<Keyframe>();
  second->keyframeId = secondKeyframeId;
  kf1->frame = second;
  m.optimizer.addKeyframe(kf1);
  for (const ImmaturePoint &pt : candidates) {
    const double idepth = PointActivation::initialIdepth(pt);
    const PointActivationResult r = m.optimizer.optimizeNewPoint(firstKeyframeId, pt.u, pt.v, idepth, pt.patch,
                                                                 pt.patchWeight, kActivationIterations);
    if (!r.accepted) {
      continue;
    }
    MapPoint mp = PointActivation::makeMapPoint(pt);
    mp.idepth = r.idepth;
    mp.idepthVar = 1. / r.idepthHessian;
    kf0->points.push_back(mp);
  }
  VP_HSLAM_LOG(vpHSlamLog::debug,
               "initialisation: " << m.selected.size() << " pixels selected, " << candidates.size() << " traced (good "
                                  << traceStats.good << ", skipped " << traceStats.skipped << ", bad condition "
                                  << traceStats.badCondition << ", outlier " << traceStats.outlier << ", out of bounds "
                                  << traceStats.outOfBounds << "), " << kf0->points.size() << " activated");
  if (static_cast<int>(kf0->points.size()) < kMinInitialPoints) {
    clear();
    return false;
  }
  m_window.push_back(kf0);
  m_window.push_back(kf1);
  m.keyframesInSegment = 2;
  m.initNoiseSigma = estimateNoiseSigma(first->pyramid.level(0));
  VP_HSLAM_LOG(vpHSlamLog::debug, "initialisation: image noise sigma " << m.initNoiseSigma);
  // The second keyframe goes through the ordinary keyframe path from "optimise" on (nothing to trace yet).
  finishKeyframe(kf1);
  if (!cornersFirst) {
    // ... but the first keyframe gets its corners now, as immature points that later frames trace, never activate,
    // and that go into the global map with the keyframe when their depth has converged (marginalize()). Without
    // them its descriptors all sat on edge pixels, which a returning camera's FAST corners rarely meet: a
    // real-time map was relocalised at its start with 21-23 PnP inliers (30 needed) in 8 of 19 runs. Activated like
    // any keyframe's corners they made three synthetic system tests fail (docs/map-files.md, "Corners of the first
    // keyframe").
    makeNewImmaturePoints(*kf0, /*cornersOnly=*/true);
    for (ImmaturePoint &pt : kf0->immature) {
      pt.descriptorOnly = true;
    }
  }
  return true;
}

// ------------------------------------------------------------------------------------------------ per frame

void LocalMapper::traceAll(const Frame &frame)
{
  for (const KeyframePtr &kf : m_window) {
    if (!kf->immature.empty()) {
      m_impl->tracer.traceAll(kf->immature, *kf->frame, frame);
    }
  }
}

void LocalMapper::noteRelocalization()
{
  m_impl->relocalizedInSegment = true;
}

void LocalMapper::makeNonKeyframe(const FramePtr &frame)
{
  traceAll(*frame);
}

void LocalMapper::makeKeyframe(const FramePtr &frame, int keyframeId, int seedKeyframe)
{
  Impl &m = *m_impl;
  const double t0 = threadCpuMs();
  collectGlobalBundleAdjustment(false); // its keyframes' states go out with this keyframe's
  if (seedKeyframe >= 0 && keepsGlobalMap()) {
    // The window could not hold the camera: the keyframe starts it again from the stored map. The old keyframes
    // leave first (into the global map): their few points, seen from a pose that drifted while they emptied,
    // dragged the new keyframe's pose in the window optimisation (3-lap synthetic loop: 3 points moved it 0.5 map
    // units away from where PnP had placed it, and no stored point matched there any more).
    while (!m_window.empty()) {
      marginalize(m_window.front()->id());
    }
  }
  traceAll(*frame);
  const double t1 = threadCpuMs();
  frame->keyframeId = keyframeId;
  KeyframePtr kf = std::make_shared<Keyframe>();
  kf->frame = frame;
  m.optimizer.addKeyframe(kf);
  m_window.push_back(kf);
  ++m.keyframesInSegment;
  activatePoints(*kf);
  const double t2 = threadCpuMs();
  finishKeyframe(kf, seedKeyframe);
  if (m.relocalization) {
    // The keyframe's bag-of-words vector: every selected point's descriptor (from its corners alone the synthetic
    // loop's loops were found less often; docs/hybrid-tracking.md).
    std::vector<OrbDescriptor> descriptors;
    descriptors.reserve(kf->immature.size());
    for (const ImmaturePoint &pt : kf->immature) {
      if (pt.hasOrb) {
        descriptors.push_back(pt.orb);
      }
    }
    m.relocalization->addKeyframe(keyframeId, descriptors);
  }
  closeLoops();
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << keyframeId << " timing: trace " << t1 - t0 << " ms, activation "
                                              << t2 - t1 << " ms, rest " << threadCpuMs() - t2 << " ms");
}

void LocalMapper::activatePoints(const Keyframe &newest)
{
  Impl &m = *m_impl;
  // DSO activatePointsMT: adapt the minimum distance to the active count, distance map over the newest keyframe.
  const int activeCount = activePointCount();
  m.activation.adaptMinDistance(activeCount, m.params.features.desiredPointDensity);
  m.activation.buildDistanceMap(m_window, newest);
  const ActivationPlan plan = m.activation.selectPoints(m_window, newest);
  std::vector<ImmaturePointRef> erase = plan.drop;
  erase.reserve(plan.drop.size() + plan.activate.size());
  // A camera turning in place measures no depth: every candidate fails the Hessian test and the window empties.
  // Then candidates whose residuals agree are kept on a weak prior (mapper.rotationFlowPx).
  const double medianIdepth = m.params.mapper.rotationFlowPx > 0. && activeCount < m.params.features.desiredPointDensity
                                  ? medianActiveIdepth()
                                  : 0.;
  int keptOnPrior = 0;
  for (const ActivationCandidate &c : plan.activate) {
    Keyframe &host = *m_window[static_cast<size_t>(c.ref.windowIndex)];
    const ImmaturePoint &pt = host.immature[static_cast<size_t>(c.ref.pointIndex)];
    PointActivationResult r =
        m.optimizer.optimizeNewPoint(host.id(), pt.u, pt.v, c.idepth, pt.patch, pt.patchWeight, kActivationIterations);
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

bool LocalMapper::activateOnDepthPrior(const Keyframe &newest, const Keyframe &host, const ActivationCandidate &c,
                                       double medianIdepth, PointActivationResult &r, double &priorIdepth,
                                       double &priorWeight) const
{
  const Impl &m = *m_impl;
  if (!(medianIdepth > 0.) || r.inlierResiduals < kMinRotationPointInliers) {
    return false;
  }
  // The prior: the window's median inverse depth, inside the interval the traces left, one standard deviation the
  // median's size. Only when even that depth would move less than rotationFlowPx from host to newest.
  const double idepth =
      std::min(std::max(medianIdepth, static_cast<double>(c.idepthMin)), static_cast<double>(c.idepthMax));
  const double flowPx = m.K0.fx * (newest.frame->cMw * host.frame->cMw.inverse()).translation().norm() * idepth;
  // The threshold is given at 640 px width: the same motion gives the same decision at any resolution.
  const double maxFlowPx = m.params.mapper.rotationFlowPx * m.width / kReferenceWidthPx;
  if (!(idepth > 0.) || flowPx >= maxFlowPx) {
    return false;
  }
  const ImmaturePoint &pt = host.immature[static_cast<size_t>(c.ref.pointIndex)];
  const double weight = 1. / (medianIdepth * medianIdepth);
  PointActivationResult withPrior = m.optimizer.optimizeNewPoint(host.id(), pt.u, pt.v, idepth, pt.patch,
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

double LocalMapper::medianActiveIdepth() const
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

void LocalMapper::finishKeyframe(const KeyframePtr &kf, int seedKeyframe)
{
  Impl &m = *m_impl;
  const double t0 = threadCpuMs();
  const std::vector<int> toMarginalize = m.optimizer.keyframesToMarginalize();
  refreshAnchors();
  const OptimizationSummary summary = m.optimizer.optimize(m.params.mapper.maxOptimizationIterations);
  const int anchorOutliers = dropAnchorOutliers();
  const double rmse =
      summary.inlierResiduals > 0
          ? std::sqrt(summary.finalPhotometricEnergy / (static_cast<double>(summary.inlierResiduals) * kPatternSize))
          : 0.;
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << kf->id() << ": " << summary.activePoints << " points, "
                                              << summary.iterations << " LM iterations (" << summary.acceptedSteps
                                              << " accepted), rmse " << rmse << ", " << summary.outlierPoints
                                              << " outlier points, " << anchorOutliers << " anchors dropped, "
                                              << summary.totalMs << " ms");
  // DSO makeKeyFrame: a high window RMSE on keyframes 2-4 means the initialisation was wrong.
  const int checked = m.keyframesInSegment - kFirstCheckedKeyframe;
  if (!m.relocalizedInSegment && checked >= 0 &&
      checked < static_cast<int>(sizeof(kInitRmseLimits) / sizeof(kInitRmseLimits[0])) &&
      rmse > initRmseLimit(kInitRmseLimits[checked], m.initNoiseSigma)) {
    m_initializationFailed = true;
  }
  const double t1 = threadCpuMs();
  m.pendingPairs.clear();
  if (keepsGlobalMap()) {
    // Pose-pose links of the keyframes about to leave, from this optimisation's linearisation (free now).
    for (int id : toMarginalize) {
      m.pendingPairs[id] = m.optimizer.pairInformation(id);
    }
  }
  buildReferencePoints();
  dropPointsOutOfView(*kf);
  makeNewImmaturePoints(*kf);
  if (keepsGlobalMap() && m.params.globalMap.reuse && reuseGlobalPoints(*kf, seedKeyframe) > 0) {
    buildReferencePoints(); // re-activated points are active in the newest keyframe: tracking uses them at once
  }
  const double t2 = threadCpuMs();
  for (int id : toMarginalize) {
    marginalize(id);
  }
  VP_HSLAM_LOG(vpHSlamLog::debug, "keyframe " << kf->id() << " timing: optimisation " << t1 - t0
                                              << " ms, reference + selection " << t2 - t1 << " ms, marginalisation "
                                              << threadCpuMs() - t2 << " ms");
}

void LocalMapper::buildReferencePoints()
{
  Impl &m = *m_impl;
  m.referencePoints.clear();
  m.referenceFeatures.clear();
  if (m_window.empty()) {
    m.referenceKeyframe = -1;
    return;
  }
  const Keyframe &newest = *m_window.back();
  m.referenceKeyframe = newest.id();
  for (const KeyframePtr &host : m_window) {
    const SE3d refMhost = newest.frame->cMw * host->frame->cMw.inverse();
    for (const MapPoint &p : host->points) {
      if (p.status != PointStatus::active || !(p.idepth > 0.)) {
        continue;
      }
      const double weight = std::sqrt(kTrackingWeightScale / std::max(p.idepthVar, kMinIdepthVariance));
      CoarseTrackerPoint out;
      if (projectIntoReference(refMhost, m.K0, m.width, m.height, p.u, p.v, static_cast<float>(p.idepth),
                               static_cast<float>(weight), out)) {
        m.referencePoints.push_back(out);
      }
      if (p.hasOrb && p.isCorner && !p.depthFromPrior) {
        // Every active corner whose depth was measured, also one outside the reference image: the new frame may
        // see it (a guessed depth would place its 3D point wrong for the pose-only step). Gradient pixels
        // are left out: their descriptor is taken on an edge, where no FAST keypoint of the new frame sits at the
        // same place, so their matches bias the pose (share of matches kept by the pose-only step, fast preset:
        // 7-Scenes 56 % -> 73 %, Tsukuba 59 % -> 74 %, KITTI 72 % -> 83 % with corners only).
        ReferenceFeature f;
        const Eigen::Vector3d ray((p.u - m.K0.cx) / m.K0.fx, (p.v - m.K0.cy) / m.K0.fy, 1.);
        f.Xref = refMhost * (ray / p.idepth);
        f.orb = p.orb;
        f.angleDeg = p.orbAngleDeg;
        f.idepthVar = p.idepthVar;
        m.referenceFeatures.push_back(f);
      }
    }
  }
}

void LocalMapper::dropPointsOutOfView(const Keyframe &newest)
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
      const Eigen::Vector3d ray((p.u - m_impl->K0.cx) / m_impl->K0.fx, (p.v - m_impl->K0.cy) / m_impl->K0.fy, 1.);
      const Eigen::Vector3d q = R * ray + t * p.idepth;
      if (!(q.z() > 0.)) {
        p.status = leavingStatus(p);
        continue;
      }
      const double u = m_impl->K0.fx * q.x() / q.z() + m_impl->K0.cx;
      const double v = m_impl->K0.fy * q.y() / q.z() + m_impl->K0.cy;
      if (!level0.isInside(static_cast<float>(u), static_cast<float>(v), static_cast<float>(kPatternPadding))) {
        p.status = leavingStatus(p);
      }
    }
  }
}

void LocalMapper::makeNewImmaturePoints(Keyframe &kf, bool cornersOnly)
{
  Impl &m = *m_impl;
  m.selector.select(kf.frame->raw, kf.frame->pyramid, m.params.features.desiredImmatureDensity,
                    static_cast<unsigned int>(kf.frame->id) + kSelectionSeedOffset, m.selected, m.selectedCorner,
                    cornersOnly ? SharedPointSelector::cornersOnly : SharedPointSelector::cornersAndGradients);
  const size_t begin = kf.immature.size();
  kf.immature.reserve(begin + m.selected.size());
  ImmaturePoint pt;
  for (size_t s = 0; s < m.selected.size(); ++s) {
    const SelectedPixel &px = m.selected[s];
    if (m.tracer.createImmaturePoint(*kf.frame, static_cast<float>(px.u), static_cast<float>(px.v), px.level, pt)) {
      pt.isCorner = m.selectedCorner[s];
      kf.immature.push_back(pt);
    }
  }
  m.describe(*kf.frame, kf.immature, begin);
}

void LocalMapper::keepConvergedDescriptorPoints(Keyframe &kf)
{
  const float minQuality = static_cast<float>(m_impl->params.mapper.minTraceQuality);
  for (const ImmaturePoint &pt : kf.immature) {
    if (pt.descriptorOnly && pt.hasOrb && hasConvergedDepth(pt, minQuality)) {
      MapPoint p = PointActivation::makeMapPoint(pt);
      p.status = PointStatus::marginalized;
      kf.points.push_back(std::move(p));
    }
  }
}

void LocalMapper::marginalize(int keyframeId)
{
  Impl &m = *m_impl;
  auto it = std::find_if(m_window.begin(), m_window.end(),
                         [keyframeId](const KeyframePtr &kf) { return kf->id() == keyframeId; });
  if (it == m_window.end()) {
    return;
  }
  std::vector<PairInformation> pairs;
  if (keepsGlobalMap()) {
    auto pending = m.pendingPairs.find(keyframeId);
    pairs = pending != m.pendingPairs.end() ? pending->second : m.optimizer.pairInformation(keyframeId);
  }
  m.optimizer.marginalizeKeyframe(keyframeId);
  keepConvergedDescriptorPoints(**it);
  if (m.relocalization) {
    RelocalizationKeyframe points;
    keyframePointsWorld(**it, points);
    m.relocalization->setKeyframePoints(keyframeId, std::move(points.wX), std::move(points.descriptors));
  }
  KeyframeState state;
  state.id = keyframeId;
  state.wMc = (*it)->frame->cMw.inverse();
  state.inWindow = false;
  state.activePoints = 0;
  m.marginalizedStates.push_back(state);
  if (keepsGlobalMap()) {
    handOverToLoopCloser(**it);    // before storing: a keyframe culled at once leaves the loop closer too
    storeInGlobalMap(**it, pairs); // after setKeyframePoints: a culled keyframe then leaves the index whole
  }
  m_window.erase(it);
}

// ------------------------------------------------------------------------------------------------ loop closure

void LocalMapper::handOverToLoopCloser(const Keyframe &kf)
{
  if (!m_loop) {
    return;
  }
  // Depth samples: the keyframe's own points (final now) and the window's active points seen from it.
  const PinholeIntrinsics &K = m_impl->K0;
  std::vector<IdepthSample> samples;
  for (const KeyframePtr &host : m_window) {
    const bool own = host.get() == &kf;
    const SE3d kMh = kf.frame->cMw * host->frame->cMw.inverse();
    for (const MapPoint &p : host->points) {
      const bool usable = p.status == PointStatus::active || (own && p.status == PointStatus::marginalized);
      if (!usable || !(p.idepth > 0.) || p.depthFromPrior) {
        continue;
      }
      const Eigen::Vector3d X = own ? K.unproject(p.u, p.v, p.idepth) : kMh * K.unproject(p.u, p.v, p.idepth);
      if (X.z() > 0.) {
        const Eigen::Vector2d uv = K.project(X);
        samples.push_back({uv.x(), uv.y(), 1. / X.z()});
      }
    }
  }
  m_loop->addKeyframe(kf.id(), m_segment, kf.frame->raw, samples);
}

std::set<int> LocalMapper::connectedToWindow() const
{
  // Not the window's co-visible keyframes: the query is a stored keyframe now, and a keyframe DSO keeps in the window
  // for long (it still sees most of its points) is co-visible with a whole pass; with them, every keyframe of the
  // outward pass was excluded on 7-Scenes played there and back. The query's own co-visible ones are excluded by
  // the loop closer.
  std::set<int> connected;
  for (const KeyframePtr &kf : m_window) {
    connected.insert(kf->id());
    // Keyframes whose points the window re-uses now are connected (their co-visibility is only counted once those
    // points leave the window again): re-use has already joined them to the present, no loop is needed there.
    for (const MapPoint &pt : kf->points) {
      if (pt.status == PointStatus::active && pt.fromGlobalMap) {
        connected.insert(pt.observers.begin(), pt.observers.end());
      }
    }
  }
  return connected;
}

void LocalMapper::closeLoops()
{
  DetectedLoop loop;
  if (m_loop && m_loop->detect(m_globalMap, connectedToWindow(), loop)) {
    correctLoop(loop);
  }
}

bool LocalMapper::correctLoop(const DetectedLoop &loop)
{
  Impl &m = *m_impl;
  struct Flag {
    std::atomic<bool> &flag;
    ~Flag() { flag = false; }
  } correcting{m_correctingLoop};
  m_correctingLoop = true;
  // A global bundle adjustment of an earlier loop: written back if it has ended; else it goes on (it works on its own
  // copy) until this correction is known to succeed, and is stopped only then (its keyframes move; a new one follows).
  collectGlobalBundleAdjustment(false);
  const auto t0 = std::chrono::steady_clock::now();
  std::map<int, SE3d> windowPoses;
  for (const KeyframePtr &kf : m_window) {
    windowPoses[kf->id()] = kf->frame->cMw;
  }
  std::vector<std::pair<int, Sim3d>> solution;
  bool solved = false;
  try {
    solved = m_loop->correct(loop, m_globalMap, windowPoses, solution);
  } catch (const vpHSlamException &e) { // nothing is changed before the pose graph succeeded
    VP_HSLAM_LOG(vpHSlamLog::warning,
                 "loop " << loop.keyframe << "-" << loop.candidate << " not corrected: " << e.getStringMessage());
  }
  if (!solved) {
    VP_HSLAM_LOG(vpHSlamLog::warning, "loop " << loop.keyframe << "-" << loop.candidate << " not corrected");
    return false;
  }
  m.globalBa.cancel(); // its result would undo this correction
  for (const auto &entry : solution) {
    m_globalMap.applySimilarity(entry.first, entry.second);
    m_loop->rescale(entry.first, entry.second.scale());
    publishStoredKeyframe(entry.first, entry.second.scale());
  }
  LoopStatistics &stats = m_loop->statistics();
  stats.lastCorrectionMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  stats.correctionMsMax = std::max(stats.correctionMsMax, stats.lastCorrectionMs);
  VP_HSLAM_LOG(vpHSlamLog::info, "loop " << loop.keyframe << "-" << loop.candidate << " corrected, " << solution.size()
                                         << " stored keyframes moved, " << stats.lastCorrectionMs << " ms");
  startGlobalBundleAdjustment();
  return true;
}

const LocalMapper::LoopStatistics &LocalMapper::loopStatistics() const
{
  static const LoopStatistics none;
  return m_loop ? m_loop->statistics() : none;
}

double LocalMapper::loopMemoryBytes() const
{
  return m_loop ? m_loop->memoryBytes() : 0.;
}
} // namespace hslam
