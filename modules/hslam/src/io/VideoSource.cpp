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

  // OpenCV's reader (in the plug-in), not vpVideoReader: ViSP 3.5's reader keeps returning the last decoded image
  // when a container does not store its frame count (e.g. an MPEG-1 stream), which would feed the same frame
  // forever.
  m_decoder = io::openVideoDecoder(path);
  if (!readFrame(m_first)) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "video '" + path + "' has no decodable frame");
  }
  m_firstPending = true; // read for its size: acquire() delivers it first
  // The first frame gives the size to calibration formats that do not store it (KITTI calib.txt).
  m_camera = vpHSlamCamera::load(m_cameraFile, m_first.getWidth(), m_first.getHeight());
  // The container's frame count is a hint only (some formats estimate it); -1 when it has none.
  const double stored = m_decoder->storedFrameCount();
  if (stored >= 2. && stored < 1e9) { // MPEG-1 streams report 1
    long count = static_cast<long>(stored) - static_cast<long>(options.startFrame);
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

bool VideoSource::readFrame(vpImage<unsigned char> &I)
{
  std::string error;
  switch (m_decoder->read(I, error)) {
  case io::VideoDecoder::Status::frame:
    return true;
  case io::VideoDecoder::Status::end:
    return false;
  case io::VideoDecoder::Status::error:
    break;
  }
  throw vpHSlamException(vpHSlamException::fileUnreadable, error);
}

bool VideoSource::decodeNext(vpImage<unsigned char> &I)
{
  if (m_ended) {
    return false;
  }
  if (m_firstPending) {
    m_firstPending = false;
    I = m_first;
  } else {
    bool decoded = false;
    try {
      decoded = readFrame(I);
    } catch (const vpHSlamException &e) {
      const std::string message =
          "video '" + m_path + "', frame " + std::to_string(m_fileIndex) + ": " + e.getStringMessage();
      ++m_fileIndex; // consumed: the next frame keeps its own index and timestamp
      throw vpHSlamException(vpHSlamException::fileUnreadable, message);
    }
    if (!decoded) {
      m_ended = true;
      return false;
    }
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
