/*
 * H-SLAM for ViSP.
 */
#include "io/IndexedImageSource.h"

#include "common/TextParsing.h"
#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <sstream>

namespace hslam
{
using namespace io;

namespace
{
std::string where(const IndexedFrame &f)
{
  return f.listFile.empty() ? f.path : fileLine(f.listFile, f.line);
}
} // namespace

IndexedImageSource::IndexedImageSource(Format format, const std::string &root) : m_format(format), m_root(root) {}

void IndexedImageSource::setFrames(std::vector<IndexedFrame> all, const vpHSlamImageSource::Options &options,
                                   double nominalFrameRate)
{
  if (all.empty()) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "'" + m_root + "' lists no image");
  }
  // Checked over the whole list, not only the selection: a broken list is broken whatever the user selects.
  for (std::size_t i = 1; i < all.size(); ++i) {
    if (!(all[i].timestamp > all[i - 1].timestamp)) {
      std::ostringstream msg;
      msg.precision(17);
      msg << where(all[i]) << ": timestamp " << all[i].timestamp << " s of '" << baseName(all[i].path)
          << "' is not greater than the previous one (" << all[i - 1].timestamp << " s, " << where(all[i - 1]) << ")";
      throw vpHSlamException(vpHSlamException::invalidTimestamps, msg.str());
    }
  }
  if (options.startFrame >= all.size()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "start frame " + std::to_string(options.startFrame) +
                                                                  " is beyond the " + std::to_string(all.size()) +
                                                                  " frames of '" + m_root + "'");
  }
  std::size_t count = all.size() - options.startFrame;
  if (options.maxFrames > 0) {
    count = std::min<std::size_t>(count, options.maxFrames);
  }
  m_frames.assign(all.begin() + static_cast<std::ptrdiff_t>(options.startFrame),
                  all.begin() + static_cast<std::ptrdiff_t>(options.startFrame + count));
  // Fail at open, not half-way through a run, when a listed file is missing.
  for (const IndexedFrame &f : m_frames) {
    if (f.entry.empty() && !pathIsFile(f.path)) {
      throw vpHSlamException(vpHSlamException::fileNotFound,
                             "image '" + f.path + "' (listed at " + where(f) + ") does not exist");
    }
  }
  m_next = 0;

  if (nominalFrameRate > 0.) {
    m_frameRate = nominalFrameRate;
  } else if (all.size() > 1) {
    // Median step: robust to the odd dropped frame of real recordings.
    std::vector<double> steps(all.size() - 1);
    for (std::size_t i = 1; i < all.size(); ++i) {
      steps[i - 1] = all[i].timestamp - all[i - 1].timestamp;
    }
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
    m_frameRate = 1. / steps[steps.size() / 2];
  } else {
    m_frameRate = 0.;
  }
}

bool IndexedImageSource::acquire(vpImage<unsigned char> &I, Frame &frame)
{
  if (m_next >= m_frames.size()) {
    return false;
  }
  const IndexedFrame &f = m_frames[m_next];
  // Consumed before it is read: after a frame that throws, the next acquire() reads the following one (a program
  // may skip unreadable frames), instead of failing on the same file for ever.
  ++m_next;
  if (f.entry.empty()) {
    readGreyImage(f.path, I);
  } else {
    readArchivedImage(f, I);
  }
  if (I.getWidth() != m_camera.getWidth() || I.getHeight() != m_camera.getHeight()) {
    throw vpHSlamException(vpHSlamException::invalidImage,
                           "image '" + f.path + "' is " + std::to_string(I.getWidth()) + "x" +
                               std::to_string(I.getHeight()) + " but the calibration '" + m_cameraFile + "' is " +
                               std::to_string(m_camera.getWidth()) + "x" + std::to_string(m_camera.getHeight()));
  }
  frame.index = static_cast<unsigned int>(m_next - 1);
  frame.timestamp = f.timestamp;
  frame.exposure = f.exposure;
  frame.name = f.path;
  return true;
}

void IndexedImageSource::loadFolderPhotometricCalibration(const std::string &folder)
{
  const std::string pcalib = joinPath(folder, "pcalib.txt");
  const std::string vignette = joinPath(folder, "vignette.png");
  const bool hasResponse = pathIsFile(pcalib), hasVignette = pathIsFile(vignette);
  if (hasResponse || hasVignette) {
    m_photometric.load(hasResponse ? pcalib : std::string(), hasVignette ? vignette : std::string(),
                       m_camera.getWidth(), m_camera.getHeight());
  }
}

void IndexedImageSource::readArchivedImage(const IndexedFrame &frame, vpImage<unsigned char> &)
{
  throw vpHSlamException(vpHSlamException::unsupported,
                         "'" + frame.path + "': this reader does not read images inside archives");
}

std::string IndexedImageSource::describe() const
{
  std::ostringstream s;
  s << formatName(m_format) << " '" << m_root << "': " << m_frames.size() << " frames, " << m_camera.getWidth() << "x"
    << m_camera.getHeight() << ", " << m_frameRate << " Hz";
  return s.str();
}
} // namespace hslam
