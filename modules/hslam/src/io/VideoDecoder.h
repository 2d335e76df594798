/*
 * H-SLAM for ViSP.
 */
//! \file VideoDecoder.h  Video files decoded by a plug-in loaded on first use (libvisp_hslam_video).
#ifndef HSLAM_IO_VIDEO_DECODER_H
#define HSLAM_IO_VIDEO_DECODER_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <memory>
#include <string>

namespace hslam
{
namespace io
{
/*!
  The frames of one video file, decoded to 8-bit grey.

  Implemented by the plug-in libvisp_hslam_video (modules/hslam/plugins/video/, OpenCV's videoio with FFmpeg),
  which the module loads with dlopen() the first time a video file is opened, not at program start: OpenCV's video
  and image I/O pull in about 200 shared libraries (FFmpeg, GStreamer, GDAL, ...) whose loading costs every program
  ~0.2 s of CPU and ~60 MB, while most runs read image files or a V4L2 camera. The interface crosses the library
  boundary without exceptions (errors come back as Status::error with a message).
*/
class VideoDecoder
{
public:
  //! What read() produced.
  enum class Status { frame, end, error };

  virtual ~VideoDecoder() = default;
  //! Next frame into \e I; Status::end at the end of the stream, Status::error with \e error set when it fails.
  virtual Status read(vpImage<unsigned char> &I, std::string &error) = 0;
  //! The frame count the container stores (a hint: some formats estimate it), negative or 0 when it has none.
  virtual double storedFrameCount() const = 0;
};

//! Name of the plug-in's factory: VideoDecoder *(const char *path, std::string *error), null on failure.
constexpr const char *kVideoPluginFactory = "hslamOpenVideoDecoder";
//! File name of the plug-in, looked for beside libvisp_hslam, then on the loader's path.
constexpr const char *kVideoPluginFile = "libvisp_hslam_video.so";

/*!
  Open a video file through the plug-in, loading it on first use (the environment variable HSLAM_VIDEO_PLUGIN may
  name the plug-in file explicitly).
  \exception vpHSlamException::unsupported when the plug-in cannot be loaded (the message says where it was looked
  for), fileUnreadable when the file cannot be opened as a video.
*/
VISP_EXPORT std::unique_ptr<VideoDecoder> openVideoDecoder(const std::string &path);
} // namespace io
} // namespace hslam

#endif
