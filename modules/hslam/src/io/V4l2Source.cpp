/*
 * H-SLAM for ViSP.
 */
#include "io/V4l2Source.h"

#include <visp3/hslam/vpHSlamException.h>

#ifdef VISP_HAVE_V4L2
#include <visp3/sensor/vpV4l2Grabber.h>

#include <fcntl.h>
#include <libv4l2.h>
#include <linux/videodev2.h>
#include <sys/stat.h>
#include <sys/time.h>

#include <cerrno>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <vector>
#endif

namespace hslam
{
#ifdef VISP_HAVE_V4L2
namespace
{
//! A pixel format vpV4l2Grabber can convert to grey, with its V4L2 code.
struct PixelFormat {
  __u32 fourcc;
  vpV4l2Grabber::vpV4l2PixelFormatType grabberType;
  const char *name;
};

//! Preference order: exact luma first (YUYV, GREY), then colour formats ViSP converts to grey with rounding.
const PixelFormat kPreferredFormats[] = {{V4L2_PIX_FMT_YUYV, vpV4l2Grabber::V4L2_YUYV_FORMAT, "YUYV"},
                                         {V4L2_PIX_FMT_GREY, vpV4l2Grabber::V4L2_GREY_FORMAT, "GREY"},
                                         {V4L2_PIX_FMT_BGR24, vpV4l2Grabber::V4L2_BGR24_FORMAT, "BGR24"},
                                         {V4L2_PIX_FMT_RGB24, vpV4l2Grabber::V4L2_RGB24_FORMAT, "RGB24"},
                                         {V4L2_PIX_FMT_RGB32, vpV4l2Grabber::V4L2_RGB32_FORMAT, "RGB32"}};

const __u32 kMaxEnumeratedFormats = 64;  //!< bound on VIDIOC_ENUM_FMT, far above what a camera lists
const unsigned int kGrabberBuffers = 3;  //!< ViSP's advice for real-time capture (vpV4l2Grabber::setNBuffers)
const unsigned int kCameraInput = 0;     //!< webcams have a single input; ViSP's default (2) is for TV boards
const double kMicrosecond = 1e-6;        //!< struct timeval unit, seconds
const unsigned int kDefaultWidth = 640;  //!< requested without a chosen size or a camera file: VGA, which
const unsigned int kDefaultHeight = 480; //!< virtually every webcam offers

std::string sizeText(unsigned int width, unsigned int height)
{
  return std::to_string(width) + "x" + std::to_string(height);
}

std::string fourccText(__u32 fourcc)
{
  std::string text;
  for (int shift = 0; shift < 32; shift += 8) {
    const char c = static_cast<char>((fourcc >> shift) & 0xff);
    text += (c >= ' ' && c <= '~') ? c : '?';
  }
  return text;
}

[[noreturn]] void deviceError(const std::string &device, const std::string &problem)
{
  throw vpHSlamException(vpHSlamException::deviceError, "V4L2 device '" + device + "': " + problem);
}

//! Closes a descriptor opened with v4l2_open.
class ScopedV4l2Descriptor
{
public:
  explicit ScopedV4l2Descriptor(int fd) : m_fd(fd) {}
  ~ScopedV4l2Descriptor()
  {
    if (m_fd >= 0) {
      v4l2_close(m_fd);
    }
  }
  ScopedV4l2Descriptor(const ScopedV4l2Descriptor &) = delete;
  ScopedV4l2Descriptor &operator=(const ScopedV4l2Descriptor &) = delete;
  int get() const { return m_fd; }

private:
  int m_fd;
};

//! What the device will deliver, learnt before vpV4l2Grabber streams.
struct DeviceProbe {
  PixelFormat format{};
  double nominalFrameRate = 0.; //!< Hz, 0 when the driver does not report it
  std::string card;             //!< product name reported by the driver
  std::string driver;
};

/*!
  Check the device the way vpV4l2Grabber will use it, but with errors that name the problem: vpV4l2Grabber prints
  and throws vague messages, falls back to other pixel formats silently, and never checks the size the driver
  imposed (it then converts width x height of the requested size from a buffer of another size).
*/
DeviceProbe probeDevice(const std::string &device, unsigned int width, unsigned int height)
{
  struct stat status;
  if (::stat(device.c_str(), &status) != 0) {
    deviceError(device, std::string("no such device (") + std::strerror(errno) + ")");
  }
  if (!S_ISCHR(status.st_mode)) {
    deviceError(device, "not a character device, hence not a camera");
  }
  ScopedV4l2Descriptor fd(v4l2_open(device.c_str(), O_RDWR));
  if (fd.get() < 0) {
    // libv4l2 refuses (and prints about) a node that does not answer VIDIOC_QUERYCAP.
    deviceError(device, std::string(errno == ENOTTY ? "not a V4L2 device" : "cannot be opened") + " (" +
                            std::strerror(errno) + ")");
  }

  v4l2_capability capability;
  std::memset(&capability, 0, sizeof(capability));
  if (v4l2_ioctl(fd.get(), VIDIOC_QUERYCAP, &capability) != 0) {
    deviceError(device, std::string("not a V4L2 device (VIDIOC_QUERYCAP: ") + std::strerror(errno) + ")");
  }
  const __u32 caps =
      (capability.capabilities & V4L2_CAP_DEVICE_CAPS) ? capability.device_caps : capability.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING)) {
    deviceError(device, "not a streaming video capture device (a metadata node or an output?)");
  }
  DeviceProbe probe;
  probe.card = reinterpret_cast<const char *>(capability.card);
  probe.driver = reinterpret_cast<const char *>(capability.driver);

  std::vector<__u32> offered;
  for (__u32 index = 0; index < kMaxEnumeratedFormats; ++index) {
    v4l2_fmtdesc description;
    std::memset(&description, 0, sizeof(description));
    description.index = index;
    description.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (v4l2_ioctl(fd.get(), VIDIOC_ENUM_FMT, &description) != 0) {
      break;
    }
    offered.push_back(description.pixelformat);
  }
  bool found = false;
  for (const PixelFormat &candidate : kPreferredFormats) {
    for (__u32 fourcc : offered) {
      found = found || (fourcc == candidate.fourcc);
    }
    if (found) {
      probe.format = candidate;
      break;
    }
  }
  if (!found) {
    std::string list;
    for (__u32 fourcc : offered) {
      list += (list.empty() ? "" : ", ") + fourccText(fourcc);
    }
    deviceError(device, "offers none of the pixel formats ViSP converts to grey (YUYV, GREY, BGR24, RGB24, RGB32); "
                        "it offers: " +
                            (list.empty() ? std::string("nothing") : list));
  }

  // S_FMT like the grabber: drivers adjust the size to one they support instead of failing.
  v4l2_format format;
  std::memset(&format, 0, sizeof(format));
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  format.fmt.pix.width = width;
  format.fmt.pix.height = height;
  format.fmt.pix.pixelformat = probe.format.fourcc;
  format.fmt.pix.field = V4L2_FIELD_ANY;
  if (v4l2_ioctl(fd.get(), VIDIOC_S_FMT, &format) != 0) {
    deviceError(device, std::string("VIDIOC_S_FMT ") + probe.format.name + " " + sizeText(width, height) + " failed (" +
                            std::strerror(errno) + ")");
  }
  if (format.fmt.pix.pixelformat != probe.format.fourcc) {
    deviceError(device, std::string("asked for pixel format ") + probe.format.name + ", the driver chose " +
                            fourccText(format.fmt.pix.pixelformat));
  }
  if (format.fmt.pix.width != width || format.fmt.pix.height != height) {
    deviceError(device, "requested size " + sizeText(width, height) + " but the device delivers " +
                            sizeText(format.fmt.pix.width, format.fmt.pix.height) + " in " + probe.format.name +
                            "; request a size the camera supports (v4l2-ctl "
                            "--list-formats-ext)");
  }

  v4l2_streamparm parameters;
  std::memset(&parameters, 0, sizeof(parameters));
  parameters.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (v4l2_ioctl(fd.get(), VIDIOC_G_PARM, &parameters) == 0 &&
      (parameters.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) &&
      parameters.parm.capture.timeperframe.numerator > 0) {
    const v4l2_fract &period = parameters.parm.capture.timeperframe; // seconds per frame
    probe.nominalFrameRate = static_cast<double>(period.denominator) / period.numerator;
  }
  return probe;
}

class V4l2Source : public vpHSlamImageSource
{
public:
  V4l2Source(const std::string &device, const Options &options) : m_device(device), m_options(options)
  {
    if ((options.width == 0) != (options.height == 0)) {
      throw vpHSlamException(vpHSlamException::invalidArgument,
                             "V4L2 device '" + device + "': requested size " + sizeText(options.width, options.height) +
                                 " gives one dimension only; give both, or neither (the camera file's size, else " +
                                 sizeText(kDefaultWidth, kDefaultHeight) + ")");
    }
    loadCamera(); // before touching the device: a bad file fails fast; also fixes the size when none was chosen
    m_probe = probeDevice(device, m_options.width, m_options.height);
    openGrabber();
  }

  ~V4l2Source() override { releaseGrabber(); }

  bool acquire(vpImage<unsigned char> &I, Frame &frame) override
  {
    if (m_options.maxFrames > 0 && m_delivered >= m_options.maxFrames) {
      return false;
    }
    while (m_grabbed < m_options.startFrame) {
      grab(I);
    }
    frame.timestamp = grab(I);
    frame.index = m_delivered;
    frame.exposure = -1.; // vpV4l2Grabber gives no exposure time
    frame.name = m_device + " #" + std::to_string(m_grabbed - 1);
    if (m_delivered == 0) {
      m_firstTimestamp = frame.timestamp;
    }
    ++m_delivered;
    return true;
  }

  const vpHSlamCamera &getCamera() const override { return m_camera; }
  const vpHSlamPhotometricCalibration &getPhotometricCalibration() const override { return m_photometric; }
  int getFrameCount() const override { return m_options.maxFrames > 0 ? static_cast<int>(m_options.maxFrames) : -1; }

  double getFrameRate() const override
  {
    if (m_probe.nominalFrameRate > 0.) {
      return m_probe.nominalFrameRate;
    }
    // No nominal rate from the driver: the mean rate of the frames delivered so far.
    return (m_delivered >= 2 && m_lastTimestamp > m_firstTimestamp)
               ? (m_delivered - 1) / (m_lastTimestamp - m_firstTimestamp)
               : 0.;
  }

  Format getFormat() const override { return formatV4l2; }

  std::string describe() const override
  {
    std::ostringstream text;
    text << "v4l2 " << m_device << " (" << m_probe.card << ", driver " << m_probe.driver
         << "): " << sizeText(m_options.width, m_options.height) << " " << m_probe.format.name << ", ";
    if (m_probe.nominalFrameRate > 0.) {
      text << std::setprecision(4) << m_probe.nominalFrameRate << " Hz nominal, ";
    } else {
      text << "frame rate unknown, ";
    }
    text << "live, " << (m_options.maxFrames > 0 ? std::to_string(m_options.maxFrames) + " frames" : "unbounded");
    if (m_options.startFrame > 0) {
      text << " after dropping " << m_options.startFrame;
    }
    text << "; camera: " << m_camera.toString();
    if (m_cameraGuessed) {
      text << " GUESSED (no camera file: pinhole, fx = fy = width, centred principal point); calibrate the camera "
              "and pass a camera file for real use";
    } else {
      text << " from " << m_options.cameraFile;
    }
    return text.str();
  }

private:
  //! Camera, and the size to request when the caller chose none (Options::width = height = 0).
  void loadCamera()
  {
    const bool sizeChosen = m_options.width > 0;
    if (m_options.cameraFile.empty()) {
      if (!sizeChosen) {
        m_options.width = kDefaultWidth;
        m_options.height = kDefaultHeight;
      }
      const unsigned int width = m_options.width, height = m_options.height;
      const double focal = width; // see createV4l2Source(): fx = fy = width is the documented guess
      m_camera =
          vpHSlamCamera(vpHSlamCamera::pinhole, width, height, focal, focal, 0.5 * (width - 1.), 0.5 * (height - 1.));
      m_cameraGuessed = true;
      return;
    }
    // A chosen size serves the calibration formats that do not store one (KITTI calib.txt).
    m_camera = vpHSlamCamera::load(m_options.cameraFile, m_options.width, m_options.height);
    if (!sizeChosen) {
      m_options.width = m_camera.getWidth();
      m_options.height = m_camera.getHeight();
    }
    const unsigned int width = m_options.width, height = m_options.height;
    if (m_camera.getWidth() != width || m_camera.getHeight() != height) {
      throw vpHSlamException(vpHSlamException::invalidCalibration,
                             "camera file '" + m_options.cameraFile + "' is for " +
                                 sizeText(m_camera.getWidth(), m_camera.getHeight()) + " images but V4L2 device '" +
                                 m_device + "' is opened at " + sizeText(width, height));
    }
  }

  /*!
    vpV4l2Grabber::close() throws when STREAMOFF or munmap fails (unplugged camera) and the grabber's destructor
    calls it again: close here, and on failure leak the grabber rather than let a destructor throw (terminate).
  */
  void releaseGrabber() noexcept
  {
    if (!m_grabber) {
      return;
    }
    try {
      m_grabber->close();
      m_grabber.reset();
    } catch (...) {
      static_cast<void>(m_grabber.release());
    }
  }

  void openGrabber()
  {
    m_grabber.reset(new vpV4l2Grabber());
    m_grabber->setDevice(m_device);
    m_grabber->setInput(kCameraInput);
    m_grabber->setWidth(m_options.width);
    m_grabber->setHeight(m_options.height);
    m_grabber->setPixelFormat(m_probe.format.grabberType);
    // 25 fps selects whole (interlaced) images; 50 fps would select single fields and cap the height to 288.
    m_grabber->setFramerate(vpV4l2Grabber::framerate_25fps);
    m_grabber->setNBuffers(kGrabberBuffers);
    try {
      m_grabber->open(m_image);
    } catch (const vpException &e) {
      releaseGrabber();
      deviceError(m_device, "vpV4l2Grabber::open failed: " + e.getStringMessage());
    }
    // On failure of the requested format, the grabber silently tries the others and may end with another one,
    // or with none streaming.
    if (m_grabber->getPixelFormat() != m_probe.format.grabberType) {
      releaseGrabber();
      deviceError(m_device, std::string("vpV4l2Grabber could not stream ") + m_probe.format.name);
    }
  }

  //! Grab one frame into I; returns its timestamp in seconds after checking it increases.
  double grab(vpImage<unsigned char> &I)
  {
    struct timeval stamp;
    stamp.tv_sec = 0;
    stamp.tv_usec = 0;
    try {
      m_grabber->acquire(I, stamp);
    } catch (const vpException &e) {
      deviceError(m_device, "frame " + std::to_string(m_grabbed) + ": " + e.getStringMessage());
    }
    if (I.getWidth() != m_options.width || I.getHeight() != m_options.height) {
      deviceError(m_device, "frame " + std::to_string(m_grabbed) + " is " + sizeText(I.getWidth(), I.getHeight()) +
                                ", requested " + sizeText(m_options.width, m_options.height));
    }
    const double timestamp = static_cast<double>(stamp.tv_sec) + kMicrosecond * static_cast<double>(stamp.tv_usec);
    if (m_grabbed > 0 && !(timestamp > m_lastTimestamp)) {
      std::ostringstream message;
      message << std::fixed << std::setprecision(6) << "V4L2 device '" << m_device << "': frame " << m_grabbed
              << " has timestamp " << timestamp << " s, not after the previous frame's " << m_lastTimestamp
              << " s (driver timestamps must increase strictly)";
      throw vpHSlamException(vpHSlamException::invalidTimestamps, message.str());
    }
    m_lastTimestamp = timestamp;
    ++m_grabbed;
    return timestamp;
  }

  std::string m_device;
  Options m_options; //!< as given, with the size resolved by loadCamera() (never 0 after construction)
  vpHSlamCamera m_camera;
  bool m_cameraGuessed = false;
  vpHSlamPhotometricCalibration m_photometric; //!< always empty: a live camera has no photometric calibration
  DeviceProbe m_probe;
  std::unique_ptr<vpV4l2Grabber> m_grabber;
  vpImage<unsigned char> m_image; //!< sized by vpV4l2Grabber::open
  unsigned int m_grabbed = 0;     //!< frames taken from the driver, dropped ones included
  unsigned int m_delivered = 0;   //!< frames returned by acquire()
  double m_firstTimestamp = 0.;   //!< seconds, first delivered frame
  double m_lastTimestamp = 0.;    //!< seconds, last grabbed frame
};
} // namespace

std::unique_ptr<vpHSlamImageSource> createV4l2Source(const std::string &device,
                                                     const vpHSlamImageSource::Options &options)
{
  return std::unique_ptr<vpHSlamImageSource>(new V4l2Source(device, options));
}

#else // ViSP built without V4L2

std::unique_ptr<vpHSlamImageSource> createV4l2Source(const std::string &device, const vpHSlamImageSource::Options &)
{
  throw vpHSlamException(vpHSlamException::unsupported,
                         "V4L2 device '" + device + "': this ViSP was built without V4L2 (VISP_HAVE_V4L2)");
}
#endif
} // namespace hslam
