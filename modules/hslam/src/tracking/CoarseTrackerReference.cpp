/*
 * H-SLAM for ViSP.
 */
// The reference side of the coarse tracker: inverse-depth maps of the reference keyframe on every level, their
// dilation and the residual point lists (DSO CoarseTracker::makeCoarseDepthL0 and setCoarseTrackingRef),
// re-implemented; see CoarseTracker.h for the model and the conventions.
#include "common/TextParsing.h"
#include "tracking/CoarseTracker.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hslam
{
namespace
{
//! Reference pixels closer than this to the border are not used (DSO: 2 <= x < w - 2).
constexpr int kReferenceBorder = 2;
//! Levels below this dilate the inverse-depth map diagonally, coarser ones along the axes (DSO).
constexpr int kDiagonalDilationLevels = 2;
} // namespace

void CoarseTracker::setReference(const Frame &refKf, const std::vector<CoarseTrackerPoint> &points)
{
  const ImagePyramid &pyr = refKf.pyramid;
  if (pyr.numLevels() < 1 || pyr.numLevels() > kCoarseTrackerMaxLevels) {
    throwAt(vpHSlamException::invalidArgument, __FILE__, static_cast<std::size_t>(__LINE__),
            "CoarseTracker: reference pyramid has " + std::to_string(pyr.numLevels()) + " levels, expected 1.." +
                std::to_string(kCoarseTrackerMaxLevels));
  }
  m_numLevels = pyr.numLevels();
  m_K0 = pyr.level(0).K;
  m_features.clear();
  m_refAffine = refKf.affine;
  m_refExposure = refKf.exposure;
  m_firstRmse = std::numeric_limits<double>::quiet_NaN();
  for (int l = 0; l < m_numLevels; ++l) {
    const PyramidLevel &src = pyr.level(l);
    LevelData &dst = m_levels[static_cast<size_t>(l)];
    dst.width = src.width;
    dst.height = src.height;
    dst.K = src.K;
    const size_t n = static_cast<size_t>(src.width) * static_cast<size_t>(src.height);
    dst.idepthMap.assign(n, 0.f);
    dst.weightMap.assign(n, 0.f);
    dst.weightBackup.resize(n);
  }
  buildDepthMaps(points);

  // Residual point lists (SoA), level by level, from the normalised maps.
  int maxPoints = 0;
  for (int l = 0; l < m_numLevels; ++l) {
    LevelData &L = m_levels[static_cast<size_t>(l)];
    const PyramidLevel &refLevel = pyr.level(l);
    const size_t n = L.idepthMap.size();
    L.pu.resize(n);
    L.pv.resize(n);
    L.pidepth.resize(n);
    L.pcolor.resize(n);
    int count = 0;
    for (int y = kReferenceBorder; y < L.height - kReferenceBorder; ++y) {
      for (int x = kReferenceBorder; x < L.width - kReferenceBorder; ++x) {
        const size_t i = static_cast<size_t>(y) * static_cast<size_t>(L.width) + static_cast<size_t>(x);
        if (!(L.weightMap[i] > 0.f)) {
          continue;
        }
        const float idepth = L.idepthMap[i] / L.weightMap[i];
        const float color = refLevel.color[i][0];
        if (!(idepth > 0.f) || !std::isfinite(idepth) || !std::isfinite(color)) {
          continue;
        }
        L.pu[static_cast<size_t>(count)] = static_cast<float>(x);
        L.pv[static_cast<size_t>(count)] = static_cast<float>(y);
        L.pidepth[static_cast<size_t>(count)] = idepth;
        L.pcolor[static_cast<size_t>(count)] = color;
        ++count;
      }
    }
    L.numPoints = count;
    maxPoints = std::max(maxPoints, count);
  }
  const size_t m = static_cast<size_t>(maxPoints);
  for (std::vector<float> *buf :
       {&m_bufIdepth, &m_bufU, &m_bufV, &m_bufDx, &m_bufDy, &m_bufResidual, &m_bufWeight, &m_bufRefColor}) {
    buf->assign(m, 0.f);
  }
}

void CoarseTracker::buildDepthMaps(const std::vector<CoarseTrackerPoint> &points)
{
  // Level 0: weighted sums of inverse depth at the nearest pixel (DSO makeCoarseDepthL0).
  LevelData &L0 = m_levels[0];
  for (const CoarseTrackerPoint &p : points) {
    const int x = static_cast<int>(std::floor(p.u + 0.5f));
    const int y = static_cast<int>(std::floor(p.v + 0.5f));
    if (x < 0 || y < 0 || x >= L0.width || y >= L0.height || !(p.idepth > 0.f) || !(p.weight > 0.f) ||
        !std::isfinite(p.idepth)) {
      continue;
    }
    const size_t i = static_cast<size_t>(y) * static_cast<size_t>(L0.width) + static_cast<size_t>(x);
    L0.idepthMap[i] += p.idepth * p.weight;
    L0.weightMap[i] += p.weight;
  }
  // Coarser levels: sums over 2x2 blocks (the ratio stays a weighted average).
  for (int l = 1; l < m_numLevels; ++l) {
    const LevelData &F = m_levels[static_cast<size_t>(l - 1)];
    LevelData &C = m_levels[static_cast<size_t>(l)];
    for (int y = 0; y < C.height; ++y) {
      for (int x = 0; x < C.width; ++x) {
        const size_t f = static_cast<size_t>(2 * y) * static_cast<size_t>(F.width) + static_cast<size_t>(2 * x);
        const size_t fw = f + static_cast<size_t>(F.width);
        const size_t c = static_cast<size_t>(y) * static_cast<size_t>(C.width) + static_cast<size_t>(x);
        C.idepthMap[c] = F.idepthMap[f] + F.idepthMap[f + 1] + F.idepthMap[fw] + F.idepthMap[fw + 1];
        C.weightMap[c] = F.weightMap[f] + F.weightMap[f + 1] + F.weightMap[fw] + F.weightMap[fw + 1];
      }
    }
  }
  // One dilation step: an empty pixel takes the mean of its filled neighbours (diagonal neighbours on the two
  // finest levels, axis neighbours on coarser ones, DSO). The sums are averaged as sums, so the normalised value
  // is the weighted mean of the neighbours.
  for (int l = 0; l < m_numLevels; ++l) {
    LevelData &L = m_levels[static_cast<size_t>(l)];
    const int w = L.width;
    std::copy(L.weightMap.begin(), L.weightMap.end(), L.weightBackup.begin());
    const bool diagonal = l < kDiagonalDilationLevels;
    const int o1 = diagonal ? w + 1 : 1;
    const int o2 = diagonal ? w - 1 : w;
    const int offsets[4] = {o1, -o1, o2, -o2};
    // Only the empty neighbours of filled pixels can change: they are visited from the filled pixels (a few
    // thousand of the 307200 at 640x480) instead of testing every pixel's four neighbours. Each is computed once,
    // from the filled pixels only, with the same sums in the same order, so the order of the visits does not matter.
    const float *filled = L.weightBackup.data();
    const size_t n = L.weightBackup.size();
    for (size_t j = 0; j < n; ++j) {
      if (!(filled[j] > 0.f)) {
        continue;
      }
      for (int o : offsets) {
        const int i = static_cast<int>(j) - o;
        const int x = i % w;
        const int y = i / w;
        if (i < 0 || x < 1 || y < 1 || x >= w - 1 || y >= L.height - 1 || filled[i] > 0.f ||
            L.weightMap[static_cast<size_t>(i)] > 0.f) {
          continue; // outside the interior, filled, or already visited
        }
        dilatePixel(L, i, offsets);
      }
    }
  }
}

void CoarseTracker::dilatePixel(LevelData &L, int i, const int (&offsets)[4])
{
  float sumIdepth = 0.f, sumWeight = 0.f;
  int count = 0;
  for (int o : offsets) {
    const size_t j = static_cast<size_t>(i + o);
    if (L.weightBackup[j] > 0.f) {
      sumIdepth += L.idepthMap[j];
      sumWeight += L.weightBackup[j];
      ++count;
    }
  }
  if (count > 0) {
    L.idepthMap[static_cast<size_t>(i)] = sumIdepth / static_cast<float>(count);
    L.weightMap[static_cast<size_t>(i)] = sumWeight / static_cast<float>(count);
  }
}
double CoarseTracker::meanShiftPx(const SE3d &fromMref, const SE3d &toMref) const
{
  if (m_numLevels < 1) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const LevelData &L = m_levels[0];
  const int step = std::max(1, L.numPoints / kShiftSamplePoints);
  const Eigen::Matrix3d Rfrom = fromMref.rotationMatrix(), Rto = toMref.rotationMatrix();
  const Eigen::Vector3d tFrom = fromMref.translation(), tTo = toMref.translation();
  double sum = 0.;
  int count = 0;
  for (int k = 0; k < L.numPoints; k += step) {
    const size_t i = static_cast<size_t>(k);
    const Eigen::Vector3d X = L.K.unproject(L.pu[i], L.pv[i], L.pidepth[i]);
    const Eigen::Vector3d a = Rfrom * X + tFrom, b = Rto * X + tTo;
    if (!(a.z() > 0.) || !(b.z() > 0.)) {
      continue;
    }
    sum += (L.K.project(a) - L.K.project(b)).norm();
    ++count;
  }
  return count > 0 ? sum / count : std::numeric_limits<double>::quiet_NaN();
}
} // namespace hslam
