/*
 * H-SLAM for ViSP.
 */
#include <visp3/hslam/vpHSlamVocabulary.h>

#include "features/OrbExtractor.h"
#include "features/OrbVocabulary.h"
#include "features/VocabularyFiles.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace
{
const char *const kDefaultFileName = "hslam-orb.hvoc";

hslam::VocabularyFormat toInternal(vpHSlamVocabulary::FileFormat format)
{
  switch (format) {
  case vpHSlamVocabulary::formatBinary:
    return hslam::VocabularyFormat::binary;
  case vpHSlamVocabulary::formatDbow2Text:
    return hslam::VocabularyFormat::dbow2Text;
  case vpHSlamVocabulary::formatDbow2Yaml:
    return hslam::VocabularyFormat::dbow2Yaml;
  default:
    return hslam::VocabularyFormat::automatic;
  }
}

bool isFile(const std::string &path)
{
  std::error_code ec;
  return !path.empty() && std::filesystem::is_regular_file(path, ec);
}

std::vector<hslam::OrbDescriptor> describeImage(const vpImage<unsigned char> &I)
{
  hslam::OrbExtractor extractor;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  extractor.extract(I, keypoints, descriptors);
  return hslam::descriptorsFromMat(descriptors);
}
} // namespace

vpHSlamVocabulary::vpHSlamVocabulary() : m_impl(new hslam::OrbVocabulary()) {}
vpHSlamVocabulary::~vpHSlamVocabulary() = default;
vpHSlamVocabulary::vpHSlamVocabulary(const vpHSlamVocabulary &other) : m_impl(new hslam::OrbVocabulary(*other.m_impl))
{
}
vpHSlamVocabulary &vpHSlamVocabulary::operator=(const vpHSlamVocabulary &other)
{
  if (this != &other) {
    *m_impl = *other.m_impl;
  }
  return *this;
}
vpHSlamVocabulary::vpHSlamVocabulary(vpHSlamVocabulary &&other) noexcept : m_impl(std::move(other.m_impl))
{
  other.m_impl.reset(new (std::nothrow) hslam::OrbVocabulary());
}
vpHSlamVocabulary &vpHSlamVocabulary::operator=(vpHSlamVocabulary &&other) noexcept
{
  if (this != &other) {
    m_impl.swap(other.m_impl);
  }
  return *this;
}
vpHSlamVocabulary::vpHSlamVocabulary(const hslam::OrbVocabulary &vocabulary)
    : m_impl(new hslam::OrbVocabulary(vocabulary))
{
}

vpHSlamVocabulary vpHSlamVocabulary::load(const std::string &path, FileFormat format)
{
  vpHSlamVocabulary result;
  *result.m_impl = hslam::loadVocabulary(path, toInternal(format));
  return result;
}

void vpHSlamVocabulary::save(const std::string &path, FileFormat format) const
{
  hslam::saveVocabulary(*m_impl, path, format == formatAuto ? hslam::VocabularyFormat::binary : toInternal(format));
}

std::string vpHSlamVocabulary::defaultPath()
{
  const char *env = std::getenv("HSLAM_VOCABULARY");
  if (env && *env) {
    return env;
  }
  const std::string installed = std::string(HSLAM_INSTALL_DATA_DIR) + "/" + kDefaultFileName;
  if (isFile(installed)) {
    return installed;
  }
  const std::string source =
      std::filesystem::path(std::string(HSLAM_SOURCE_DATA_DIR) + "/" + kDefaultFileName).lexically_normal().string();
  return isFile(source) ? source : std::string();
}

vpHSlamVocabulary::FileFormat vpHSlamVocabulary::parseFormat(const std::string &name)
{
  if (name == "auto") {
    return formatAuto;
  }
  if (name == "binary") {
    return formatBinary;
  }
  if (name == "text") {
    return formatDbow2Text;
  }
  if (name == "yaml") {
    return formatDbow2Yaml;
  }
  throw vpHSlamException(vpHSlamException::invalidArgument,
                         "unknown vocabulary format '" + name + "' (auto, binary, text or yaml)");
}

bool vpHSlamVocabulary::empty() const
{
  return m_impl->empty();
}
unsigned int vpHSlamVocabulary::getBranching() const
{
  return static_cast<unsigned int>(m_impl->branching());
}
unsigned int vpHSlamVocabulary::getLevels() const
{
  return static_cast<unsigned int>(m_impl->levels());
}
std::size_t vpHSlamVocabulary::getWordCount() const
{
  return m_impl->wordCount();
}
std::size_t vpHSlamVocabulary::getNodeCount() const
{
  return m_impl->nodeCount();
}
std::uint64_t vpHSlamVocabulary::getFingerprint() const
{
  return m_impl->fingerprint();
}
const hslam::OrbVocabulary &vpHSlamVocabulary::impl() const
{
  return *m_impl;
}

std::string vpHSlamVocabulary::describe() const
{
  if (empty()) {
    return "empty vocabulary";
  }
  static const char *const kWeighting[] = {"TF-IDF", "TF", "IDF", "binary"};
  std::ostringstream out;
  out << "ORB vocabulary: k = " << getBranching() << ", L = " << getLevels() << ", " << getWordCount() << " words, "
      << getNodeCount() << " nodes, " << kWeighting[static_cast<int>(m_impl->weighting())] << " weights, L1 score";
  return out.str();
}

double vpHSlamVocabulary::score(const vpImage<unsigned char> &I1, const vpImage<unsigned char> &I2) const
{
  if (empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "vpHSlamVocabulary::score: the vocabulary is empty");
  }
  hslam::BowVector v1, v2;
  m_impl->transform(describeImage(I1), v1);
  m_impl->transform(describeImage(I2), v2);
  return hslam::OrbVocabulary::score(v1, v2);
}
