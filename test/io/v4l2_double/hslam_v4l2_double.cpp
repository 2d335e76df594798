/*
 * H-SLAM for ViSP.
 */
// A fake V4L2 capture device for tests without a camera.
//
// It defines the libv4l2 entry points that ViSP's vpV4l2Grabber imports (v4l2_open, v4l2_close, v4l2_ioctl,
// v4l2_mmap, v4l2_munmap; `nm -D --undefined-only libvisp_sensor.so.3.5`) and stat()/stat64(), because the grabber
// stat()s the path and requires a character device. When this library comes before libv4l2 in the global symbol
// scope (linked first into the test executable, or LD_PRELOAD), every call on the fake device path is answered
// here; any other path or descriptor is forwarded to the next definition (the real libv4l2 / libc), so real
// cameras keep working in the same process.
//
// The device behaves like a fixed-resolution webcam: one input, the pixel formats listed in the environment,
// a single frame size (that of the served images) imposed on every S_FMT/TRY_FMT whatever was requested, MMAP
// streaming with a FIFO of queued buffers. select() works on the returned descriptor because it is a real
// descriptor on /dev/null, always readable.
//
// Environment, read at each v4l2_open() of the fake device:
//   HSLAM_V4L2_DOUBLE_DEVICE      fake device path (default /dev/video-hslam-test)
//   HSLAM_V4L2_DOUBLE_FRAMES      ':'-separated binary 8-bit PGM (P5) files of one size, served in a loop (required)
//   HSLAM_V4L2_DOUBLE_FORMATS     ','-separated pixel formats offered, in order, among GREY, YUYV, RGB24, MJPG
//                                 (default YUYV,GREY). GREY pixel p is sent as p, YUYV as Y = p, U = V = 128,
//                                 RGB24 as R = G = B = p; MJPG is listed but
//                                 its frames are raw (for a device ViSP cannot read).
//   HSLAM_V4L2_DOUBLE_FPS         nominal frame rate reported by G_PARM and used for timestamps (default 30)
//   HSLAM_V4L2_DOUBLE_TIMESTAMPS  ':'-separated timestamps in seconds for the first frames (then + 1/fps each);
//                                 default: 1000 s + n / fps
// Problems in the set-up are printed to stderr (this is test code) and v4l2_open() fails with EIO.
#include <libv4l2.h>
#include <linux/videodev2.h>

#include <dlfcn.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

namespace
{
const char *const kDefaultDevice = "/dev/video-hslam-test";
const double kDefaultFps = 30.;
const double kDefaultStartTime = 1000.;   // seconds; any positive value, like an uptime clock
const unsigned int kMaxBuffers = 8;       // what uvcvideo also caps to
const unsigned int kFakeMajor = 81;       // the video4linux character major
const unsigned int kFakeMinor = 199;      // unlikely to collide with a real /dev/videoN
const unsigned char kNeutralChroma = 128; // U = V = 128: no colour
const __u32 kDriverVersion = 0x010000;    // 1.0.0 in QUERYCAP's major.minor.patch bytes

struct Image {
  unsigned int width = 0, height = 0;
  std::vector<unsigned char> pixels; // row-major grey
};

struct Buffer {
  std::vector<unsigned char> data;
  bool queued = false;
  bool mapped = false;
  v4l2_buffer last{}; // as last dequeued
};

struct Device {
  int fd = -1;
  std::vector<Image> frames;
  std::vector<__u32> formats;
  std::vector<double> timestamps;
  double fps = kDefaultFps;
  __u32 pixelformat = 0;
  std::vector<Buffer> buffers;
  std::deque<unsigned int> queue; // indices of queued buffers, FIFO as a driver fills them
  bool streaming = false;
  unsigned long delivered = 0;
};

std::mutex g_mutex;
std::map<int, Device> g_devices;

std::string fakeDevicePath()
{
  const char *env = std::getenv("HSLAM_V4L2_DOUBLE_DEVICE");
  return (env && *env) ? std::string(env) : std::string(kDefaultDevice);
}

bool isFakePath(const char *path)
{
  return path && fakeDevicePath() == path;
}

template <typename Fn> Fn next(const char *name)
{
  return reinterpret_cast<Fn>(dlsym(RTLD_NEXT, name));
}

std::vector<std::string> split(const std::string &text, char separator)
{
  std::vector<std::string> parts;
  std::stringstream stream(text);
  std::string part;
  while (std::getline(stream, part, separator)) {
    if (!part.empty()) {
      parts.push_back(part);
    }
  }
  return parts;
}

// Binary PGM, maxval <= 255, '#' comments in the header.
bool readPgm(const std::string &path, Image &image)
{
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    std::fprintf(stderr, "hslam_v4l2_double: cannot open '%s'\n", path.c_str());
    return false;
  }
  std::string magic;
  file >> magic;
  unsigned int header[3] = {0, 0, 0};
  for (unsigned int &value : header) {
    file >> std::ws;
    while (file.peek() == '#') {
      std::string comment;
      std::getline(file, comment);
      file >> std::ws;
    }
    file >> value;
  }
  file.get(); // the single whitespace before the raster
  if (magic != "P5" || !file || header[0] == 0 || header[1] == 0 || header[2] == 0 || header[2] > 255) {
    std::fprintf(stderr, "hslam_v4l2_double: '%s' is not an 8-bit binary PGM\n", path.c_str());
    return false;
  }
  image.width = header[0];
  image.height = header[1];
  image.pixels.resize(static_cast<std::size_t>(image.width) * image.height);
  file.read(reinterpret_cast<char *>(image.pixels.data()), static_cast<std::streamsize>(image.pixels.size()));
  if (!file) {
    std::fprintf(stderr, "hslam_v4l2_double: '%s' is truncated\n", path.c_str());
    return false;
  }
  return true;
}

bool parseFormat(const std::string &name, __u32 &format)
{
  if (name == "GREY") {
    format = V4L2_PIX_FMT_GREY;
  } else if (name == "YUYV") {
    format = V4L2_PIX_FMT_YUYV;
  } else if (name == "RGB24") {
    format = V4L2_PIX_FMT_RGB24;
  } else if (name == "MJPG") { // offered only: frames are never compressed (tests a format ViSP cannot read)
    format = V4L2_PIX_FMT_MJPEG;
  } else {
    return false;
  }
  return true;
}

unsigned int bytesPerPixel(__u32 format)
{
  switch (format) {
  case V4L2_PIX_FMT_YUYV:
    return 2;
  case V4L2_PIX_FMT_RGB24:
    return 3;
  default:
    return 1;
  }
}

bool configure(Device &device)
{
  const char *frames = std::getenv("HSLAM_V4L2_DOUBLE_FRAMES");
  for (const std::string &path : split(frames ? frames : "", ':')) {
    Image image;
    if (!readPgm(path, image)) {
      return false;
    }
    if (!device.frames.empty() && (image.width != device.frames[0].width || image.height != device.frames[0].height)) {
      std::fprintf(stderr, "hslam_v4l2_double: '%s' differs in size from the first frame\n", path.c_str());
      return false;
    }
    device.frames.push_back(std::move(image));
  }
  if (device.frames.empty()) {
    std::fprintf(stderr, "hslam_v4l2_double: HSLAM_V4L2_DOUBLE_FRAMES lists no image\n");
    return false;
  }
  const char *formats = std::getenv("HSLAM_V4L2_DOUBLE_FORMATS");
  for (const std::string &name : split((formats && *formats) ? formats : "YUYV,GREY", ',')) {
    __u32 format = 0;
    if (!parseFormat(name, format)) {
      std::fprintf(stderr, "hslam_v4l2_double: unknown pixel format '%s'\n", name.c_str());
      return false;
    }
    device.formats.push_back(format);
  }
  if (device.formats.empty()) {
    return false;
  }
  device.pixelformat = device.formats[0];
  const char *fps = std::getenv("HSLAM_V4L2_DOUBLE_FPS");
  if (fps && *fps) {
    device.fps = std::atof(fps);
    if (!(device.fps > 0.)) {
      std::fprintf(stderr, "hslam_v4l2_double: bad HSLAM_V4L2_DOUBLE_FPS '%s'\n", fps);
      return false;
    }
  }
  const char *timestamps = std::getenv("HSLAM_V4L2_DOUBLE_TIMESTAMPS");
  for (const std::string &value : split(timestamps ? timestamps : "", ':')) {
    device.timestamps.push_back(std::atof(value.c_str()));
  }
  if ((device.frames[0].width % 2) != 0) {
    std::fprintf(stderr, "hslam_v4l2_double: YUYV needs an even width\n");
    return false;
  }
  return true;
}

void fillFormat(const Device &device, v4l2_format &format, __u32 pixelformat)
{
  const Image &first = device.frames[0];
  v4l2_pix_format &pix = format.fmt.pix;
  pix.width = first.width; // a fixed-resolution sensor: the request is ignored, as drivers adjust silently
  pix.height = first.height;
  pix.pixelformat = pixelformat;
  pix.field = V4L2_FIELD_NONE;
  pix.bytesperline = first.width * bytesPerPixel(pixelformat);
  pix.sizeimage = pix.bytesperline * first.height;
  pix.colorspace = V4L2_COLORSPACE_SRGB;
}

__u32 chooseFormat(const Device &device, __u32 requested)
{
  for (__u32 offered : device.formats) {
    if (offered == requested) {
      return requested;
    }
  }
  return device.formats[0]; // drivers fall back to a format they have instead of failing
}

double frameTimestamp(const Device &device, unsigned long n)
{
  if (n < device.timestamps.size()) {
    return device.timestamps[n];
  }
  const double last = device.timestamps.empty() ? kDefaultStartTime - 1. / device.fps : device.timestamps.back();
  const unsigned long sinceLast = n - device.timestamps.size() + 1;
  return last + static_cast<double>(sinceLast) / device.fps;
}

void fillFrame(Device &device, Buffer &buffer)
{
  const Image &image = device.frames[device.delivered % device.frames.size()];
  const std::size_t count = image.pixels.size();
  unsigned char *out = buffer.data.data();
  switch (device.pixelformat) {
  case V4L2_PIX_FMT_YUYV:
    for (std::size_t i = 0; i < count; i += 2) {
      out[2 * i] = image.pixels[i];
      out[2 * i + 1] = kNeutralChroma;
      out[2 * i + 2] = image.pixels[i + 1];
      out[2 * i + 3] = kNeutralChroma;
    }
    break;
  case V4L2_PIX_FMT_RGB24:
    for (std::size_t i = 0; i < count; ++i) {
      out[3 * i] = out[3 * i + 1] = out[3 * i + 2] = image.pixels[i];
    }
    break;
  default:
    std::memcpy(out, image.pixels.data(), count);
    break;
  }
}

int fail(int error)
{
  errno = error;
  return -1;
}

int handleIoctl(Device &device, unsigned long request, void *arg)
{
  switch (request) {
  case VIDIOC_QUERYCAP: {
    v4l2_capability *cap = static_cast<v4l2_capability *>(arg);
    std::memset(cap, 0, sizeof(*cap));
    std::snprintf(reinterpret_cast<char *>(cap->driver), sizeof(cap->driver), "hslam_double");
    std::snprintf(reinterpret_cast<char *>(cap->card), sizeof(cap->card), "H-SLAM test camera");
    std::snprintf(reinterpret_cast<char *>(cap->bus_info), sizeof(cap->bus_info), "platform:hslam");
    cap->version = kDriverVersion;
    cap->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
    cap->capabilities = cap->device_caps | V4L2_CAP_DEVICE_CAPS;
    return 0;
  }
  case VIDIOC_ENUMINPUT: {
    v4l2_input *input = static_cast<v4l2_input *>(arg);
    if (input->index != 0) {
      return fail(EINVAL);
    }
    std::memset(input, 0, sizeof(*input));
    std::snprintf(reinterpret_cast<char *>(input->name), sizeof(input->name), "Camera 1");
    input->type = V4L2_INPUT_TYPE_CAMERA;
    return 0;
  }
  case VIDIOC_G_INPUT:
    *static_cast<int *>(arg) = 0;
    return 0;
  case VIDIOC_S_INPUT:
    return (*static_cast<int *>(arg) == 0) ? 0 : fail(EINVAL);
  case VIDIOC_ENUM_FMT: {
    v4l2_fmtdesc *desc = static_cast<v4l2_fmtdesc *>(arg);
    if (desc->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || desc->index >= device.formats.size()) {
      return fail(EINVAL);
    }
    const __u32 index = desc->index;
    std::memset(desc, 0, sizeof(*desc));
    desc->index = index;
    desc->type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    desc->pixelformat = device.formats[index];
    std::snprintf(reinterpret_cast<char *>(desc->description), sizeof(desc->description), "%.4s",
                  reinterpret_cast<const char *>(&desc->pixelformat));
    return 0;
  }
  case VIDIOC_G_FMT:
  case VIDIOC_S_FMT:
  case VIDIOC_TRY_FMT: {
    v4l2_format *format = static_cast<v4l2_format *>(arg);
    if (format->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) {
      return fail(EINVAL);
    }
    if (request == VIDIOC_S_FMT && !device.buffers.empty()) {
      return fail(EBUSY);
    }
    const __u32 pixelformat =
        (request == VIDIOC_G_FMT) ? device.pixelformat : chooseFormat(device, format->fmt.pix.pixelformat);
    std::memset(&format->fmt, 0, sizeof(format->fmt));
    fillFormat(device, *format, pixelformat);
    if (request == VIDIOC_S_FMT) {
      device.pixelformat = pixelformat;
    }
    return 0;
  }
  case VIDIOC_G_PARM:
  case VIDIOC_S_PARM: {
    v4l2_streamparm *parm = static_cast<v4l2_streamparm *>(arg);
    if (parm->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) {
      return fail(EINVAL);
    }
    std::memset(&parm->parm, 0, sizeof(parm->parm));
    parm->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
    const double kMicro = 1e6; // timeperframe as a fraction over microseconds
    parm->parm.capture.timeperframe.numerator = static_cast<__u32>(std::lround(kMicro / device.fps));
    parm->parm.capture.timeperframe.denominator = static_cast<__u32>(kMicro);
    parm->parm.capture.readbuffers = 0;
    return 0;
  }
  case VIDIOC_REQBUFS: {
    v4l2_requestbuffers *req = static_cast<v4l2_requestbuffers *>(arg);
    if (req->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || req->memory != V4L2_MEMORY_MMAP) {
      return fail(EINVAL);
    }
    if (device.streaming) {
      return fail(EBUSY);
    }
    for (const Buffer &buffer : device.buffers) {
      if (buffer.mapped) {
        return fail(EBUSY);
      }
    }
    device.buffers.clear();
    device.queue.clear();
    req->count = std::min(req->count, kMaxBuffers);
    v4l2_format format{};
    fillFormat(device, format, device.pixelformat);
    device.buffers.resize(req->count);
    for (Buffer &buffer : device.buffers) {
      buffer.data.assign(format.fmt.pix.sizeimage, 0);
    }
    return 0;
  }
  case VIDIOC_QUERYBUF:
  case VIDIOC_QBUF:
  case VIDIOC_DQBUF: {
    v4l2_buffer *buf = static_cast<v4l2_buffer *>(arg);
    if (buf->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || buf->memory != V4L2_MEMORY_MMAP) {
      return fail(EINVAL);
    }
    const long pageSize = sysconf(_SC_PAGESIZE);
    if (request == VIDIOC_DQBUF) {
      if (!device.streaming) {
        return fail(EINVAL);
      }
      if (device.queue.empty()) {
        return fail(EAGAIN);
      }
      const unsigned int index = device.queue.front();
      device.queue.pop_front();
      Buffer &buffer = device.buffers[index];
      fillFrame(device, buffer);
      const double t = frameTimestamp(device, device.delivered);
      const double kMicro = 1e6;
      const long long us = std::llround(t * kMicro);
      buffer.queued = false;
      std::memset(&buffer.last, 0, sizeof(buffer.last));
      buffer.last.index = index;
      buffer.last.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buffer.last.memory = V4L2_MEMORY_MMAP;
      buffer.last.bytesused = static_cast<__u32>(buffer.data.size());
      buffer.last.length = static_cast<__u32>(buffer.data.size());
      buffer.last.m.offset = static_cast<__u32>(index * pageSize);
      buffer.last.field = V4L2_FIELD_NONE;
      buffer.last.flags = V4L2_BUF_FLAG_MAPPED | V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
      buffer.last.sequence = static_cast<__u32>(device.delivered);
      buffer.last.timestamp.tv_sec = static_cast<time_t>(us / 1000000);
      buffer.last.timestamp.tv_usec = static_cast<suseconds_t>(us % 1000000);
      ++device.delivered;
      *buf = buffer.last;
      return 0;
    }
    if (buf->index >= device.buffers.size()) {
      return fail(EINVAL);
    }
    Buffer &buffer = device.buffers[buf->index];
    if (request == VIDIOC_QBUF) {
      if (buffer.queued) {
        return fail(EINVAL);
      }
      buffer.queued = true;
      device.queue.push_back(buf->index);
    }
    buf->length = static_cast<__u32>(buffer.data.size());
    buf->m.offset = static_cast<__u32>(buf->index * pageSize);
    buf->flags = (buffer.mapped ? V4L2_BUF_FLAG_MAPPED : 0u) | (buffer.queued ? V4L2_BUF_FLAG_QUEUED : 0u);
    return 0;
  }
  case VIDIOC_STREAMON:
  case VIDIOC_STREAMOFF:
    if (*static_cast<int *>(arg) != V4L2_BUF_TYPE_VIDEO_CAPTURE) {
      return fail(EINVAL);
    }
    device.streaming = (request == VIDIOC_STREAMON);
    if (!device.streaming) { // as in the kernel: STREAMOFF dequeues everything
      device.queue.clear();
      for (Buffer &buffer : device.buffers) {
        buffer.queued = false;
      }
    }
    return 0;
  default: // ENUMSTD, G_STD, controls...: a webcam has no analogue standard, and we have no control
    return fail(ENOTTY);
  }
}
} // namespace

extern "C" {

__attribute__((visibility("default"))) int v4l2_open(const char *file, int oflag, ...)
{
  mode_t mode = 0;
  if (oflag & O_CREAT) {
    va_list args;
    va_start(args, oflag);
    mode = static_cast<mode_t>(va_arg(args, int));
    va_end(args);
  }
  if (!isFakePath(file)) {
    auto real = next<int (*)(const char *, int, ...)>("v4l2_open");
    return real ? real(file, oflag, mode) : fail(ENOSYS);
  }
  Device device;
  if (!configure(device)) {
    return fail(EIO);
  }
  device.fd = ::open("/dev/null", O_RDWR | O_CLOEXEC); // a real descriptor, so select() reports it readable
  if (device.fd < 0) {
    return -1;
  }
  std::lock_guard<std::mutex> lock(g_mutex);
  const int fd = device.fd;
  g_devices[fd] = std::move(device);
  return fd;
}

__attribute__((visibility("default"))) int v4l2_close(int fd)
{
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    auto found = g_devices.find(fd);
    if (found != g_devices.end()) {
      g_devices.erase(found); // buffers go with it, mapped or not (the kernel keeps them alive the same way)
      return ::close(fd);
    }
  }
  auto real = next<int (*)(int)>("v4l2_close");
  return real ? real(fd) : fail(ENOSYS);
}

__attribute__((visibility("default"))) int v4l2_ioctl(int fd, unsigned long int request, ...)
{
  va_list args;
  va_start(args, request);
  void *arg = va_arg(args, void *);
  va_end(args);
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    auto found = g_devices.find(fd);
    if (found != g_devices.end()) {
      return handleIoctl(found->second, request, arg);
    }
  }
  auto real = next<int (*)(int, unsigned long int, ...)>("v4l2_ioctl");
  return real ? real(fd, request, arg) : fail(ENOSYS);
}

__attribute__((visibility("default"))) void *v4l2_mmap(void *start, size_t length, int prot, int flags, int fd,
                                                       int64_t offset)
{
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    auto found = g_devices.find(fd);
    if (found != g_devices.end()) {
      const long pageSize = sysconf(_SC_PAGESIZE);
      Device &device = found->second;
      const std::size_t index = static_cast<std::size_t>(offset / pageSize);
      if (offset % pageSize != 0 || index >= device.buffers.size() || length > device.buffers[index].data.size()) {
        errno = EINVAL;
        return MAP_FAILED;
      }
      device.buffers[index].mapped = true;
      return device.buffers[index].data.data();
    }
  }
  auto real = next<void *(*)(void *, size_t, int, int, int, int64_t)>("v4l2_mmap");
  if (!real) {
    errno = ENOSYS;
    return MAP_FAILED;
  }
  return real(start, length, prot, flags, fd, offset);
}

// The length is not checked: ViSP 3.5 unmaps GREY buffers with twice their length (it raises bytesperline to
// 2 * width as "buggy driver paranoia"), and the buffers here are not real mappings anyway.
__attribute__((visibility("default"))) int v4l2_munmap(void *start, size_t length)
{
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    for (auto &entry : g_devices) {
      for (Buffer &buffer : entry.second.buffers) {
        if (buffer.data.data() == start) {
          buffer.mapped = false;
          return 0;
        }
      }
    }
  }
  auto real = next<int (*)(void *, size_t)>("v4l2_munmap");
  return real ? real(start, length) : fail(ENOSYS);
}

static void fakeStat(struct stat *buf)
{
  std::memset(buf, 0, sizeof(*buf));
  buf->st_mode = S_IFCHR | 0660;
  buf->st_rdev = makedev(kFakeMajor, kFakeMinor);
  buf->st_nlink = 1;
}

__attribute__((visibility("default"))) int stat(const char *path, struct stat *buf) noexcept
{
  if (isFakePath(path)) {
    fakeStat(buf);
    return 0;
  }
  auto real = next<int (*)(const char *, struct stat *)>("stat");
  return real ? real(path, buf) : fail(ENOSYS);
}

__attribute__((visibility("default"))) int stat64(const char *path, struct stat64 *buf) noexcept
{
  if (isFakePath(path)) {
    static_assert(sizeof(struct stat) == sizeof(struct stat64), "x86_64 and aarch64: stat and stat64 agree");
    fakeStat(reinterpret_cast<struct stat *>(buf));
    return 0;
  }
  auto real = next<int (*)(const char *, struct stat64 *)>("stat64");
  return real ? real(path, buf) : fail(ENOSYS);
}

} // extern "C"
