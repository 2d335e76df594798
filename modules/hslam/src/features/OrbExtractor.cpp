/*
 * H-SLAM for ViSP.
 */
#include "features/OrbExtractor.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <string>

namespace hslam
{
namespace
{
//! Border excluded by ORB: the 31x31 rBRIEF patch must fit (ORB-SLAM2: EDGE_THRESHOLD 19 for a patch of 31).
constexpr int kOrbEdgeThreshold = 19;
constexpr int kOrbPatchSize = 31;
//! cv::ORB's WTA_K = 2: plain binary tests, Hamming distance.
constexpr int kOrbWtaK = 2;
} // namespace

OrbExtractor::OrbExtractor(const OrbExtractorOptions &options) : m_options(options)
{
  if (options.maxFeatures <= 0 || options.levels <= 0 || options.scaleFactor <= 1.f || options.cellSizePx <= 0 ||
      options.oversampling <= 0 || options.fastThreshold <= 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           std::string(__FILE__) + ":" + std::to_string(__LINE__) + ": invalid ORB extractor options");
  }
  m_orb = cv::ORB::create(options.maxFeatures * options.oversampling, options.scaleFactor, options.levels,
                          kOrbEdgeThreshold, 0, kOrbWtaK, cv::ORB::HARRIS_SCORE, kOrbPatchSize, options.fastThreshold);
}

void OrbExtractor::extract(const vpImage<unsigned char> &I, std::vector<cv::KeyPoint> &keypoints, cv::Mat &descriptors)
{
  if (I.getSize() == 0) {
    throw vpHSlamException(vpHSlamException::invalidImage,
                           std::string(__FILE__) + ":" + std::to_string(__LINE__) + ": empty image given to ORB");
  }
  // vpImage rows are contiguous 8-bit pixels: wrap without copying.
  const cv::Mat image(static_cast<int>(I.getHeight()), static_cast<int>(I.getWidth()), CV_8UC1,
                      const_cast<unsigned char *>(I.bitmap));

  std::vector<cv::KeyPoint> candidates;
  m_orb->detect(image, candidates);

  // Bucketing: every cell first keeps its strongest corners, up to an equal share of the budget.
  const int cols = (image.cols + m_options.cellSizePx - 1) / m_options.cellSizePx;
  const int rows = (image.rows + m_options.cellSizePx - 1) / m_options.cellSizePx;
  const int perCell = std::max(1, (m_options.maxFeatures + cols * rows - 1) / (cols * rows));
  std::sort(candidates.begin(), candidates.end(),
            [](const cv::KeyPoint &a, const cv::KeyPoint &b) { return a.response > b.response; });
  std::vector<int> cellCount(static_cast<size_t>(cols * rows), 0);
  std::vector<cv::KeyPoint> selected, leftovers;
  selected.reserve(static_cast<size_t>(m_options.maxFeatures));
  for (const cv::KeyPoint &kp : candidates) {
    const int cx = std::min(cols - 1, std::max(0, static_cast<int>(kp.pt.x) / m_options.cellSizePx));
    const int cy = std::min(rows - 1, std::max(0, static_cast<int>(kp.pt.y) / m_options.cellSizePx));
    int &count = cellCount[static_cast<size_t>(cy * cols + cx)];
    if (count < perCell && static_cast<int>(selected.size()) < m_options.maxFeatures) {
      ++count;
      selected.push_back(kp);
    } else {
      leftovers.push_back(kp);
    }
  }
  // Cells without texture leave budget unused: give it to the strongest remaining corners.
  for (size_t i = 0; i < leftovers.size() && static_cast<int>(selected.size()) < m_options.maxFeatures; ++i) {
    selected.push_back(leftovers[i]);
  }
  keypoints.swap(selected);
  m_orb->compute(image, keypoints, descriptors);
}
} // namespace hslam
