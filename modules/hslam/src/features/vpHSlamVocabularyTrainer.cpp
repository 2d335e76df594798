/*
 * H-SLAM for ViSP.
 */
#include <visp3/hslam/vpHSlamVocabularyTrainer.h>

#include "features/OrbExtractor.h"
#include "features/VocabularyTrainer.h"

#include <visp3/hslam/vpHSlamException.h>

struct vpHSlamVocabularyTrainer::Impl {
  explicit Impl(const Options &o) : options(o), extractor(extractorOptions(o)) {}
  static hslam::OrbExtractorOptions extractorOptions(const Options &o)
  {
    if (o.featuresPerImage == 0) {
      throw vpHSlamException(vpHSlamException::invalidArgument,
                             "vpHSlamVocabularyTrainer: featuresPerImage must be positive");
    }
    hslam::OrbExtractorOptions e;
    e.maxFeatures = static_cast<int>(o.featuresPerImage);
    return e;
  }
  Options options;
  hslam::OrbExtractor extractor;
  std::vector<std::vector<hslam::OrbDescriptor>> images;
  std::size_t descriptors = 0;
};

vpHSlamVocabularyTrainer::vpHSlamVocabularyTrainer() : m_impl(new Impl(Options())) {}
vpHSlamVocabularyTrainer::vpHSlamVocabularyTrainer(const Options &options) : m_impl(new Impl(options)) {}
vpHSlamVocabularyTrainer::~vpHSlamVocabularyTrainer() = default;

unsigned int vpHSlamVocabularyTrainer::addImage(const vpImage<unsigned char> &I)
{
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  m_impl->extractor.extract(I, keypoints, descriptors);
  m_impl->images.push_back(hslam::descriptorsFromMat(descriptors));
  m_impl->descriptors += m_impl->images.back().size();
  return static_cast<unsigned int>(m_impl->images.back().size());
}

std::size_t vpHSlamVocabularyTrainer::getImageCount() const
{
  return m_impl->images.size();
}
std::size_t vpHSlamVocabularyTrainer::getDescriptorCount() const
{
  return m_impl->descriptors;
}

vpHSlamVocabulary vpHSlamVocabularyTrainer::train(const std::function<void(double)> &progress) const
{
  hslam::VocabularyTrainingOptions o;
  o.branching = static_cast<int>(m_impl->options.branching);
  o.levels = static_cast<int>(m_impl->options.levels);
  o.seed = m_impl->options.seed;
  o.maxKmeansIterations = static_cast<int>(m_impl->options.maxKmeansIterations);
  return vpHSlamVocabulary(hslam::trainVocabulary(m_impl->images, o, progress));
}
