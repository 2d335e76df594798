/*
 * H-SLAM for ViSP.
 */
//! \file V4l2Source.h  Live camera source through ViSP's vpV4l2Grabber.
#ifndef HSLAM_IO_V4L2_SOURCE_H
#define HSLAM_IO_V4L2_SOURCE_H

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamImageSource.h>

#include <memory>
#include <string>

namespace hslam
{
/*!
  Open a live V4L2 camera (e.g. "/dev/video0") as a vpHSlamImageSource. vpHSlamImageSource::create() calls this
  for formatV4l2; tests call it directly.

  - Size: Options::width x Options::height when given (both non-zero); when both are 0 (the default), the camera
    file's size if Options::cameraFile is given, else 640x480. Only one of them 0 is invalidArgument. The device is
  probed before streaming; if it imposes another size (V4L2 drivers adjust a request silently, and vpV4l2Grabber would
  then copy a wrongly strided image or read past the driver's buffer), vpHSlamException::deviceError names the device,
  the requested and the delivered size.
  - Pixel format: the first one the device lists among YUYV (luma copied exactly), GREY (exact), BGR24, RGB24,
    RGB32 (converted to grey by ViSP, rounding of +-1 grey level). Emulated formats of libv4l2 count (an MJPEG-only
    camera is read as RGB24/BGR24).
  - Timestamps: the driver's buffer timestamp (vpV4l2Grabber::acquire(I, timeval&)) in seconds. Drivers usually
    stamp with CLOCK_MONOTONIC (time since boot), so only differences are meaningful. A timestamp that is not
    strictly greater than the previous one is an ERROR (vpHSlamException::invalidTimestamps naming the device, the
    frame and both times), never shifted by an epsilon: the interface promises strictly increasing times that are
    true, and a repeated stamp means a repeated buffer or a broken clock, which the caller must see.
  - Options::startFrame frames are grabbed and dropped at the first acquire() (lets auto-exposure settle);
    Options::maxFrames > 0 ends the sequence (acquire() returns false) after that many frames, otherwise a live
    source never ends and getFrameCount() is -1.
  - Camera: Options::cameraFile when given (vpHSlamCamera::load; its size must equal the requested size), else a
    GUESSED pinhole camera, fx = fy = width (about 53 degrees of horizontal field of view, a common webcam order of
    magnitude) and the principal point at the image centre; describe() says so.
  - Errors (missing path, not a character device, not a V4L2 capture device, no usable pixel format, size
    mismatch, a grabber failure) are vpHSlamException::deviceError with the device path; vpFrameGrabberException
    from ViSP is converted. Nothing is printed by this code; ViSP itself prints on some failures the probe does
    not catch first.

  Threading: one thread at a time, like every source. The source owns the grabber and its mapped buffers.
  \exception vpHSlamException as above; vpHSlamException::unsupported when ViSP was built without V4L2.
*/
VISP_EXPORT std::unique_ptr<vpHSlamImageSource> createV4l2Source(const std::string &device,
                                                                 const vpHSlamImageSource::Options &options);
} // namespace hslam

#endif
