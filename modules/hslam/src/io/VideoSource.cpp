/*
 * H-SLAM for ViSP.
 */
#include "io/VideoSource.h"

#include "io/SourceFiles.h"
#include "io/TumRgbdSource.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <sstream>

namespace hslam
{
using namespace io;

VideoSource::VideoSource(const std::string &path, const vpHSlamImageSource::Options &options) : m_path(path)
{
  if (!pathIsFile(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "video file '" + path + "' does not exist");
  }
  if (!(options.frameRate > 0.)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "video '" + path + "' needs a positive frame rate (Options::frameRate, --fps)");
  }
  m_cameraFile = findFolderCameraFile(parentPath(path), options);
  if (m_cameraFile.empty()) {
    throw vpHSlamException(vpHSlamException::fileNotFound,
                           "no camera file for video '" + path +
                               "': give one (Options::cameraFile, --camera) or put camera.txt or camera.xml beside it");
  }
  m_frameRate = options.frameRate;
  m_maxFrames = options.maxFrames;

  try {
    m_reader.setFileName(path);
    if (!m_reader.isVideoFormat()) {
      throw vpHSlamException(vpHSlamException::unsupported, "'" + path + "' is not a video format vpVideoReader reads");
    }
    m_reader.open(m_first);
  } catch (const vpHSlamException &) {
    throw;
  } catch (const vpException &e) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           "cannot open video '" + path + "': " + e.getStringMessage());
  }
  if (m_first.getSize() == 0) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "video '" + path + "' has no decodable frame");
  }
  // open() decoded the first frame for its size and rewound: acquire() delivers it again.
  // The first frame gives the size to calibration formats that do not store it (KITTI calib.txt).
  m_camera = vpHSlamCamera::load(m_cameraFile, m_first.getWidth(), m_first.getHeight());
  const long last = m_reader.getLastFrameIndex();
  const long first = m_reader.getFirstFrameIndex();
  if (last >= first && last > 0) {
    long count = last - first + 1 - static_cast<long>(options.startFrame);
    if (options.maxFrames > 0) {
      count = std::min<long>(count, options.maxFrames);
    }
    m_frameCount = static_cast<int>(std::max<long>(count, 0));
  }
  // Skip to the start frame by decoding: seeking in compressed streams is not frame exact.
  vpImage<unsigned char> skipped;
  for (unsigned int i = 0; i < options.startFrame; ++i) {
    if (!decodeNext(skipped)) {
      throw vpHSlamException(vpHSlamException::invalidArgument, "start frame " + std::to_string(options.startFrame) +
                                                                    " is beyond the end of video '" + path + "'");
    }
  }
}

bool VideoSource::decodeNext(vpImage<unsigned char> &I)
{
  if (m_ended) {
    return false;
  }
  if (m_reader.end()) {
    m_ended = true;
    return false;
  }
  try {
    m_reader.acquire(I);
  } catch (const vpException &e) {
    const std::string message =
        "video '" + m_path + "', frame " + std::to_string(m_fileIndex) + ": " + e.getStringMessage();
    ++m_fileIndex; // consumed: the next frame keeps its own index and timestamp
    throw vpHSlamException(vpHSlamException::fileUnreadable, message);
  }
  if (I.getSize() == 0) {
    m_ended = true;
    return false;
  }
  if (I.getWidth() != m_camera.getWidth() || I.getHeight() != m_camera.getHeight()) {
    throw vpHSlamException(vpHSlamException::invalidImage,
                           "video '" + m_path + "' frame " + std::to_string(m_fileIndex) + " is " +
                               std::to_string(I.getWidth()) + "x" + std::to_string(I.getHeight()) +
                               " but the calibration '" + m_cameraFile + "' is " + std::to_string(m_camera.getWidth()) +
                               "x" + std::to_string(m_camera.getHeight()));
  }
  ++m_fileIndex;
  return true;
}

bool VideoSource::acquire(vpImage<unsigned char> &I, Frame &frame)
{
  if ((m_maxFrames > 0 && m_delivered >= m_maxFrames) || !decodeNext(I)) {
    return false;
  }
  const unsigned int fileIndex = m_fileIndex - 1;
  frame.index = m_delivered;
  frame.timestamp = static_cast<double>(fileIndex) / m_frameRate;
  frame.exposure = -1.;
  frame.name = m_path + "#" + std::to_string(fileIndex);
  ++m_delivered;
  return true;
}

std::string VideoSource::describe() const
{
  std::ostringstream s;
  s << "video '" << m_path << "': " << m_frameCount << " frames, " << m_camera.getWidth() << "x" << m_camera.getHeight()
    << ", " << m_frameRate << " Hz";
  return s.str();
}
} // namespace hslam
