/*
 * H-SLAM for ViSP.
 */
//! \file IndexedImageSource.h  Common base of every reader whose frames are a known list of image files.
#ifndef HSLAM_IO_INDEXED_IMAGE_SOURCE_H
#define HSLAM_IO_INDEXED_IMAGE_SOURCE_H

#include <visp3/hslam/vpHSlamImageSource.h>

#include <cstddef>
#include <string>
#include <vector>

namespace hslam
{
//! One frame of an indexed sequence, with where it was listed (for messages).
struct IndexedFrame {
  std::string path;      //!< image file, or "<archive>:<entry>" for an image inside an archive (for messages)
  std::string entry;     //!< entry name inside the reader's archive, empty for a file on disk
  double timestamp = 0.; //!< seconds
  double exposure = -1.; //!< milliseconds, <= 0 when unknown
  std::string listFile;  //!< file that listed the frame (rgb.txt, data.csv, times.txt), empty when none
  std::size_t line = 0;  //!< 1-based line in listFile, 0 when none
};

/*!
  Base of the dataset readers (EuRoC, TUM monoVO, TUM RGB-D, KITTI, image folders and patterns).

  A derived reader parses its lists, loads m_camera (and m_photometric) and hands the full frame list to
  setFrames(), which checks it once (timestamps strictly increasing, every selected file present), applies
  Options::startFrame / maxFrames and fixes the frame rate. acquire() then reads each file with io::readGreyImage() (or,
  for frames inside an archive, through readArchivedImage()): a frame is never skipped (unlike vpVideoReader), an
  unreadable file or a size different from the calibration throws.
*/
class IndexedImageSource : public vpHSlamImageSource
{
public:
  bool acquire(vpImage<unsigned char> &I, Frame &frame) override;
  const vpHSlamCamera &getCamera() const override { return m_camera; }
  const vpHSlamPhotometricCalibration &getPhotometricCalibration() const override { return m_photometric; }
  int getFrameCount() const override { return static_cast<int>(m_frames.size()); }
  double getFrameRate() const override { return m_frameRate; }
  Format getFormat() const override { return m_format; }
  std::string describe() const override;

protected:
  IndexedImageSource(Format format, const std::string &root);

  /*!
    Validate and select the frames.
    \param all : every frame of the sequence, in order.
    \param options : startFrame, maxFrames.
    \param nominalFrameRate : Hz, used when the list has no real timestamps (> 0), else 0 to derive it from the
    median timestamp step.
  */
  void setFrames(std::vector<IndexedFrame> all, const vpHSlamImageSource::Options &options,
                 double nominalFrameRate = 0.);

  /*!
    Camera from Options::cameraFile when given (vpHSlamCamera::load, any format; \e width and \e height serve the
    formats that do not store the image size), else from \e defaultFile through \e loader.
  */
  template <typename Loader>
  void loadCamera(const vpHSlamImageSource::Options &options, const std::string &defaultFile, Loader loader,
                  unsigned int width = 0, unsigned int height = 0)
  {
    m_cameraFile = options.cameraFile.empty() ? defaultFile : options.cameraFile;
    m_camera =
        options.cameraFile.empty() ? loader(defaultFile) : vpHSlamCamera::load(options.cameraFile, width, height);
  }

  /*!
    Load the photometric calibration of \e folder into m_photometric when it holds pcalib.txt and/or vignette.png
    (TUM monoVO names), sized for m_camera: load the camera first. Nothing happens when neither file exists.
  */
  void loadFolderPhotometricCalibration(const std::string &folder);

  /*!
    Read a frame whose IndexedFrame::entry is set (an image inside an archive). Readers that list such frames
    override it; the default throws vpHSlamException::unsupported.
  */
  virtual void readArchivedImage(const IndexedFrame &frame, vpImage<unsigned char> &I);

  Format m_format;
  std::string m_root;       //!< path given by the user
  std::string m_cameraFile; //!< where m_camera came from (for messages)
  vpHSlamCamera m_camera;
  vpHSlamPhotometricCalibration m_photometric;

private:
  std::vector<IndexedFrame> m_frames; //!< selected frames only
  std::size_t m_next = 0;
  double m_frameRate = 0.;
};
} // namespace hslam

#endif
