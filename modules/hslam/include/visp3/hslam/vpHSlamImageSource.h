/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamImageSource.h
  \brief Abstract source of timestamped grey images: datasets, videos and live cameras behind one interface.
*/
#ifndef VP_HSLAM_IMAGE_SOURCE_H
#define VP_HSLAM_IMAGE_SOURCE_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamPhotometricCalibration.h>

#include <memory>
#include <string>

/*!
  \class vpHSlamImageSource
  \ingroup group_hslam
  \brief Where frames come from: one interface for every dataset format, image folders, videos and V4L2 cameras.

  What it is for: the same vpHSlam system is fed by all sources, so a program written for a dataset runs on a
  live camera by changing the source only. A source yields 8-bit grey frames (colour files are converted by ViSP's
  readers) strictly in order, each with a timestamp in seconds (strictly increasing) and, where the format has it,
  an exposure time. It also reports the camera calibration (model + rectification target) of the RAW images it
  delivers and the photometric calibration, if any.

  Readers never skip or shift a frame silently: a missing, unreadable or corrupt image, an unparsable line,
  non-increasing timestamps, a list and a folder of different lengths, or an image whose size differs from the
  calibration raise vpHSlamException naming the file (and line). Lists are checked when the source is created
  (missing files included), image contents when acquire() reads them. A list whose last line has no end of line is
  refused as truncated (a line cut inside its last number would still parse). The end of a sequence is not an
  error: acquire() returns false.

  Dataset images are read one by one with vpHSlamImageIo's decoder (JPEG, PNG, PGM, PPM; TUM monoVO's images.zip:
  decompressed with libzip and decoded in memory), never through vpVideoReader, which silently skips unreadable
  frames. Video files are decoded by OpenCV (FFmpeg) in a plug-in, libvisp_hslam_video, loaded when the first video
  is opened.

  Threading: a source is used from one thread at a time.

  \code
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create("/data/MH_01_easy");
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  while (source->acquire(I, frame)) {
    // frame.timestamp (s), frame.exposure (ms, <= 0 if unknown), frame.index
  }
  \endcode
*/
class VISP_EXPORT vpHSlamImageSource
{
public:
  //! Per-frame metadata delivered with each image.
  struct Frame {
    unsigned int index = 0; //!< 0 for the first DELIVERED frame, whatever Options::startFrame, then +1
    double timestamp = 0.;  //!< seconds, strictly increasing within a source
    double exposure = -1.;  //!< exposure time in milliseconds, <= 0 when unknown
    std::string name;       //!< image file path, or another identifier of the frame (for messages)
  };

  //! Dataset and input formats that create() understands.
  enum Format {
    formatAuto,    //!< detect from the folder's content
    formatEuroc,   //!< EuRoC / TUM-VI ASL: mav0/cam0/data.csv + data/ + sensor.yaml (or the cam0 folder)
    formatTumMono, //!< TUM monoVO: images/ or images.zip (read in place, entries sorted by name), times.txt,
                   //!< camera.txt [, pcalib.txt, vignette.png]; images/ wins when both exist
    formatTumRgbd, //!< TUM RGB-D: rgb.txt + camera.txt or camera.xml in the folder, or Options::cameraFile; H-SLAM
                   //!< extension: optional pcalib.txt / vignette.png and times.txt (id time exposure_ms per frame)
    formatKitti,   //!< KITTI odometry: image_0/, times.txt, calib.txt (P0); size from the first image
    formatImages,  //!< image folder (sorted by name) or printf pattern; camera file and frame rate required
    formatVideo,   //!< video file (OpenCV/FFmpeg plug-in), with a camera file and a frame rate
    formatV4l2     //!< live camera through vpV4l2Grabber ("/dev/videoN")
  };

  //! Options for create(); every field has a usable default.
  struct Options {
    Format format = formatAuto; //!< explicit format, or detect
    std::string cameraFile;     //!< camera file overriding the one found in the folder (any vpHSlamCamera::load format)
    double frameRate = 30.;     //!< Hz, for formats without timestamps (images, video): frame i is at i / frameRate s
    unsigned int startFrame = 0; //!< first frame to deliver (0-based in the sequence; timestamps are unchanged)
    unsigned int maxFrames = 0;  //!< stop after this many frames (0 = all)
    //! Requested live image width, pixels (V4L2). 0 with height 0: not chosen, i.e. the size of cameraFile when
    //! given, else 640x480. Ignored by the other formats (their images have the size they have).
    unsigned int width = 0;
    unsigned int height = 0; //!< requested live image height, pixels (V4L2); 0 with width 0: see width
  };

  virtual ~vpHSlamImageSource();

  /*!
    Open the source at \e path (a folder, a file, a printf pattern such as "img/%06d.png" or "/dev/video0").
    The format is Options::format, or detectFormat()'s answer when that is formatAuto.
    \exception vpHSlamException naming the path when it cannot be opened (fileNotFound, parseError, ...), its
    format is not recognised (unsupported), or Options::startFrame is past the end (invalidArgument).
  */
  static std::unique_ptr<vpHSlamImageSource> create(const std::string &path, const Options &options);
  //! create() with default Options (an overload: a default argument of a nested type with member initializers
  //! cannot be formed inside the enclosing class).
  static std::unique_ptr<vpHSlamImageSource> create(const std::string &path);
  /*!
    Format detected for \e path (formatAuto when nothing matches); does not open images. In order: "/dev/video*"
    is V4L2; a path with one %d-style conversion is an image pattern; a file with a video extension is a video; a
    folder with mav0/cam0/data.csv (or cam0/data.csv, or data.csv + data/) is EuRoC; times.txt + image_0/ is
    KITTI; times.txt + images/ or images.zip is TUM monoVO; rgb.txt is TUM RGB-D; any image file makes an image
    folder.
  */
  static Format detectFormat(const std::string &path);
  //! Name of a format as accepted on command lines: "auto", "euroc", "tum-mono", "tum-rgbd", "kitti", "images",
  //! "video", "v4l2".
  static std::string formatName(Format format);
  //! Parse formatName()'s output. \exception vpHSlamException::invalidArgument on an unknown name.
  static Format parseFormat(const std::string &name);

  /*!
    Next frame. \return false at the end of the sequence (no exception); true with I and frame filled otherwise.
    \exception vpHSlamException on a corrupt or unreadable frame, or inconsistent metadata. The frame that threw is
    consumed: the next call delivers the following frame (so a program may skip unreadable frames, see
    tutorial-hslam-dataset --skip-unreadable).
  */
  virtual bool acquire(vpImage<unsigned char> &I, Frame &frame) = 0;

  //! Geometric calibration of the delivered (raw) images.
  virtual const vpHSlamCamera &getCamera() const = 0;
  //! Photometric calibration (empty when the format or folder has none).
  virtual const vpHSlamPhotometricCalibration &getPhotometricCalibration() const = 0;
  //! Number of frames that acquire() will deliver, or -1 when unknown (live, video without count).
  virtual int getFrameCount() const = 0;
  //! Nominal frame rate in Hz (from timestamps or options), 0 when unknown.
  virtual double getFrameRate() const = 0;
  //! Format of this source.
  virtual Format getFormat() const = 0;
  //! Human-readable description (format, path, frames, size).
  virtual std::string describe() const = 0;
};

#endif
