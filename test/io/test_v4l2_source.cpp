// Live V4L2 source (hslam::createV4l2Source) against a fake camera: the test double of test/io/v4l2_double
// answers libv4l2's calls for /dev/video-hslam-test with the PGM frames these tests write. Tests that need the
// double skip when it is not interposed (not linked first, not preloaded); the error tests need no camera.
#include "HSlamTestData.h"
#include "HSlamTestErrors.h"

#include "io/V4l2Source.h"

#include <visp3/hslam/vpHSlamException.h>

#include <dlfcn.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace
{
const char *const kFakeDevice = "/dev/video-hslam-test";
const unsigned int kWidth = 64, kHeight = 48;
const unsigned int kFrameCount = 3;
const double kDoubleStart = 1000.;       // seconds: the double's first timestamp when none is given
const double kDoubleFps = 30.;           // Hz: the double's default rate
const double kTimestampTolerance = 1e-6; // seconds: timeval resolution

bool doubleInterposed()
{
  void *symbol = dlsym(RTLD_DEFAULT, "v4l2_open");
  Dl_info info;
  return symbol && dladdr(symbol, &info) && info.dli_fname &&
         std::string(info.dli_fname).find("hslam_v4l2_double") != std::string::npos;
}

#define REQUIRE_V4L2_DOUBLE()                                                                                          \
  if (!doubleInterposed()) {                                                                                           \
    GTEST_SKIP() << "the V4L2 test double is not interposed: link test_v4l2_source with hslam_v4l2_double "            \
                    "(test/io/v4l2_double) or run with LD_PRELOAD=.../libhslam_v4l2_double.so";                        \
  }

//! Sets environment variables for one test and restores them after.
class ScopedEnvironment
{
public:
  ~ScopedEnvironment()
  {
    for (const auto &saved : m_saved) {
      if (saved.second.first) {
        setenv(saved.first.c_str(), saved.second.second.c_str(), 1);
      } else {
        unsetenv(saved.first.c_str());
      }
    }
  }
  void set(const std::string &name, const std::string &value)
  {
    if (m_saved.find(name) == m_saved.end()) {
      const char *old = std::getenv(name.c_str());
      m_saved[name] = std::make_pair(old != nullptr, old ? std::string(old) : std::string());
    }
    setenv(name.c_str(), value.c_str(), 1);
  }

private:
  std::map<std::string, std::pair<bool, std::string>> m_saved;
};

//! Pixel value of served frame k: distinct per frame, covering 0..255.
unsigned char pattern(unsigned int k, unsigned int i, unsigned int j)
{
  return static_cast<unsigned char>((5 * j + 11 * i + 70 * k) & 0xff);
}

class V4l2SourceTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    char folder[] = "/tmp/hslam_v4l2_XXXXXX";
    ASSERT_NE(mkdtemp(folder), nullptr);
    m_folder = folder;
    std::string list;
    for (unsigned int k = 0; k < kFrameCount; ++k) {
      vpImage<unsigned char> I(kHeight, kWidth);
      for (unsigned int i = 0; i < kHeight; ++i) {
        for (unsigned int j = 0; j < kWidth; ++j) {
          I[i][j] = pattern(k, i, j);
        }
      }
      const std::string path = m_folder + "/frame" + std::to_string(k) + ".pgm";
      std::ofstream file(path, std::ios::binary);
      file << "P5\n# served by the V4L2 double\n" << kWidth << " " << kHeight << "\n255\n";
      file.write(reinterpret_cast<const char *>(I.bitmap), I.getSize());
      m_frames.push_back(I);
      m_files.push_back(path);
      list += (list.empty() ? "" : ":") + path;
    }
    m_env.set("HSLAM_V4L2_DOUBLE_FRAMES", list);
    m_env.set("HSLAM_V4L2_DOUBLE_DEVICE", kFakeDevice);
    m_env.set("HSLAM_V4L2_DOUBLE_FORMATS", "YUYV,GREY");
    m_env.set("HSLAM_V4L2_DOUBLE_TIMESTAMPS", "");
    m_env.set("HSLAM_V4L2_DOUBLE_FPS", "");
    m_options.width = kWidth;
    m_options.height = kHeight;
  }

  void TearDown() override
  {
    for (const std::string &path : m_files) {
      std::remove(path.c_str());
    }
    ::rmdir(m_folder.c_str());
  }

  //! Largest absolute difference between I and served frame k.
  int maxDifference(const vpImage<unsigned char> &I, unsigned int k) const
  {
    int worst = 0;
    for (unsigned int n = 0; n < I.getSize(); ++n) {
      worst = std::max(worst, std::abs(static_cast<int>(I.bitmap[n]) - m_frames[k].bitmap[n]));
    }
    return worst;
  }

  //! Acquire \e count frames and check content (within \e tolerance grey levels), index and timestamps.
  void checkStream(vpHSlamImageSource &source, unsigned int count, int tolerance)
  {
    vpImage<unsigned char> I;
    vpHSlamImageSource::Frame frame;
    for (unsigned int n = 0; n < count; ++n) {
      ASSERT_TRUE(source.acquire(I, frame)) << "frame " << n;
      ASSERT_EQ(I.getWidth(), kWidth);
      ASSERT_EQ(I.getHeight(), kHeight);
      EXPECT_LE(maxDifference(I, n % kFrameCount), tolerance) << "frame " << n;
      EXPECT_EQ(frame.index, n);
      EXPECT_NEAR(frame.timestamp, kDoubleStart + n / kDoubleFps, kTimestampTolerance) << "frame " << n;
      EXPECT_LE(frame.exposure, 0.);
    }
  }

  std::string m_folder;
  std::vector<std::string> m_files;
  std::vector<vpImage<unsigned char>> m_frames;
  ScopedEnvironment m_env;
  vpHSlamImageSource::Options m_options;
};

void expectDeviceError(const std::string &device, const vpHSlamImageSource::Options &options,
                       const std::vector<std::string> &mentions)
{
  hslam_test::expectHSlamError([&] { hslam::createV4l2Source(device, options); }, vpHSlamException::deviceError,
                               mentions);
}
} // namespace

TEST(V4l2SourceErrors, MissingDeviceIsDeviceError)
{
  const std::string device = "/dev/video-hslam-missing-" + std::to_string(getpid());
  expectDeviceError(device, vpHSlamImageSource::Options(), {device, "no such device"});
}

TEST(V4l2SourceErrors, RegularFileIsNotADevice)
{
  const std::string path = HSLAM_SOURCE_DIR "/test/io/test_v4l2_source.cpp";
  expectDeviceError(path, vpHSlamImageSource::Options(), {path, "not a character device"});
}

TEST(V4l2SourceErrors, CharacterDeviceWithoutV4l2IsDeviceError)
{
  if (!hslam_test::pathExists("/dev/null")) {
    GTEST_SKIP() << "/dev/null is absent";
  }
  expectDeviceError("/dev/null", vpHSlamImageSource::Options(), {"/dev/null", "not a V4L2 device"});
}

TEST_F(V4l2SourceTest, GreyFramesAreDeliveredExactly)
{
  REQUIRE_V4L2_DOUBLE();
  m_env.set("HSLAM_V4L2_DOUBLE_FORMATS", "GREY");
  std::unique_ptr<vpHSlamImageSource> source = hslam::createV4l2Source(kFakeDevice, m_options);
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatV4l2);
  EXPECT_EQ(source->getFrameCount(), -1);
  EXPECT_NEAR(source->getFrameRate(), kDoubleFps, 0.01);
  EXPECT_NE(source->describe().find("GREY"), std::string::npos) << source->describe();
  checkStream(*source, 2 * kFrameCount + 1, 0); // the double loops: 7 frames cover every buffer reuse
}

TEST_F(V4l2SourceTest, YuyvIsPreferredAndItsLumaIsExact)
{
  REQUIRE_V4L2_DOUBLE();
  m_env.set("HSLAM_V4L2_DOUBLE_FORMATS", "GREY,YUYV"); // listed second, chosen first
  std::unique_ptr<vpHSlamImageSource> source = hslam::createV4l2Source(kFakeDevice, m_options);
  EXPECT_NE(source->describe().find("YUYV"), std::string::npos) << source->describe();
  checkStream(*source, 2 * kFrameCount + 1, 0);
}

TEST_F(V4l2SourceTest, Rgb24IsConvertedWithinRounding)
{
  REQUIRE_V4L2_DOUBLE();
  m_env.set("HSLAM_V4L2_DOUBLE_FORMATS", "RGB24");
  std::unique_ptr<vpHSlamImageSource> source = hslam::createV4l2Source(kFakeDevice, m_options);
  EXPECT_NE(source->describe().find("RGB24"), std::string::npos) << source->describe();
  checkStream(*source, kFrameCount, 1); // R = G = B = p, ViSP's weighted sum rounds to p +- 1
}

TEST_F(V4l2SourceTest, GuessedCameraIsCentredPinholeWithFocalEqualToWidth)
{
  REQUIRE_V4L2_DOUBLE();
  std::unique_ptr<vpHSlamImageSource> source = hslam::createV4l2Source(kFakeDevice, m_options);
  const vpHSlamCamera &cam = source->getCamera();
  EXPECT_EQ(cam.getModel(), vpHSlamCamera::pinhole);
  EXPECT_EQ(cam.getWidth(), kWidth);
  EXPECT_EQ(cam.getHeight(), kHeight);
  EXPECT_DOUBLE_EQ(cam.getFx(), kWidth);
  EXPECT_DOUBLE_EQ(cam.getFy(), kWidth);
  EXPECT_DOUBLE_EQ(cam.getCx(), 0.5 * (kWidth - 1));
  EXPECT_DOUBLE_EQ(cam.getCy(), 0.5 * (kHeight - 1));
  EXPECT_NE(source->describe().find("GUESSED"), std::string::npos) << source->describe();
  EXPECT_TRUE(source->getPhotometricCalibration().isEmpty());
}

TEST_F(V4l2SourceTest, CameraFileIsUsedAndItsSizeMustMatch)
{
  REQUIRE_V4L2_DOUBLE();
  const std::string matching = m_folder + "/camera.txt";
  std::ofstream(matching) << "Pinhole 50 51 30.5 22.5 0\n"
                          << kWidth << " " << kHeight << "\nnone\n"
                          << kWidth << " " << kHeight << "\n";
  m_files.push_back(matching);
  m_options.cameraFile = matching;
  std::unique_ptr<vpHSlamImageSource> source = hslam::createV4l2Source(kFakeDevice, m_options);
  EXPECT_DOUBLE_EQ(source->getCamera().getFx(), 50.);
  EXPECT_DOUBLE_EQ(source->getCamera().getCy(), 22.5);
  EXPECT_EQ(source->describe().find("GUESSED"), std::string::npos) << source->describe();

  const std::string other = m_folder + "/camera_vga.txt";
  std::ofstream(other) << "Pinhole 500 500 319.5 239.5 0\n640 480\nnone\n640 480\n";
  m_files.push_back(other);
  m_options.cameraFile = other;
  // A 640x480 camera file must be refused for 64x48 images.
  hslam_test::expectHSlamError([&] { hslam::createV4l2Source(kFakeDevice, m_options); },
                               vpHSlamException::invalidCalibration, {other});
}

TEST_F(V4l2SourceTest, UnchosenSizeIsTheCameraFileSize)
{
  REQUIRE_V4L2_DOUBLE();
  const std::string camera = m_folder + "/camera_small.txt";
  std::ofstream(camera) << "Pinhole 50 51 30.5 22.5 0\n"
                        << kWidth << " " << kHeight << "\nnone\n"
                        << kWidth << " " << kHeight << "\n";
  m_files.push_back(camera);
  m_options.width = 0; // not chosen: the camera file's size is requested, which the double serves
  m_options.height = 0;
  m_options.cameraFile = camera;
  std::unique_ptr<vpHSlamImageSource> source = hslam::createV4l2Source(kFakeDevice, m_options);
  EXPECT_EQ(source->getCamera().getWidth(), kWidth);
  EXPECT_DOUBLE_EQ(source->getCamera().getFx(), 50.);
  checkStream(*source, kFrameCount, 0);

  // A VGA camera file makes the source ask for 640x480, which the double (64x48 only) refuses.
  const std::string vga = m_folder + "/camera_vga.txt";
  std::ofstream(vga) << "Pinhole 500 500 319.5 239.5 0\n640 480\nnone\n640 480\n";
  m_files.push_back(vga);
  m_options.cameraFile = vga;
  expectDeviceError(kFakeDevice, m_options, {kFakeDevice, "requested size 640x480", "64x48"});
}

TEST_F(V4l2SourceTest, UnchosenSizeWithoutCameraFileIsVga)
{
  REQUIRE_V4L2_DOUBLE();
  const vpHSlamImageSource::Options defaults;
  EXPECT_EQ(defaults.width, 0u);
  EXPECT_EQ(defaults.height, 0u);
  m_options.width = 0;
  m_options.height = 0;
  expectDeviceError(kFakeDevice, m_options, {kFakeDevice, "requested size 640x480", "64x48"});
}

TEST_F(V4l2SourceTest, OneDimensionOnlyIsInvalidArgument)
{
  REQUIRE_V4L2_DOUBLE();
  m_options.height = 0;
  hslam_test::expectHSlamError([&] { hslam::createV4l2Source(kFakeDevice, m_options); },
                               vpHSlamException::invalidArgument, {kFakeDevice, "64x0"});
}

TEST_F(V4l2SourceTest, ImposedSizeIsDeviceErrorNamingBothSizes)
{
  REQUIRE_V4L2_DOUBLE();
  m_options.width = 80;
  m_options.height = 60;
  expectDeviceError(kFakeDevice, m_options, {kFakeDevice, "80x60", "64x48"});
}

TEST_F(V4l2SourceTest, NoConvertibleFormatIsDeviceError)
{
  REQUIRE_V4L2_DOUBLE();
  m_env.set("HSLAM_V4L2_DOUBLE_FORMATS", "MJPG"); // compressed only, and no libv4l2 emulation in the double
  expectDeviceError(kFakeDevice, m_options, {kFakeDevice, "MJPG"});
}

TEST_F(V4l2SourceTest, RepeatedTimestampIsAnError)
{
  REQUIRE_V4L2_DOUBLE();
  m_env.set("HSLAM_V4L2_DOUBLE_TIMESTAMPS", "5.0:5.5:5.5");
  std::unique_ptr<vpHSlamImageSource> source = hslam::createV4l2Source(kFakeDevice, m_options);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  ASSERT_TRUE(source->acquire(I, frame));
  EXPECT_NEAR(frame.timestamp, 5.0, kTimestampTolerance);
  ASSERT_TRUE(source->acquire(I, frame));
  EXPECT_NEAR(frame.timestamp, 5.5, kTimestampTolerance);
  // A repeated timestamp is refused.
  hslam_test::expectHSlamError([&] { source->acquire(I, frame); }, vpHSlamException::invalidTimestamps, {kFakeDevice});
}

TEST_F(V4l2SourceTest, StartFrameIsDroppedAndMaxFramesEndsTheSequence)
{
  REQUIRE_V4L2_DOUBLE();
  const unsigned int start = 2, count = 3;
  m_options.startFrame = start;
  m_options.maxFrames = count;
  std::unique_ptr<vpHSlamImageSource> source = hslam::createV4l2Source(kFakeDevice, m_options);
  EXPECT_EQ(source->getFrameCount(), static_cast<int>(count));
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  for (unsigned int n = 0; n < count; ++n) {
    ASSERT_TRUE(source->acquire(I, frame));
    EXPECT_EQ(frame.index, n);
    EXPECT_EQ(maxDifference(I, (start + n) % kFrameCount), 0) << "frame " << n;
    EXPECT_NEAR(frame.timestamp, kDoubleStart + (start + n) / kDoubleFps, kTimestampTolerance);
  }
  EXPECT_FALSE(source->acquire(I, frame));
}

TEST_F(V4l2SourceTest, CreateDispatchesDevicePathsToTheV4l2Source)
{
  REQUIRE_V4L2_DOUBLE();
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(kFakeDevice, m_options);
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatV4l2);
  std::cout << source->describe() << std::endl;
  checkStream(*source, kFrameCount, 0);
}
