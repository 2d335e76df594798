/*
 * H-SLAM for ViSP.
 */
#include "features/CornerDetector.h"

#include <opencv2/features2d.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

namespace hslam
{
namespace
{
//! Grid of accepted corners for the minimum-distance rule: cells of minDistance, neighbours checked.
class DistanceGrid
{
public:
  DistanceGrid(int width, int height, double minDistance)
      : m_cell(std::max(1., minDistance)), m_minDistance2(minDistance * minDistance),
        m_cols(static_cast<int>(width / m_cell) + 1), m_rows(static_cast<int>(height / m_cell) + 1),
        m_cells(static_cast<size_t>(m_cols) * static_cast<size_t>(m_rows))
  {
  }
  bool isFree(const cv::Point2f &p) const
  {
    if (m_minDistance2 <= 0.) {
      return true;
    }
    const int cx = static_cast<int>(p.x / m_cell), cy = static_cast<int>(p.y / m_cell);
    for (int y = std::max(0, cy - 1); y <= std::min(m_rows - 1, cy + 1); ++y) {
      for (int x = std::max(0, cx - 1); x <= std::min(m_cols - 1, cx + 1); ++x) {
        for (const cv::Point2f &q : m_cells[static_cast<size_t>(y * m_cols + x)]) {
          const double du = p.x - q.x, dv = p.y - q.y;
          if (du * du + dv * dv < m_minDistance2) {
            return false;
          }
        }
      }
    }
    return true;
  }
  void add(const cv::Point2f &p)
  {
    const int cx = static_cast<int>(p.x / m_cell), cy = static_cast<int>(p.y / m_cell);
    m_cells[static_cast<size_t>(cy * m_cols + cx)].push_back(p);
  }

private:
  double m_cell, m_minDistance2;
  int m_cols, m_rows;
  std::vector<std::vector<cv::Point2f>> m_cells;
};

//! Packed sort keys (see detectSorted()): scores below 2^16, coordinates below 2^20.
constexpr float kMaxPackedScore = 65536.f;
constexpr float kMaxPackedCoordinate = 1048576.f;

//! Outcome of the selection passes.
struct SpreadResult {
  bool filledInFirstPass = false; //!< the budget was filled before the per-cell caps were lifted
  float weakest = 0.f;            //!< then: the lowest FAST score among the selected corners
};

//! FAST corners of \e image at \e threshold, inside the border, strongest first (ties by position).
void detectSorted(const cv::Mat &image, int threshold, int border, std::vector<cv::KeyPoint> &fast)
{
  fast.clear();
  cv::FAST(image, fast, std::max(1, threshold), true);
  const float lo = static_cast<float>(border);
  const float hiU = static_cast<float>(image.cols - 1 - border), hiV = static_cast<float>(image.rows - 1 - border);
  fast.erase(
      std::remove_if(fast.begin(), fast.end(),
                     [&](const cv::KeyPoint &k) { return k.pt.x < lo || k.pt.y < lo || k.pt.x > hiU || k.pt.y > hiV; }),
      fast.end());
  // Strongest first; ties broken by position so the order never depends on the sort implementation. FAST's scores
  // and positions are small non-negative integers: packed into one 64-bit key (score descending, then row, then
  // column) they sort in the same order several times faster than the keypoints themselves.
  const auto packable = [](const cv::KeyPoint &k) {
    return k.response >= 0.f && k.response < kMaxPackedScore && k.response == std::floor(k.response) && k.pt.x >= 0.f &&
           k.pt.x < kMaxPackedCoordinate && k.pt.x == std::floor(k.pt.x) && k.pt.y >= 0.f &&
           k.pt.y < kMaxPackedCoordinate && k.pt.y == std::floor(k.pt.y);
  };
  if (!std::all_of(fast.begin(), fast.end(), packable)) {
    std::sort(fast.begin(), fast.end(), [](const cv::KeyPoint &a, const cv::KeyPoint &b) {
      if (a.response != b.response) {
        return a.response > b.response;
      }
      return a.pt.y != b.pt.y ? a.pt.y < b.pt.y : a.pt.x < b.pt.x;
    });
    return;
  }
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keys(fast.size());
  for (size_t i = 0; i < fast.size(); ++i) {
    const cv::KeyPoint &k = fast[i];
    const std::uint64_t weakness = static_cast<std::uint64_t>(kMaxPackedScore - 1.f - k.response);
    keys[i] = {(weakness << 40) | (static_cast<std::uint64_t>(k.pt.y) << 20) | static_cast<std::uint64_t>(k.pt.x),
               static_cast<std::uint32_t>(i)};
  }
  std::sort(keys.begin(), keys.end());
  std::vector<cv::KeyPoint> sorted;
  sorted.reserve(fast.size());
  for (const auto &key : keys) {
    sorted.push_back(fast[key.second]);
  }
  fast.swap(sorted);
}

//! The two selection passes over \e fast (sorted, strongest first).
SpreadResult selectSpread(const std::vector<cv::KeyPoint> &fast, int width, int height, const CornerOptions &options,
                          std::vector<cv::Point2f> &corners, std::vector<float> *responses)
{
  corners.clear();
  if (responses) {
    responses->clear();
  }
  const int cell = std::max(1, options.cellSizePx);
  const int cols = (width + cell - 1) / cell, rows = (height + cell - 1) / cell;
  const int cap = std::max(
      1, static_cast<int>(std::ceil(options.cellShareFactor * options.maxCorners / static_cast<double>(cols * rows))));
  std::vector<int> perCell(static_cast<size_t>(cols * rows), 0);
  std::vector<bool> taken(fast.size(), false);
  DistanceGrid grid(width, height, options.minDistance);
  const size_t budget = static_cast<size_t>(options.maxCorners);
  SpreadResult result;
  for (int pass = 0; pass < 2; ++pass) {
    for (size_t i = 0; i < fast.size(); ++i) {
      if (corners.size() >= budget) {
        break;
      }
      if (taken[i]) {
        continue;
      }
      const cv::Point2f &p = fast[i].pt;
      const size_t c = static_cast<size_t>(static_cast<int>(p.y) / cell * cols + static_cast<int>(p.x) / cell);
      if ((pass == 0 && perCell[c] >= cap) || !grid.isFree(p)) {
        continue;
      }
      taken[i] = true;
      ++perCell[c];
      grid.add(p);
      corners.push_back(p);
      result.weakest = fast[i].response; // the first pass takes them strongest first
      if (responses) {
        responses->push_back(fast[i].response);
      }
    }
    if (corners.size() >= budget) {
      result.filledInFirstPass = pass == 0;
      break;
    }
  }
  return result;
}
} // namespace

void detectCorners(const vpImage<unsigned char> &I, const CornerOptions &options, std::vector<cv::Point2f> &corners,
                   std::vector<float> *responses, CornerThresholdHint *hint)
{
  corners.clear();
  if (responses) {
    responses->clear();
  }
  const int w = static_cast<int>(I.getWidth()), h = static_cast<int>(I.getHeight());
  if (options.maxCorners <= 0 || w <= 2 * options.border || h <= 2 * options.border) {
    return;
  }
  const cv::Mat image(h, w, CV_8UC1, const_cast<unsigned char *>(I.bitmap));
  std::vector<cv::KeyPoint> fast;
  // A FAST score does not depend on the threshold, and non-maximum suppression keeps a corner whatever its weaker
  // neighbours' threshold: the corners scoring T or more are the same at threshold T as at any lower one, in the
  // same order at the head of the list. When they fill the budget in the bucketed first pass, the weaker ones would
  // never have been reached, so the detection at T alone gives exactly the corners of the full one. It is much
  // cheaper: at threshold 7 most pixels of a textured image pass FAST's quick test (bench_corner_detector). The
  // hint starts the ladder at the step the previous image's corners would have filled, so that a caller whose
  // images need the full detection does not pay for the failing strong ones every time.
  const int start = hint ? hint->threshold : kCornerStrongThresholds[0];
  SpreadResult result;
  for (int strong : kCornerStrongThresholds) {
    if (options.strongFirst && strong <= start && strong > options.threshold) {
      detectSorted(image, strong, options.border, fast);
      result = selectSpread(fast, w, h, options, corners, responses);
      if (result.filledInFirstPass) {
        break;
      }
    }
  }
  if (!result.filledInFirstPass) {
    detectSorted(image, options.threshold, options.border, fast);
    result = selectSpread(fast, w, h, options, corners, responses);
  }
  if (hint) {
    hint->threshold = 0; // next time: the configured threshold at once
    for (int strong : kCornerStrongThresholds) {
      if (result.filledInFirstPass && static_cast<float>(strong) <= result.weakest) {
        hint->threshold = strong;
        break;
      }
    }
  }
}
} // namespace hslam
