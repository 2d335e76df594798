/*
 * H-SLAM for ViSP.
 */
#include "loop/LoopFeatures.h"

#include "common/HeapBytes.h"

#include <opencv2/core.hpp>

#include <cmath>

namespace hslam
{
double LoopKeyframe::memoryBytes() const
{
  return vectorHeapBytes(X) + vectorHeapBytes(orb) + vectorHeapBytes(octave);
}

void LoopKeyframe::rescale(double scale)
{
  const float inverse = static_cast<float>(1. / scale);
  for (Eigen::Vector3f &p : X) {
    p *= inverse;
  }
}

namespace
{
OrbExtractorOptions extractorOptions(const LoopFeatureOptions &o)
{
  OrbExtractorOptions e;
  e.maxFeatures = o.maxFeatures > 0 ? o.maxFeatures : 1;
  return e;
}
} // namespace

LoopFeatureExtractor::LoopFeatureExtractor(const LoopFeatureOptions &options)
    : m_options(options), m_extractor(extractorOptions(options))
{
}

LoopKeyframe LoopFeatureExtractor::extract(int id, const vpImage<unsigned char> &image,
                                           const std::vector<IdepthSample> &samples, const PinholeIntrinsics &K,
                                           std::vector<OrbDescriptor> &allDescriptors)
{
  LoopKeyframe out;
  out.id = id;
  allDescriptors.clear();
  if (m_options.maxFeatures <= 0 || image.getSize() == 0) {
    return out;
  }
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  m_extractor.extract(image, keypoints, descriptors);
  allDescriptors = descriptorsFromMat(descriptors);
  if (samples.empty()) {
    return out;
  }
  const SparseIdepthInterpolator interpolator(samples, static_cast<int>(image.getWidth()),
                                              static_cast<int>(image.getHeight()), m_options.sampleNeighbours, 0.);
  const double maxDistancePx = kMaxSampleDistanceFraction * image.getWidth();
  for (size_t i = 0; i < keypoints.size() && i < allDescriptors.size(); ++i) {
    const cv::KeyPoint &kp = keypoints[i];
    const IdepthPrior prior = interpolator.query(kp.pt.x, kp.pt.y);
    if (prior.neighbours < 3 || prior.farthestPx > maxDistancePx || !(prior.idepth > 0.) ||
        std::sqrt(prior.idepthVar) > kMaxRelativeSpread * prior.idepth) {
      continue;
    }
    out.X.push_back(K.unproject(kp.pt.x, kp.pt.y, prior.idepth).cast<float>());
    out.orb.push_back(allDescriptors[i]);
    out.octave.push_back(static_cast<std::uint8_t>(kp.octave));
  }
  out.X.shrink_to_fit();
  out.orb.shrink_to_fit();
  out.octave.shrink_to_fit();
  return out;
}
} // namespace hslam
