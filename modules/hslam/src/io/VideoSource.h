/*
 * H-SLAM for ViSP.
 */
//! \file VideoSource.h  Video files, decoded by the video plug-in (io/VideoDecoder.h).
#ifndef HSLAM_IO_VIDEO_SOURCE_H
#define HSLAM_IO_VIDEO_SOURCE_H

#include <visp3/hslam/vpHSlamImageSource.h>

#include "io/VideoDecoder.h"

#include <memory>

#include <string>

namespace hslam
{
/*!
  A video file (avi, mp4, ...) decoded by the video plug-in (OpenCV, FFmpeg; io/VideoDecoder.h). Frame i of the file is
  at i / frameRate seconds, Options::frameRate in Hz. A camera file is required: Options::cameraFile, else camera.txt,
  camera.xml or camera.yaml beside the video. A frame of another size than the calibration throws; the end of the stream
  (or a frame the decoder cannot produce) ends the sequence.
*/
class VideoSource : public vpHSlamImageSource
{
public:
  VideoSource(const std::string &path, const vpHSlamImageSource::Options &options);

  bool acquire(vpImage<unsigned char> &I, Frame &frame) override;
  const vpHSlamCamera &getCamera() const override { return m_camera; }
  const vpHSlamPhotometricCalibration &getPhotometricCalibration() const override { return m_photometric; }
  int getFrameCount() const override { return m_frameCount; }
  double getFrameRate() const override { return m_frameRate; }
  Format getFormat() const override { return formatVideo; }
  std::string describe() const override;

private:
  //! Next decoded frame of the file, size-checked; false at the end of the stream.
  bool decodeNext(vpImage<unsigned char> &I);
  //! Next frame of the stream in grey; false at its end.
  bool readFrame(vpImage<unsigned char> &I);

  std::string m_path, m_cameraFile;
  std::unique_ptr<io::VideoDecoder> m_decoder;
  vpHSlamCamera m_camera;
  vpHSlamPhotometricCalibration m_photometric;
  vpImage<unsigned char> m_first; //!< first frame, read for the size and delivered first
  bool m_firstPending = false;
  bool m_ended = false;
  int m_frameCount = -1;
  unsigned int m_maxFrames = 0;
  unsigned int m_delivered = 0;
  unsigned int m_fileIndex = 0; //!< index in the file of the next frame
  double m_frameRate = 0.;
};
} // namespace hslam

#endif
