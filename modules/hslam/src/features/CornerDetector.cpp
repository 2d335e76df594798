/*
 * H-SLAM for ViSP.
 */
#include "features/CornerDetector.h"

#include <opencv2/features2d.hpp>

#include <algorithm>
#include <cmath>

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
} // namespace

void detectCorners(const vpImage<unsigned char> &I, const CornerOptions &options, std::vector<cv::Point2f> &corners,
                   std::vector<float> *responses)
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
  cv::FAST(image, fast, std::max(1, options.threshold), true);
  const float lo = static_cast<float>(options.border);
  const float hiU = static_cast<float>(w - 1 - options.border), hiV = static_cast<float>(h - 1 - options.border);
  fast.erase(
      std::remove_if(fast.begin(), fast.end(),
                     [&](const cv::KeyPoint &k) { return k.pt.x < lo || k.pt.y < lo || k.pt.x > hiU || k.pt.y > hiV; }),
      fast.end());
  // Strongest first; ties broken by position so the order never depends on the sort implementation.
  std::sort(fast.begin(), fast.end(), [](const cv::KeyPoint &a, const cv::KeyPoint &b) {
    if (a.response != b.response) {
      return a.response > b.response;
    }
    return a.pt.y != b.pt.y ? a.pt.y < b.pt.y : a.pt.x < b.pt.x;
  });
  const int cell = std::max(1, options.cellSizePx);
  const int cols = (w + cell - 1) / cell, rows = (h + cell - 1) / cell;
  const int cap = std::max(
      1, static_cast<int>(std::ceil(options.cellShareFactor * options.maxCorners / static_cast<double>(cols * rows))));
  std::vector<int> perCell(static_cast<size_t>(cols * rows), 0);
  std::vector<bool> taken(fast.size(), false);
  DistanceGrid grid(w, h, options.minDistance);
  const size_t budget = static_cast<size_t>(options.maxCorners);
  for (int pass = 0; pass < 2 && corners.size() < budget; ++pass) {
    for (size_t i = 0; i < fast.size() && corners.size() < budget; ++i) {
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
      if (responses) {
        responses->push_back(fast[i].response);
      }
    }
  }
}
} // namespace hslam
