/*
 * H-SLAM for ViSP.
 */
#include "mapping/SparseIdepthInterpolator.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace hslam
{
namespace
{
//! Grid cells are sized to hold about this many samples each, so a k-NN query visits few cells.
constexpr double kSamplesPerCell = 2.;
//! Mean absolute deviation to standard deviation for Gaussian data: sqrt(pi / 2).
constexpr double kMeanAbsDevToSigma = 1.2533;

int clampCell(double x, double cell, int n)
{
  return std::min(n - 1, std::max(0, static_cast<int>(x / cell)));
}
} // namespace

SparseIdepthInterpolator::SparseIdepthInterpolator(const std::vector<IdepthSample> &samples, int width, int height,
                                                   int neighbours, double minRelativeSigma)
    : m_samples(samples), m_neighbours(neighbours), m_minRelativeSigma(minRelativeSigma)
{
  if (samples.empty() || width <= 0 || height <= 0 || neighbours < 1 || neighbours > kMaxNeighbours ||
      minRelativeSigma < 0.) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                               ": SparseIdepthInterpolator needs samples, a positive size and 1 <= k <= " +
                               std::to_string(kMaxNeighbours));
  }
  m_cellSize = std::max(1., std::sqrt(static_cast<double>(width) * height * kSamplesPerCell / samples.size()));
  m_cols = static_cast<int>(std::ceil(width / m_cellSize));
  m_rows = static_cast<int>(std::ceil(height / m_cellSize));
  std::vector<int> cellOf(samples.size());
  m_cellStart.assign(static_cast<size_t>(m_cols * m_rows + 1), 0);
  for (size_t i = 0; i < samples.size(); ++i) {
    cellOf[i] = clampCell(samples[i].v, m_cellSize, m_rows) * m_cols + clampCell(samples[i].u, m_cellSize, m_cols);
    ++m_cellStart[static_cast<size_t>(cellOf[i] + 1)];
  }
  for (size_t c = 1; c < m_cellStart.size(); ++c) {
    m_cellStart[c] += m_cellStart[c - 1];
  }
  m_cellIndex.assign(samples.size(), 0);
  std::vector<int> fill(m_cellStart.begin(), m_cellStart.end() - 1);
  for (size_t i = 0; i < samples.size(); ++i) {
    m_cellIndex[static_cast<size_t>(fill[static_cast<size_t>(cellOf[i])]++)] = static_cast<int>(i);
  }
}

IdepthPrior SparseIdepthInterpolator::query(double u, double v) const
{
  const int k = std::min(m_neighbours, static_cast<int>(m_samples.size()));
  // Sorted k best (squared distance, sample index), insertion into a fixed buffer.
  std::array<double, kMaxNeighbours> bestD2;
  std::array<int, kMaxNeighbours> bestIdx;
  int found = 0;
  const int cu = clampCell(u, m_cellSize, m_cols), cv = clampCell(v, m_cellSize, m_rows);
  const int maxRing = std::max(m_cols, m_rows);
  for (int ring = 0; ring <= maxRing; ++ring) {
    // Cells of this ring are at least (ring - 1) cells away from the query (it may sit anywhere in its cell).
    if (found == k) {
      const double minDist = std::max(0, ring - 1) * m_cellSize;
      if (minDist * minDist > bestD2[static_cast<size_t>(k - 1)]) {
        break;
      }
    }
    for (int gy = cv - ring; gy <= cv + ring; ++gy) {
      if (gy < 0 || gy >= m_rows) {
        continue;
      }
      const bool edgeRow = gy == cv - ring || gy == cv + ring;
      for (int gx = cu - ring; gx <= cu + ring; gx += (edgeRow || ring == 0) ? 1 : 2 * ring) {
        if (gx < 0 || gx >= m_cols) {
          continue;
        }
        const int c = gy * m_cols + gx;
        for (int j = m_cellStart[static_cast<size_t>(c)]; j < m_cellStart[static_cast<size_t>(c + 1)]; ++j) {
          const int idx = m_cellIndex[static_cast<size_t>(j)];
          const IdepthSample &s = m_samples[static_cast<size_t>(idx)];
          const double d2 = (s.u - u) * (s.u - u) + (s.v - v) * (s.v - v);
          if (found == k && d2 >= bestD2[static_cast<size_t>(k - 1)]) {
            continue;
          }
          int pos = found < k ? found++ : k - 1;
          while (pos > 0 && bestD2[static_cast<size_t>(pos - 1)] > d2) {
            bestD2[static_cast<size_t>(pos)] = bestD2[static_cast<size_t>(pos - 1)];
            bestIdx[static_cast<size_t>(pos)] = bestIdx[static_cast<size_t>(pos - 1)];
            --pos;
          }
          bestD2[static_cast<size_t>(pos)] = d2;
          bestIdx[static_cast<size_t>(pos)] = idx;
        }
      }
    }
  }
  std::array<double, kMaxNeighbours> values;
  for (int i = 0; i < found; ++i) {
    values[static_cast<size_t>(i)] = m_samples[static_cast<size_t>(bestIdx[static_cast<size_t>(i)])].idepth;
  }
  IdepthPrior prior;
  prior.neighbours = found;
  if (found == 0) {
    return prior;
  }
  prior.farthestPx = std::sqrt(bestD2[static_cast<size_t>(found - 1)]);
  auto median = [found](std::array<double, kMaxNeighbours> &a) {
    std::sort(a.begin(), a.begin() + found);
    return found % 2 ? a[static_cast<size_t>(found / 2)]
                     : 0.5 * (a[static_cast<size_t>(found / 2 - 1)] + a[static_cast<size_t>(found / 2)]);
  };
  prior.idepth = median(values);
  // Mean (not median) absolute deviation from the median: a minority of neighbours on the other side of a depth
  // edge must widen the prior even though the median ignores them.
  double absDevSum = 0.;
  for (int i = 0; i < found; ++i) {
    absDevSum += std::abs(values[static_cast<size_t>(i)] - prior.idepth);
  }
  const double sigmaSpread = kMeanAbsDevToSigma * absDevSum / found;
  const double sigmaFloor = m_minRelativeSigma * std::abs(prior.idepth);
  prior.idepthVar = sigmaSpread * sigmaSpread + sigmaFloor * sigmaFloor;
  return prior;
}
} // namespace hslam
