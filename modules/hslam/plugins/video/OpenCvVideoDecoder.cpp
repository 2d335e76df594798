/*
 * H-SLAM for ViSP.
 */
// The video plug-in (libvisp_hslam_video): io::VideoDecoder on OpenCV's VideoCapture with FFmpeg. Loaded by
// io::openVideoDecoder() on first use, so that only programs that open a video file load OpenCV's video I/O and
// its dependencies (src/io/VideoDecoder.h says why).
#include "io/VideoDecoder.h"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cstring>

namespace
{
class OpenCvVideoDecoder final : public hslam::io::VideoDecoder
{
public:
  bool open(const char *path, std::string &error)
  {
    try {
      // FFmpeg only: OpenCV's other backends (GStreamer, image sequences) print to stderr on files they cannot
      // play, and library code stays silent.
      m_capture.open(path, cv::CAP_FFMPEG);
    } catch (const cv::Exception &e) {
      error = e.what();
      return false;
    }
    if (!m_capture.isOpened()) {
      error = "not a video this build of OpenCV can decode";
      return false;
    }
    return true;
  }

  Status read(vpImage<unsigned char> &I, std::string &error) override
  {
    try {
      cv::Mat frame;
      if (!m_capture.read(frame) || frame.empty()) {
        return Status::end;
      }
      cv::Mat grey = frame;
      if (frame.channels() != 1) {
        cv::cvtColor(frame, grey, frame.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
      }
      if (grey.depth() != CV_8U) {
        error = "the video's frames are not 8-bit";
        return Status::error;
      }
      I.resize(static_cast<unsigned int>(grey.rows), static_cast<unsigned int>(grey.cols));
      for (int y = 0; y < grey.rows; ++y) {
        std::memcpy(I[static_cast<unsigned int>(y)], grey.ptr<unsigned char>(y), static_cast<size_t>(grey.cols));
      }
      return Status::frame;
    } catch (const cv::Exception &e) {
      error = e.what();
      return Status::error;
    }
  }

  double storedFrameCount() const override { return m_capture.get(cv::CAP_PROP_FRAME_COUNT); }

private:
  cv::VideoCapture m_capture;
};
} // namespace

//! The plug-in's factory (io::kVideoPluginFactory): a decoder for \e path, or null with \e error set.
extern "C" __attribute__((visibility("default"))) hslam::io::VideoDecoder *hslamOpenVideoDecoder(const char *path,
                                                                                                 std::string *error)
{
  try {
    auto *decoder = new OpenCvVideoDecoder();
    if (!decoder->open(path, *error)) {
      delete decoder;
      return nullptr;
    }
    return decoder;
  } catch (const std::exception &e) {
    *error = e.what();
    return nullptr;
  }
}
