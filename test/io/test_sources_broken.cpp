// Every reader on broken copies made by the test in a temporary folder: a missing image, a list cut in the middle
// of its last line, and corrupt images (PNG and JPEG cut in half, garbage bytes). Each error must carry its code and
// name the file (and the list's line). Sequences are small synthetic ones (64x48, a few frames), so these tests
// run everywhere in milliseconds; TUM monoVO's images.zip has its own broken-entry tests in test_sources_tum.cpp.
#include "HSlamTestData.h"
#include "HSlamTestErrors.h"
#include "ImageSourceFixtures.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/io/vpImageIo.h>
#include <visp3/io/vpVideoWriter.h>

#include <opencv2/videoio.hpp>

#include <cstdio>
#include <filesystem>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using hslam_test::expectHSlamError;
using namespace hslam_test;

namespace
{
const unsigned int kFrames = 4;
//! The frame the tests damage: neither the first (some readers decode it at open for the size) nor the last.
const unsigned int kBroken = 2;

std::string numbered(const char *format, unsigned int i)
{
  char name[64];
  std::snprintf(name, sizeof(name), format, i);
  return name;
}

//! EuRoC/ASL layout: mav0/cam0/{sensor.yaml, data.csv, data/<ns>.png}. Returns the sequence folder.
std::string makeEuroc(const TempDir &tmp)
{
  const std::string seq = tmp / "euroc";
  const std::string cam = seq + "/mav0/cam0";
  writeText(cam + "/sensor.yaml",
            "%YAML:1.0\nsensor_type: camera\nrate_hz: 20\nresolution: [64, 48]\n"
            "camera_model: pinhole\nintrinsics: [50.0, 50.0, 31.5, 23.5]\n"
            "distortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n");
  std::ostringstream csv;
  csv << "#timestamp [ns],filename\n";
  for (unsigned int i = 0; i < kFrames; ++i) {
    const std::string stamp = std::to_string(1403715273262142976ULL + 50000000ULL * i);
    fs::create_directories(cam + "/data");
    vpImageIo::write(patternImage(i), cam + "/data/" + stamp + ".png");
    csv << stamp << "," << stamp << ".png\n";
  }
  writeText(cam + "/data.csv", csv.str());
  return seq;
}

std::string eurocImage(const std::string &seq, unsigned int i)
{
  return seq + "/mav0/cam0/data/" + std::to_string(1403715273262142976ULL + 50000000ULL * i) + ".png";
}

//! TUM RGB-D layout with H-SLAM's times.txt: rgb/NNNNNN.<ext>, rgb.txt (2 comment lines), camera.txt.
std::string makeRgbd(const TempDir &tmp, const std::string &ext)
{
  const std::string dir = tmp / "rgbd";
  std::ostringstream list, times;
  list << "# color images\n# timestamp filename\n";
  for (unsigned int i = 0; i < kFrames; ++i) {
    const std::string name = numbered("rgb/%06u.", i) + ext;
    fs::create_directories(dir + "/rgb");
    vpImageIo::write(patternImage(i), dir + "/" + name);
    list << numbered("%u.", i) << numbered("%06u", 1000 * i / 30) << " " << name << "\n";
    times << numbered("%06u ", i) << numbered("%u.", i) << numbered("%06u", 1000 * i / 30) << " " << (8. + i) << "\n";
  }
  writeText(dir + "/rgb.txt", list.str());
  writeText(dir + "/times.txt", times.str());
  writeText(dir + "/camera.txt", testCameraText());
  return dir;
}

//! KITTI odometry layout: image_0/NNNNNN.png, times.txt (scientific notation, as KITTI), calib.txt.
std::string makeKitti(const TempDir &tmp)
{
  const std::string dir = tmp / "kitti";
  std::ostringstream times;
  for (unsigned int i = 0; i < kFrames; ++i) {
    fs::create_directories(dir + "/image_0");
    vpImageIo::write(patternImage(i), dir + numbered("/image_0/%06u.png", i));
    char line[32];
    std::snprintf(line, sizeof(line), "%e\n", 0.1036 * i);
    times << line;
  }
  writeText(dir + "/times.txt", times.str());
  writeText(dir + "/calib.txt", "P0: 50 0 31.5 0 0 50 23.5 0 0 0 1 0\n");
  return dir;
}

//! Plain image folder with its camera.txt: images/NNNNN.<ext>.
std::string makeImageFolder(const TempDir &tmp, const std::string &ext)
{
  const std::string dir = tmp / "images";
  fs::create_directories(dir);
  for (unsigned int i = 0; i < kFrames; ++i) {
    vpImageIo::write(patternImage(i), dir + numbered("/%05u.", i) + ext);
  }
  writeText(dir + "/camera.txt", testCameraText());
  return dir;
}

vpHSlamImageSource::Options withFrameRate()
{
  vpHSlamImageSource::Options options;
  options.frameRate = 20.;
  return options;
}

/*!
  Damage \e image in each way a copy can (cut in half, replaced by garbage), and check that the reader opened on
  \e input delivers the frames before it and then throws fileUnreadable naming the image. The file is restored
  after each damage.
*/
void expectCorruptImageReported(const std::string &input, const vpHSlamImageSource::Options &options,
                                const std::string &image, unsigned int index, const std::string &mention)
{
  const std::vector<unsigned char> original = readBytes(image);
  ASSERT_FALSE(original.empty()) << image;
  const std::vector<std::pair<std::string, std::function<void()>>> damages = {
      {"cut in half", [&] { truncateToHalf(image); }},
      {"garbage", [&] { writeText(image, std::string(original.size(), '\x5a')); }}};
  for (const auto &damage : damages) {
    SCOPED_TRACE(damage.first + ": " + image);
    damage.second();
    std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(input, options);
    vpImage<unsigned char> I;
    vpHSlamImageSource::Frame frame;
    for (unsigned int i = 0; i < index; ++i) {
      ASSERT_TRUE(source->acquire(I, frame)) << "frame " << i;
    }
    expectHSlamError([&] { source->acquire(I, frame); }, vpHSlamException::fileUnreadable, {mention});
    writeBytes(image, original);
  }
}
} // namespace

// ---- EuRoC / ASL ------------------------------------------------------------------------------------------------

TEST(ImageSourceBrokenEuroc, MissingImageNamesFileAndLine)
{
  TempDir tmp;
  const std::string seq = makeEuroc(tmp);
  fs::remove(eurocImage(seq, kBroken));
  // data.csv: the header is line 1, frame 2 is line 4.
  expectHSlamError([&] { vpHSlamImageSource::create(seq); }, vpHSlamException::fileNotFound,
                   {fs::path(eurocImage(seq, kBroken)).filename().string(), "data.csv:4"});
}

TEST(ImageSourceBrokenEuroc, TruncatedListNamesLine)
{
  TempDir tmp;
  const std::string seq = makeEuroc(tmp);
  cutLastLineMidway(seq + "/mav0/cam0/data.csv");
  expectHSlamError([&] { vpHSlamImageSource::create(seq); }, vpHSlamException::parseError, {"data.csv:5"});
}

TEST(ImageSourceBrokenEuroc, CorruptImage)
{
  TempDir tmp;
  const std::string seq = makeEuroc(tmp);
  const std::string image = eurocImage(seq, kBroken);
  expectCorruptImageReported(seq, {}, image, kBroken, fs::path(image).filename().string());
}

// ---- TUM monoVO, images/ folder ------------------------------------------------------------------------------------

TEST(ImageSourceBrokenTumMono, MissingImageNamesItsLine)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kFrames);
  fs::remove(dir + "/images/00002.png");
  // The id of times.txt line 3 no longer matches the image at its position.
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::invalidTimestamps,
                   {"times.txt:3", "00002"});
}

TEST(ImageSourceBrokenTumMono, TruncatedListNamesLine)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kFrames);
  cutLastLineMidway(dir + "/times.txt");
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::parseError, {"times.txt:4"});
}

TEST(ImageSourceBrokenTumMono, CorruptPngAndJpeg)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kFrames);
  expectCorruptImageReported(dir, {}, dir + "/images/00002.png", kBroken, "images/00002.png");
  // The same sequence in JPEG: libjpeg decodes a cut file without error, the reader must not.
  for (unsigned int i = 0; i < kFrames; ++i) {
    const std::string stem = dir + numbered("/images/%05u", i);
    vpImageIo::write(patternImage(i), stem + ".jpg");
    fs::remove(stem + ".png");
  }
  expectCorruptImageReported(dir, {}, dir + "/images/00002.jpg", kBroken, "images/00002.jpg");
}

// ---- TUM monoVO, images.zip ----------------------------------------------------------------------------------------

TEST(ImageSourceBrokenTumMonoZip, MissingImageNamesItsLine)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kFrames);
  fs::remove(dir + "/images/00002.png");
  zipTumMonoImages(dir);
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::invalidTimestamps,
                   {"times.txt:3", "00002", "images.zip"});
}

TEST(ImageSourceBrokenTumMonoZip, TruncatedListNamesLine)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kFrames);
  zipTumMonoImages(dir);
  cutLastLineMidway(dir + "/times.txt");
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::parseError, {"times.txt:4"});
}

// ---- TUM RGB-D ---------------------------------------------------------------------------------------------------

TEST(ImageSourceBrokenTumRgbd, MissingImageNamesFileAndLine)
{
  TempDir tmp;
  const std::string dir = makeRgbd(tmp, "png");
  fs::remove(dir + "/rgb/000002.png");
  // rgb.txt: two comment lines, frame 2 on line 5.
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::fileNotFound,
                   {"rgb/000002.png", "rgb.txt:5"});
}

TEST(ImageSourceBrokenTumRgbd, TruncatedListsNameLine)
{
  TempDir tmp;
  const std::string dir = makeRgbd(tmp, "png");
  EXPECT_NEAR(readAll(*vpHSlamImageSource::create(dir), 64, 48).at(3).exposure, 11., 1e-12);
  cutLastLineMidway(dir + "/times.txt");
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::parseError, {"times.txt:4"});
  fs::remove(dir + "/times.txt");
  cutLastLineMidway(dir + "/rgb.txt");
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::parseError, {"rgb.txt:6"});
}

TEST(ImageSourceBrokenTumRgbd, CorruptPngAndJpeg)
{
  TempDir tmp;
  const std::string png = makeRgbd(tmp, "png");
  expectCorruptImageReported(png, {}, png + "/rgb/000002.png", kBroken, "rgb/000002.png");
  fs::remove_all(png);
  const std::string jpg = makeRgbd(tmp, "jpg");
  expectCorruptImageReported(jpg, {}, jpg + "/rgb/000002.jpg", kBroken, "rgb/000002.jpg");
}

// ---- KITTI odometry -----------------------------------------------------------------------------------------------

TEST(ImageSourceBrokenKitti, MissingImageNamesFileAndLine)
{
  TempDir tmp;
  const std::string dir = makeKitti(tmp);
  EXPECT_EQ(vpHSlamImageSource::create(dir)->getFrameCount(), static_cast<int>(kFrames));
  fs::remove(dir + "/image_0/000002.png");
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::fileNotFound,
                   {"image_0/000002.png", "times.txt:3"});
}

TEST(ImageSourceBrokenKitti, TruncatedListNamesLine)
{
  TempDir tmp;
  const std::string dir = makeKitti(tmp);
  // "3.108000e-01" cut to "3.108" still parses, as a time ten times too late: only the missing end of line tells.
  cutLastLineMidway(dir + "/times.txt");
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::parseError, {"times.txt:4"});
}

TEST(ImageSourceBrokenKitti, CorruptImage)
{
  TempDir tmp;
  const std::string dir = makeKitti(tmp);
  expectCorruptImageReported(dir, {}, dir + "/image_0/000002.png", kBroken, "image_0/000002.png");
}

// ---- Image folder and printf pattern (no list: the folder or the numbering is the list) ---------------------------

TEST(ImageSourceBrokenImages, MissingImageInPatternNumbering)
{
  TempDir tmp;
  const std::string dir = makeImageFolder(tmp, "png");
  const std::string pattern = dir + "/%05d.png";
  EXPECT_EQ(vpHSlamImageSource::create(pattern, withFrameRate())->getFrameCount(), static_cast<int>(kFrames));
  fs::remove(dir + "/00002.png");
  // Frames 0 and 1 exist, 3 too: stopping at the gap would drop frame 3 silently.
  expectHSlamError([&] { vpHSlamImageSource::create(pattern, withFrameRate()); }, vpHSlamException::fileNotFound,
                   {"00002.png", "00003.png"});
  // The missing folder itself.
  expectHSlamError(
      [&] {
        vpHSlamImageSource::create(tmp / "gone", [] {
          vpHSlamImageSource::Options o = withFrameRate();
          o.format = vpHSlamImageSource::formatImages;
          return o;
        }());
      },
      vpHSlamException::fileNotFound, {"gone"});
}

TEST(ImageSourceBrokenImages, CorruptPngAndJpeg)
{
  TempDir tmp;
  const std::string png = makeImageFolder(tmp, "png");
  expectCorruptImageReported(png, withFrameRate(), png + "/00002.png", kBroken, "00002.png");
  expectCorruptImageReported(png + "/%05d.png", withFrameRate(), png + "/00002.png", kBroken, "00002.png");
  fs::remove_all(png);
  const std::string jpg = makeImageFolder(tmp, "jpg");
  expectCorruptImageReported(jpg, withFrameRate(), jpg + "/00002.jpg", kBroken, "00002.jpg");
}

// ---- Video file ---------------------------------------------------------------------------------------------------

namespace
{
//! Motion-JPEG AVI of kFrames 64x48 frames beside a camera.txt.
std::string makeVideo(const TempDir &tmp)
{
  const std::string video = tmp / "clip.avi";
  vpVideoWriter writer;
  writer.setCodec(cv::VideoWriter::fourcc('M', 'J', 'P', 'G'));
  writer.setFramerate(20.);
  writer.setFileName(video);
  vpImage<unsigned char> I = patternImage(0);
  writer.open(I);
  for (unsigned int i = 0; i < kFrames; ++i) {
    I = patternImage(i);
    writer.saveFrame(I);
  }
  writer.close();
  writeText(tmp / "camera.txt", testCameraText());
  return video;
}
} // namespace

TEST(ImageSourceBrokenVideo, MissingVideoFile)
{
  TempDir tmp;
  const std::string video = makeVideo(tmp);
  EXPECT_EQ(readAll(*vpHSlamImageSource::create(video, withFrameRate()), 64, 48).size(), kFrames);
  fs::remove(video);
  vpHSlamImageSource::Options options = withFrameRate();
  options.format = vpHSlamImageSource::formatVideo;
  expectHSlamError([&] { vpHSlamImageSource::create(video, options); }, vpHSlamException::fileNotFound, {"clip.avi"});
}

TEST(ImageSourceBrokenVideo, GarbageVideoFile)
{
  TempDir tmp;
  const std::string video = makeVideo(tmp);
  writeText(video, std::string(4096, '\x5a'));
  expectHSlamError([&] { vpHSlamImageSource::create(video, withFrameRate()); }, vpHSlamException::fileUnreadable,
                   {"clip.avi"});
}

TEST(ImageSourceBrokenVideo, TruncatedVideoFile)
{
  TempDir tmp;
  const std::string video = makeVideo(tmp);
  truncateToHalf(video); // the AVI index at the end is gone
  // Refused at open or at the first undecodable frame, but never a shorter sequence without a word.
  unsigned int delivered = 0;
  expectHSlamError(
      [&] {
        std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(video, withFrameRate());
        vpImage<unsigned char> I;
        vpHSlamImageSource::Frame frame;
        while (source->acquire(I, frame)) {
          ++delivered;
        }
      },
      vpHSlamException::fileUnreadable, {"clip.avi"});
  EXPECT_LT(delivered, kFrames);
}
