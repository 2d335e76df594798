/*
 * H-SLAM for ViSP.
 */
#include "mapping/ImmaturePointTracer.h"

#include "common/RobustWeights.h"
#include "map/AffineBrightness.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace hslam
{
namespace
{
//! Border kept free around a new point, pixels: pattern padding plus one pixel of interpolation room (DSO).
constexpr float kCreationBorder = static_cast<float>(kPatternPadding + 1);
//! Projections closer than this to the target border end the point's life (DSO: 4 px, then out of bounds).
constexpr float kTraceBorder = 4.f;
//! Allowed depth ratio target/host at the near end of the interval (DSO: outside (0.75, 1.5) = out of bounds).
constexpr float kMinScaleChange = 0.75f;
constexpr float kMaxScaleChange = 1.5f;
//! Expected matching error along the line, pixels: base + base * (gradient energy / energy along the line) (DSO).
constexpr float kErrorInPixelBase = 0.2f;
//! The expected error is capped to this many pixels (DSO).
constexpr float kMaxErrorInPixel = 10.f;
//! Size of the per-step error buffer; the discrete search never visits more positions (DSO: 100).
constexpr int kMaxTraceSteps = 100;
//! numSteps = floor(this + length / step): both end points are always visited (DSO).
constexpr float kStepCountRounding = 1.9999f;
//! Positions within this many steps of the best one do not count as a "second best" (DSO minTraceTestRadius).
constexpr int kSecondBestExclusionRadius = 2;
//! Quality is always refreshed when the search was longer than this many steps (DSO).
constexpr int kQualityRefreshSteps = 10;
//! Floor of the best energy in the quality ratio: a perfect match (energy 0) must not give 0 / 0.
constexpr float kMinQualityDenominator = 1e-6f;
//! Energy charged for a pattern pixel that falls outside the target image (DSO: 1e5 per missing pixel).
constexpr float kOutOfImageEnergy = 1e5f;
//! Energy before the first Gauss-Newton evaluation, so the first evaluation is always accepted (DSO).
constexpr float kInitialGaussNewtonEnergy = 1e5f;
//! Start of the "best energy" search, larger than any reachable energy.
constexpr float kNoEnergy = 1e10f;
//! Prior added to the 1-D Gauss-Newton Hessian (DSO: H starts at 1), keeps the step finite on flat patches.
constexpr float kGaussNewtonHessianPrior = 1.f;
//! Largest Gauss-Newton step along the line, in search steps (DSO).
constexpr float kGaussNewtonMaxStep = 0.5f;
//! Scale of the pseudo-random sub-step start offset: frac(uMin * this) (DSO), deterministic.
constexpr float kStartJitterScale = 1000.f;
//! Relative norm below which the epipolar direction is undefined (pixel at the epipole or no translation).
constexpr float kMinRelativeDirectionNorm = 1e-6f;

//! DSO's Huber energy of a residual: r^2 inside the threshold, 2 k |r| - k^2 outside (twice the usual Huber).
inline float huberEnergy(float residual, float threshold, float &weight)
{
  const float absResidual = std::fabs(residual);
  weight = huberWeight(absResidual, threshold);
  return weight * residual * residual * (2.f - weight);
}

/*!
  Unweighted Huber SSD of the pattern (offsets) at (px, py) against the reference intensities: the discrete search's
  inner loop. A pattern pixel outside \e level costs kOutOfImageEnergy; \e inside (the whole pattern is known to be
  inside) spares the per-pixel test.
*/
inline float patternEnergy(const PyramidLevel &level, const std::array<Eigen::Vector2f, kPatternSize> &offsets,
                           const std::array<float, kPatternSize> &reference, float px, float py, float threshold,
                           bool inside)
{
  float energy = 0.f;
  for (int k = 0; k < kPatternSize; ++k) {
    const float x = px + offsets[static_cast<size_t>(k)].x();
    const float y = py + offsets[static_cast<size_t>(k)].y();
    if (!inside && !level.isInside(x, y, 0.f)) {
      energy += kOutOfImageEnergy;
      continue;
    }
    float weight;
    energy += huberEnergy(level.interpolateIntensity(x, y) - reference[static_cast<size_t>(k)], threshold, weight);
  }
  return energy;
}

#ifdef __SSE2__
/*!
  Unweighted Huber SSD of the pattern at (px, py) (pattern offsets offX / offY, reference intensities ref), every
  pattern pixel inside \e level: the discrete search's inner loop, four pixels per vector. Lane by lane the same
  float operations as interpolateIntensity() and huberEnergy(), and the eight terms summed in the same order as the
  scalar loop, so the energy is the same bit for bit.
*/
inline float patternEnergyInside(const PyramidLevel &level, const float *offX, const float *offY, const float *ref,
                                 float px, float py, float threshold)
{
  const int w = level.width;
  const Eigen::Vector3f *color = level.color.data();
  const __m128 one = _mm_set1_ps(1.f);
  const __m128 two = _mm_set1_ps(2.f);
  const __m128 thr = _mm_set1_ps(threshold);
  const __m128 signMask = _mm_set1_ps(-0.f);
  alignas(16) float terms[kPatternSize];
  static_assert(kPatternSize % 4 == 0, "the pattern is processed four pixels at a time");
  for (int h = 0; h < kPatternSize; h += 4) {
    const __m128 x = _mm_add_ps(_mm_set1_ps(px), _mm_loadu_ps(offX + h));
    const __m128 y = _mm_add_ps(_mm_set1_ps(py), _mm_loadu_ps(offY + h));
    const __m128i ix = _mm_cvttps_epi32(x); // truncation, as static_cast<int>
    const __m128i iy = _mm_cvttps_epi32(y);
    const __m128 du = _mm_sub_ps(x, _mm_cvtepi32_ps(ix));
    const __m128 dv = _mm_sub_ps(y, _mm_cvtepi32_ps(iy));
    alignas(16) int ixs[4], iys[4];
    _mm_store_si128(reinterpret_cast<__m128i *>(ixs), ix);
    _mm_store_si128(reinterpret_cast<__m128i *>(iys), iy);
    alignas(16) float p00[4], p01[4], p10[4], p11[4];
    for (int j = 0; j < 4; ++j) {
      const Eigen::Vector3f *p = color + static_cast<ptrdiff_t>(iys[j]) * w + ixs[j];
      p00[j] = p[0][0];
      p01[j] = p[1][0];
      p10[j] = p[w][0];
      p11[j] = p[w + 1][0];
    }
    const __m128 notDu = _mm_sub_ps(one, du);
    const __m128 top = _mm_add_ps(_mm_mul_ps(notDu, _mm_load_ps(p00)), _mm_mul_ps(du, _mm_load_ps(p01)));
    const __m128 bottom = _mm_add_ps(_mm_mul_ps(notDu, _mm_load_ps(p10)), _mm_mul_ps(du, _mm_load_ps(p11)));
    const __m128 value = _mm_add_ps(_mm_mul_ps(_mm_sub_ps(one, dv), top), _mm_mul_ps(dv, bottom));
    const __m128 r = _mm_sub_ps(value, _mm_loadu_ps(ref + h));
    const __m128 absR = _mm_andnot_ps(signMask, r);
    // huberWeight: 1 inside the threshold, threshold / |r| outside (lanes inside never use the quotient).
    const __m128 inside = _mm_cmple_ps(absR, thr);
    const __m128 weight = _mm_or_ps(_mm_and_ps(inside, one), _mm_andnot_ps(inside, _mm_div_ps(thr, absR)));
    _mm_store_ps(terms + h, _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(weight, r), r), _mm_sub_ps(two, weight)));
  }
  float energy = 0.f;
  for (int k = 0; k < kPatternSize; ++k) {
    energy += terms[k];
  }
  return energy;
}
#endif

//! Slack of patternSegmentInside() for the rounding of accumulated positions, pixels.
constexpr float kSegmentInsideSlack = 0.5f;

//! True when the pattern (offsets within the box lo-hi) at every position of the segment (x0, y0)-(x1, y1) is
//! inside \e level for bilinear interpolation (PyramidLevel::isInside with margin 0), with kSegmentInsideSlack to
//! spare.
bool patternSegmentInside(const PyramidLevel &level, const Eigen::Vector2f &lo, const Eigen::Vector2f &hi, float x0,
                          float y0, float x1, float y1)
{
  const float xLo = std::min(x0, x1) + lo.x(), xHi = std::max(x0, x1) + hi.x();
  const float yLo = std::min(y0, y1) + lo.y(), yHi = std::max(y0, y1) + hi.y();
  return xLo >= kSegmentInsideSlack && yLo >= kSegmentInsideSlack &&
         xHi < static_cast<float>(level.width) - 1.f - kSegmentInsideSlack &&
         yHi < static_cast<float>(level.height) - 1.f - kSegmentInsideSlack;
}

//! Inverse depth that projects to target coordinate \e x along one image axis: x = (pr_a + Kt_a id) / (pr_z + Kt_z id).
inline float idepthFromCoordinate(float x, float prAxis, float prZ, float KtAxis, float KtZ)
{
  return (prZ * x - prAxis) / (KtAxis - KtZ * x);
}
} // namespace

void TraceStatistics::add(TraceStatus status)
{
  ++total;
  switch (status) {
  case TraceStatus::good:
    ++good;
    break;
  case TraceStatus::outOfBounds:
    ++outOfBounds;
    break;
  case TraceStatus::skipped:
    ++skipped;
    break;
  case TraceStatus::badCondition:
    ++badCondition;
    break;
  case TraceStatus::outlier:
    ++outlier;
    break;
  case TraceStatus::uninitialized:
    ++uninitialized;
    break;
  }
}

ImmaturePointTracer::ImmaturePointTracer(const vpHSlamParameters::Mapper &mapper,
                                         const vpHSlamParameters::Tracker &tracker)
    : m_huberThreshold(static_cast<float>(tracker.huberThreshold)),
      m_gradientWeightCSq(static_cast<float>(tracker.gradientWeightC * tracker.gradientWeightC)),
      m_outlierEnergyPerPixel(static_cast<float>(tracker.outlierEnergyPerPixel)),
      m_minImprovementFactor(static_cast<float>(mapper.traceMinImprovementFactor)),
      m_slackInterval(static_cast<float>(mapper.traceSlackInterval)),
      m_stepSize(static_cast<float>(mapper.traceStepSize)), m_gaussNewtonIterations(mapper.traceGaussNewtonIterations),
      m_gaussNewtonThreshold(static_cast<float>(mapper.traceGaussNewtonThreshold)),
      m_extraSlackOnThreshold(static_cast<float>(mapper.traceExtraSlackOnThreshold)),
      m_maxPixelSearchFraction(static_cast<float>(mapper.traceMaxPixelSearch))
{
  if (!(m_stepSize > 0.f) || !(m_maxPixelSearchFraction > 0.f) || m_gaussNewtonIterations < 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                               ": traceStepSize and traceMaxPixelSearch must be > 0, traceGaussNewtonIterations >= 0");
  }
}

bool ImmaturePointTracer::createImmaturePoint(const Frame &host, float u, float v, int selectionLevel,
                                              ImmaturePoint &pt) const
{
  if (host.pyramid.numLevels() < 1) {
    return false;
  }
  const PyramidLevel &level0 = host.pyramid.level(0);
  if (!level0.isInside(u, v, kCreationBorder)) {
    return false;
  }
  pt = ImmaturePoint();
  pt.hostKeyframeId = host.keyframeId;
  pt.u = u;
  pt.v = v;
  pt.selectionLevel = selectionLevel;
  for (int k = 0; k < kPatternSize; ++k) {
    const Eigen::Vector3f c =
        level0.interpolate(u + static_cast<float>(kPattern[k][0]), v + static_cast<float>(kPattern[k][1]));
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2])) {
      return false;
    }
    pt.patch[static_cast<size_t>(k)] = c[0];
    // DSO: gradient-dependent weight c^2 / (c^2 + |grad|^2), strong edges count less (they are less reliable).
    pt.patchWeight[static_cast<size_t>(k)] = gradientWeight(m_gradientWeightCSq, c.tail<2>().squaredNorm());
  }
  // DSO: the point is an outlier in a frame when its summed pattern energy exceeds pattern size x outlier energy.
  pt.energyThreshold = static_cast<float>(kPatternSize) * m_outlierEnergyPerPixel;
  pt.idepthMin = 0.f;
  pt.idepthMax = std::numeric_limits<float>::infinity();
  pt.lastStatus = TraceStatus::uninitialized;
  return true;
}

TraceContext ImmaturePointTracer::makeContext(const Frame &host, const Frame &target, const SE3d &targetMhost,
                                              double aji, double bji, const PinholeIntrinsics &K0) const
{
  if (host.pyramid.numLevels() < 1 || target.pyramid.numLevels() < 1) {
    throw vpHSlamException(vpHSlamException::invalidArgument, std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                                                                  ": host or target frame has no image pyramid");
  }
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  K(0, 0) = K0.fx;
  K(1, 1) = K0.fy;
  K(0, 2) = K0.cx;
  K(1, 2) = K0.cy;
  TraceContext context;
  context.KRKi = (K * targetMhost.rotationMatrix() * K.inverse()).cast<float>();
  context.Kt = (K * targetMhost.translation()).cast<float>();
  context.aji = static_cast<float>(aji);
  context.bji = static_cast<float>(bji);
  context.hostLevel = &host.pyramid.level(0);
  context.targetLevel = &target.pyramid.level(0);
  context.maxPixelSearch =
      m_maxPixelSearchFraction * static_cast<float>(context.targetLevel->width + context.targetLevel->height);
  // The pattern is searched as it appears in the target: rotated (and scaled) by the in-plane part of K R K^-1.
  const Eigen::Matrix2f Rplane = context.KRKi.topLeftCorner<2, 2>();
  for (int k = 0; k < kPatternSize; ++k) {
    context.rotatedPattern[static_cast<size_t>(k)] =
        Rplane * Eigen::Vector2f(static_cast<float>(kPattern[k][0]), static_cast<float>(kPattern[k][1]));
  }
  context.rotatedPatternMin = context.rotatedPatternMax = context.rotatedPattern[0];
  for (const Eigen::Vector2f &o : context.rotatedPattern) {
    context.rotatedPatternMin = context.rotatedPatternMin.cwiseMin(o);
    context.rotatedPatternMax = context.rotatedPatternMax.cwiseMax(o);
  }
  return context;
}

TraceStatus ImmaturePointTracer::trace(ImmaturePoint &pt, const Frame &host, const Frame &target,
                                       const SE3d &targetMhost, double aji, double bji, const PinholeIntrinsics &K0,
                                       TraceResult *result) const
{
  const TraceContext context = makeContext(host, target, targetMhost, aji, bji, K0);
  return trace(pt, context, result);
}

TraceStatistics ImmaturePointTracer::traceAll(std::vector<ImmaturePoint> &points, const Frame &host,
                                              const Frame &target) const
{
  TraceStatistics statistics;
  if (points.empty()) {
    return statistics;
  }
  const SE3d targetMhost = target.cMw * host.cMw.inverse();
  double aji = 1., bji = 0.;
  AffineBrightness::transfer(host.exposure, host.affine, target.exposure, target.affine, aji, bji);
  const TraceContext context = makeContext(host, target, targetMhost, aji, bji, host.pyramid.level(0).K);
  for (ImmaturePoint &pt : points) {
    statistics.add(trace(pt, context));
  }
  return statistics;
}

float ImmaturePointTracer::projectedIntervalLength(const ImmaturePoint &pt, const SE3d &targetMhost,
                                                   const PinholeIntrinsics &K0)
{
  if (!std::isfinite(pt.idepthMax) || !std::isfinite(pt.idepthMin)) {
    return std::numeric_limits<float>::infinity();
  }
  const Eigen::Vector3d ray((pt.u - K0.cx) / K0.fx, (pt.v - K0.cy) / K0.fy, 1.);
  const Eigen::Vector3d Rray = targetMhost.rotationMatrix() * ray;
  const Eigen::Vector3d &t = targetMhost.translation();
  const Eigen::Vector3d pMin = Rray + t * static_cast<double>(pt.idepthMin);
  const Eigen::Vector3d pMax = Rray + t * static_cast<double>(pt.idepthMax);
  if (!(pMin.z() > 0.) || !(pMax.z() > 0.)) {
    return std::numeric_limits<float>::infinity();
  }
  const double du = K0.fx * (pMin.x() / pMin.z() - pMax.x() / pMax.z());
  const double dv = K0.fy * (pMin.y() / pMin.z() - pMax.y() / pMax.z());
  return static_cast<float>(std::sqrt(du * du + dv * dv));
}

//! How a trace ends: the status and the target pixel and interval length it reports (see TraceResult).
struct ImmaturePointTracer::TraceEnd {
  TraceStatus status;
  float u, v, pixelInterval;

  //! The point left the target (or never fits in it): no pixel, no interval.
  static TraceEnd outOfBounds() { return TraceEnd{TraceStatus::outOfBounds, -1.f, -1.f, 0.f}; }
};

//! The point's interval projected onto the target's epipolar line: where the search starts, where it goes, how far.
struct ImmaturePointTracer::EpipolarSegment {
  Eigen::Vector3f pr; //!< K R K^-1 (u, v, 1): the host pixel at zero inverse depth, target homogeneous coordinates
  float uMin, vMin;   //!< projection of idepthMin, pixels
  float dirU, dirV;   //!< unit direction of growing inverse depth
  float dist;         //!< length of the segment to search, pixels
  bool bounded;       //!< idepthMax is finite
};

//! The best match along the line: discrete search, then refined by Gauss-Newton.
struct ImmaturePointTracer::LineMatch {
  float u, v;         //!< target pixel
  float energy;       //!< pattern energy there
  float stepU, stepV; //!< one search step along the line, pixels
};

std::optional<ImmaturePointTracer::TraceEnd> ImmaturePointTracer::projectInterval(const ImmaturePoint &pt,
                                                                                  const TraceContext &context,
                                                                                  EpipolarSegment &segment) const
{
  const PyramidLevel &target = *context.targetLevel;
  const Eigen::Vector3f &Kt = context.Kt;
  const Eigen::Vector3f pr = context.KRKi * Eigen::Vector3f(pt.u, pt.v, 1.f);
  segment.pr = pr;
  const Eigen::Vector3f ptpMin = pr + Kt * pt.idepthMin;
  if (!(ptpMin.z() > 0.f)) {
    return TraceEnd::outOfBounds();
  }
  const float uMin = ptpMin.x() / ptpMin.z();
  const float vMin = ptpMin.y() / ptpMin.z();
  if (!target.isInside(uMin, vMin, kTraceBorder)) {
    return TraceEnd::outOfBounds();
  }
  segment.uMin = uMin;
  segment.vMin = vMin;

  segment.bounded = std::isfinite(pt.idepthMax);
  if (segment.bounded) {
    const Eigen::Vector3f ptpMax = pr + Kt * pt.idepthMax;
    if (!(ptpMax.z() > 0.f)) {
      return TraceEnd::outOfBounds();
    }
    const float uMax = ptpMax.x() / ptpMax.z();
    const float vMax = ptpMax.y() / ptpMax.z();
    if (!target.isInside(uMax, vMax, kTraceBorder)) {
      return TraceEnd::outOfBounds();
    }
    const float dist = std::hypot(uMax - uMin, vMax - vMin);
    // Already certain to within the slack: nothing to gain from a search (DSO "skip").
    if (dist < m_slackInterval) {
      return TraceEnd{TraceStatus::skipped, 0.5f * (uMin + uMax), 0.5f * (vMin + vMax), dist};
    }
    segment.dist = dist;
    segment.dirU = (uMax - uMin) / dist;
    segment.dirV = (vMax - vMin) / dist;
  } else {
    // Direction of growing inverse depth: derivative of the projection, (Kt_xy - p_xy Kt_z) / z (exact tangent).
    const float tu = Kt.x() - uMin * Kt.z();
    const float tv = Kt.y() - vMin * Kt.z();
    const float norm = std::hypot(tu, tv);
    if (!(norm > kMinRelativeDirectionNorm * Kt.norm()) || !(norm > 0.f)) {
      // No parallax direction (pure rotation or pixel at the epipole): keep the interval.
      return TraceEnd{TraceStatus::skipped, uMin, vMin, 0.f};
    }
    segment.dirU = tu / norm;
    segment.dirV = tv / norm;
    segment.dist = context.maxPixelSearch;
    if (!target.isInside(uMin + segment.dist * segment.dirU, vMin + segment.dist * segment.dirV, kTraceBorder)) {
      return TraceEnd::outOfBounds();
    }
  }

  // Large depth changes distort the patch too much for the unwarped pattern comparison (DSO).
  if (!(pt.idepthMin < 0.f || (ptpMin.z() > kMinScaleChange && ptpMin.z() < kMaxScaleChange))) {
    return TraceEnd::outOfBounds();
  }
  return std::nullopt;
}

std::optional<ImmaturePointTracer::TraceEnd> ImmaturePointTracer::expectedPixelError(const ImmaturePoint &pt,
                                                                                     const TraceContext &context,
                                                                                     const EpipolarSegment &segment,
                                                                                     float &errorInPixel) const
{
  const PyramidLevel &hostLevel = *context.hostLevel;
  Eigen::Matrix2f gradH = Eigen::Matrix2f::Zero();
  for (int k = 0; k < kPatternSize; ++k) {
    const Eigen::Vector3f c =
        hostLevel.interpolate(pt.u + static_cast<float>(kPattern[k][0]), pt.v + static_cast<float>(kPattern[k][1]));
    gradH += c.tail<2>() * c.tail<2>().transpose();
  }
  const Eigen::Vector2f along(segment.dirU, segment.dirV);
  const Eigen::Vector2f across(segment.dirV, -segment.dirU);
  const float energyAlong = along.dot(gradH * along);
  const float energyAcross = across.dot(gradH * across);
  errorInPixel = kErrorInPixelBase + kErrorInPixelBase * (energyAlong + energyAcross) / energyAlong;
  if (!std::isfinite(errorInPixel)) {
    errorInPixel = std::numeric_limits<float>::infinity();
  }
  if (segment.bounded && errorInPixel * m_minImprovementFactor > segment.dist) {
    const float uEnd = segment.uMin + segment.dist * segment.dirU, vEnd = segment.vMin + segment.dist * segment.dirV;
    return TraceEnd{TraceStatus::badCondition, 0.5f * (segment.uMin + uEnd), 0.5f * (segment.vMin + vEnd),
                    segment.dist};
  }
  errorInPixel = std::min(errorInPixel, kMaxErrorInPixel);
  return std::nullopt;
}

namespace
{
/*!
  Match quality: the best energy away from the best match over the best energy (DSO: distinctiveness of the match).
  Refreshed when it got worse or the search was long.
*/
void updateQuality(ImmaturePoint &pt, const std::array<float, kMaxTraceSteps> &errors, int numSteps, int bestIndex,
                   float bestEnergy)
{
  float secondBest = kNoEnergy;
  for (int i = 0; i < numSteps; ++i) {
    if ((i < bestIndex - kSecondBestExclusionRadius || i > bestIndex + kSecondBestExclusionRadius) &&
        errors[static_cast<size_t>(i)] < secondBest) {
      secondBest = errors[static_cast<size_t>(i)];
    }
  }
  const float newQuality = secondBest / std::max(bestEnergy, kMinQualityDenominator);
  if (newQuality < pt.quality || numSteps > kQualityRefreshSteps) {
    pt.quality = newQuality;
  }
}
} // namespace

ImmaturePointTracer::LineMatch ImmaturePointTracer::searchAlongLine(ImmaturePoint &pt, const TraceContext &context,
                                                                    const EpipolarSegment &segment,
                                                                    const std::array<float, kPatternSize> &reference,
                                                                    int &numSteps) const
{
  const PyramidLevel &target = *context.targetLevel;
  const float dist = std::min(segment.dist, context.maxPixelSearch);
  LineMatch best;
  best.stepU = m_stepSize * segment.dirU;
  best.stepV = m_stepSize * segment.dirV;
  const float stepU = best.stepU, stepV = best.stepV;
  numSteps = static_cast<int>(kStepCountRounding + dist / m_stepSize);
  numSteps = std::min(numSteps, kMaxTraceSteps - 1);
  // Deterministic sub-step start offset, so consecutive traces do not sample the same positions (DSO).
  const float startShift = segment.uMin * kStartJitterScale - std::floor(segment.uMin * kStartJitterScale);
  float ptx = segment.uMin - startShift * stepU;
  float pty = segment.vMin - startShift * stepV;
  const std::array<Eigen::Vector2f, kPatternSize> &offsets = context.rotatedPattern;

  // Most segments lie well inside the image: one box test for the whole segment then spares the per-pixel test
  // (same sums in the same order either way). The positions are accumulated step by step, so the test keeps a
  // slack for their rounding.
  const bool segmentInside =
      numSteps > 0 && patternSegmentInside(target, context.rotatedPatternMin, context.rotatedPatternMax, ptx, pty,
                                           ptx + static_cast<float>(numSteps - 1) * stepU,
                                           pty + static_cast<float>(numSteps - 1) * stepV);
  std::array<float, kMaxTraceSteps> errors;
  best.u = 0.f;
  best.v = 0.f;
  best.energy = kNoEnergy;
  int bestIndex = -1;
#ifdef __SSE2__
  float offX[kPatternSize], offY[kPatternSize];
  for (int k = 0; k < kPatternSize; ++k) {
    offX[k] = offsets[static_cast<size_t>(k)].x();
    offY[k] = offsets[static_cast<size_t>(k)].y();
  }
#endif
  for (int i = 0; i < numSteps; ++i) {
#ifdef __SSE2__
    const float energy = segmentInside
                             ? patternEnergyInside(target, offX, offY, reference.data(), ptx, pty, m_huberThreshold)
                             : patternEnergy(target, offsets, reference, ptx, pty, m_huberThreshold, segmentInside);
#else
    const float energy = patternEnergy(target, offsets, reference, ptx, pty, m_huberThreshold, segmentInside);
#endif
    errors[static_cast<size_t>(i)] = energy;
    if (energy < best.energy) {
      best.u = ptx;
      best.v = pty;
      best.energy = energy;
      bestIndex = i;
    }
    ptx += stepU;
    pty += stepV;
  }
  updateQuality(pt, errors, numSteps, bestIndex, best.energy);
  return best;
}

void ImmaturePointTracer::refineAlongLine(const ImmaturePoint &pt, const TraceContext &context,
                                          const std::array<float, kPatternSize> &reference, LineMatch &match) const
{
  const PyramidLevel &target = *context.targetLevel;
  const std::array<Eigen::Vector2f, kPatternSize> &offsets = context.rotatedPattern;
  const float stepU = match.stepU, stepV = match.stepV;
  float bestU = match.u, bestV = match.v, bestEnergy = match.energy;
  float uBackup = bestU, vBackup = bestV, stepBack = 0.f;
  if (m_gaussNewtonIterations > 0) {
    bestEnergy = kInitialGaussNewtonEnergy;
  }
  for (int it = 0; it < m_gaussNewtonIterations; ++it) {
    float H = kGaussNewtonHessianPrior, b = 0.f, energy = 0.f;
    for (int k = 0; k < kPatternSize; ++k) {
      const float x = bestU + offsets[static_cast<size_t>(k)].x();
      const float y = bestV + offsets[static_cast<size_t>(k)].y();
      if (!target.isInside(x, y, 0.f)) {
        energy += kOutOfImageEnergy;
        continue;
      }
      const Eigen::Vector3f hit = target.interpolate(x, y);
      const float residual = hit[0] - reference[static_cast<size_t>(k)];
      const float dResidualdStep = stepU * hit[1] + stepV * hit[2];
      float huberWeight;
      const float e = huberEnergy(residual, m_huberThreshold, huberWeight);
      H += huberWeight * dResidualdStep * dResidualdStep;
      b += huberWeight * residual * dResidualdStep;
      energy += pt.patchWeight[static_cast<size_t>(k)] * e;
    }
    if (energy > bestEnergy) {
      // Worse than before: go back towards the previous position with half the step.
      stepBack *= 0.5f;
      bestU = uBackup + stepBack * stepU;
      bestV = vBackup + stepBack * stepV;
    } else {
      float step = -b / H;
      step = std::max(-kGaussNewtonMaxStep, std::min(kGaussNewtonMaxStep, step));
      if (!std::isfinite(step)) {
        step = 0.f;
      }
      uBackup = bestU;
      vBackup = bestV;
      stepBack = step;
      bestU += step * stepU;
      bestV += step * stepV;
      bestEnergy = energy;
    }
    if (std::fabs(stepBack) < m_gaussNewtonThreshold) {
      break;
    }
  }
  match.u = bestU;
  match.v = bestV;
  match.energy = bestEnergy;
}

ImmaturePointTracer::TraceEnd ImmaturePointTracer::updateInterval(ImmaturePoint &pt, const TraceContext &context,
                                                                  const EpipolarSegment &segment,
                                                                  const LineMatch &match, float errorInPixel)
{
  const Eigen::Vector3f &Kt = context.Kt;
  const Eigen::Vector3f &pr = segment.pr;
  const float dirU = segment.dirU, dirV = segment.dirV;
  float idepthA, idepthB;
  if (dirU * dirU > dirV * dirV) {
    idepthA = idepthFromCoordinate(match.u - errorInPixel * dirU, pr.x(), pr.z(), Kt.x(), Kt.z());
    idepthB = idepthFromCoordinate(match.u + errorInPixel * dirU, pr.x(), pr.z(), Kt.x(), Kt.z());
  } else {
    idepthA = idepthFromCoordinate(match.v - errorInPixel * dirV, pr.y(), pr.z(), Kt.y(), Kt.z());
    idepthB = idepthFromCoordinate(match.v + errorInPixel * dirV, pr.y(), pr.z(), Kt.y(), Kt.z());
  }
  const float newMin = std::min(idepthA, idepthB);
  const float newMax = std::max(idepthA, idepthB);
  if (!std::isfinite(newMin) || !std::isfinite(newMax) || newMax < 0.f) {
    return TraceEnd{TraceStatus::outlier, -1.f, -1.f, 0.f};
  }
  // Negative inverse depths lie "beyond infinity": clip, a visible point has idepth >= 0.
  pt.idepthMin = std::max(newMin, 0.f);
  pt.idepthMax = newMax;
  return TraceEnd{TraceStatus::good, match.u, match.v, 2.f * errorInPixel};
}

TraceStatus ImmaturePointTracer::trace(ImmaturePoint &pt, const TraceContext &context, TraceResult *result) const
{
  TraceResult local;
  TraceResult &out = result != nullptr ? *result : local;
  out = TraceResult();
  const auto finish = [&pt, &out](const TraceEnd &end) {
    pt.lastStatus = end.status;
    out.status = end.status;
    out.u = end.u;
    out.v = end.v;
    out.pixelInterval = end.pixelInterval;
    return end.status;
  };
  // An out-of-bounds point stays so: it has left the field of view for good (DSO).
  if (pt.lastStatus == TraceStatus::outOfBounds) {
    return finish(TraceEnd::outOfBounds());
  }

  EpipolarSegment segment;
  if (const std::optional<TraceEnd> end = projectInterval(pt, context, segment)) {
    return finish(*end);
  }
  // Expected pixel error: small when the host gradients lie along the epipolar line (DSO errorInPixel).
  float errorInPixel;
  if (const std::optional<TraceEnd> end = expectedPixelError(pt, context, segment, errorInPixel)) {
    return finish(*end);
  }

  // Discrete search along the segment, unweighted Huber SSD of the pattern (DSO).
  std::array<float, kPatternSize> reference;
  for (int k = 0; k < kPatternSize; ++k) {
    reference[static_cast<size_t>(k)] = context.aji * pt.patch[static_cast<size_t>(k)] + context.bji;
  }
  LineMatch match = searchAlongLine(pt, context, segment, reference, out.searchSteps);

  // Gauss-Newton refinement along the line (1 unknown: the position in steps), gradient-weighted energy.
  refineAlongLine(pt, context, reference, match);
  out.bestEnergy = match.energy;

  // Energy-based outlier test; two outliers in a row end the point (DSO).
  if (!(match.energy < pt.energyThreshold * m_extraSlackOnThreshold)) {
    const TraceStatus status = pt.lastStatus == TraceStatus::outlier ? TraceStatus::outOfBounds : TraceStatus::outlier;
    return finish(TraceEnd{status, -1.f, -1.f, 0.f});
  }
  // New interval: refined position +- the expected error, mapped back to inverse depth through the image axis along
  // which the line runs faster (better conditioned division, DSO).
  return finish(updateInterval(pt, context, segment, match, errorInPixel));
}
} // namespace hslam
