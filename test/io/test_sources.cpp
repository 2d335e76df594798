// Image sources: each reader on the shared sequences, auto-detection, and error reporting on broken copies made
// in a temporary folder (never in the repository). More broken copies in test_sources_broken.cpp, TUM layouts
// (images.zip, photometric extension of TUM RGB-D) in test_sources_tum.cpp.
#include "HSlamTestData.h"
#include "HSlamTestErrors.h"
#include "ImageSourceFixtures.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/io/vpImageIo.h>
#include <visp3/io/vpVideoWriter.h>

#include <opencv2/videoio.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using hslam_test::expectHSlamError;
using namespace hslam_test;

namespace
{
void checkTumRgbdSequence(const std::string &path, std::size_t count)
{
  EXPECT_EQ(vpHSlamImageSource::detectFormat(path), vpHSlamImageSource::formatTumRgbd);
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(path);
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatTumRgbd);
  EXPECT_EQ(source->getFrameCount(), static_cast<int>(count));
  EXPECT_EQ(source->getCamera().getWidth(), 640u);
  EXPECT_NEAR(source->getFrameRate(), 30., 0.01);
  EXPECT_TRUE(source->getPhotometricCalibration().isEmpty());
  const std::vector<vpHSlamImageSource::Frame> frames = readAll(*source, 640, 480);
  ASSERT_EQ(frames.size(), count);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    // rgb.txt stores index/30 with 6 decimals.
    EXPECT_NEAR(frames[i].timestamp, static_cast<double>(i) / 30., 1e-6) << frames[i].name;
    EXPECT_LE(frames[i].exposure, 0.);
  }
}

//! A TUM RGB-D folder of \e n frames copied from the 7-Scenes sequence (only those files).
std::string makeRgbdCopy(const TempDir &tmp, const std::string &seq, unsigned int n)
{
  const std::string dst = tmp / "rgbd";
  copyFile(seq + "/camera.txt", dst + "/camera.txt");
  std::ostringstream list;
  list << "# timestamp filename\n";
  for (unsigned int i = 0; i < n; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "rgb/%06u.jpg", i);
    copyFile(seq + "/" + name, dst + "/" + name);
    list << std::to_string(i / 30.) << " " << name << "\n";
  }
  writeText(dst + "/rgb.txt", list.str());
  return dst;
}

/*!
  An EuRoC layout under \e tmp (mav0/cam0) holding the sensor.yaml, header and first \e n frames of the EuRoC
  sequence (only those files). Returns the data.csv text written; \e lines receives every line of the original.
*/
std::string makeEurocCopy(const TempDir &tmp, const std::string &seq, std::size_t n, std::vector<std::string> &lines)
{
  const std::string cam = tmp / "mav0/cam0";
  copyFile(seq + "/mav0/cam0/sensor.yaml", cam + "/sensor.yaml");
  lines = readLines(seq + "/mav0/cam0/data.csv");
  std::ostringstream csv;
  for (std::size_t i = 0; i <= n; ++i) {
    csv << lines[i] << "\n";
    if (i > 0) {
      const std::string name = lines[i].substr(lines[i].find(',') + 1);
      copyFile(seq + "/mav0/cam0/data/" + name, cam + "/data/" + name);
    }
  }
  writeText(cam + "/data.csv", csv.str());
  return csv.str();
}
} // namespace

TEST(ImageSourceFormats, NamesRoundTrip)
{
  for (int f = vpHSlamImageSource::formatAuto; f <= vpHSlamImageSource::formatV4l2; ++f) {
    const auto format = static_cast<vpHSlamImageSource::Format>(f);
    EXPECT_EQ(vpHSlamImageSource::parseFormat(vpHSlamImageSource::formatName(format)), format);
  }
  EXPECT_EQ(vpHSlamImageSource::formatName(vpHSlamImageSource::formatTumMono), "tum-mono");
  expectHSlamError([] { vpHSlamImageSource::parseFormat("tum"); }, vpHSlamException::invalidArgument, {"tum"});
  EXPECT_EQ(vpHSlamImageSource::detectFormat("/dev/video0"), vpHSlamImageSource::formatV4l2);
  EXPECT_EQ(vpHSlamImageSource::detectFormat("seq/img_%04d.png"), vpHSlamImageSource::formatImages);
  EXPECT_EQ(vpHSlamImageSource::detectFormat("/nonexistent/hslam/folder"), vpHSlamImageSource::formatAuto);
}

TEST(ImageSourceFormats, MissingOrUnknownInput)
{
  expectHSlamError([] { vpHSlamImageSource::create("/nonexistent/hslam/folder"); }, vpHSlamException::fileNotFound,
                   {"/nonexistent/hslam/folder"});
  TempDir tmp;
  writeText(tmp / "notes.txt", "nothing to see\n");
  expectHSlamError([&] { vpHSlamImageSource::create(tmp.path); }, vpHSlamException::unsupported, {tmp.path});
  vpHSlamImageSource::Options options;
  options.format = vpHSlamImageSource::formatKitti;
  expectHSlamError([&] { vpHSlamImageSource::create(tmp / "missing", options); }, vpHSlamException::fileNotFound,
                   {"missing"});
}

TEST(ImageSourceShared, SevenScenesTumRgbd)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "7scenes_redkitchen_000-299");
  checkTumRgbdSequence(seq, 300);
}

TEST(ImageSourceShared, TsukubaTumRgbd)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "tsukuba_cg_000-149");
  checkTumRgbdSequence(seq, 150);
}

TEST(ImageSourceShared, KittiOdometry)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "kitti06_000-050");
  EXPECT_EQ(vpHSlamImageSource::detectFormat(seq), vpHSlamImageSource::formatKitti);
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(seq);
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatKitti);
  EXPECT_EQ(source->getFrameCount(), 51);
  EXPECT_EQ(source->getCamera().getWidth(), 1226u);
  EXPECT_EQ(source->getCamera().getHeight(), 370u);
  EXPECT_NEAR(source->getCamera().getFx(), 707.0912, 1e-9);
  const std::vector<std::string> times = readLines(seq + "/times.txt");
  const std::vector<vpHSlamImageSource::Frame> frames = readAll(*source, 1226, 370);
  ASSERT_EQ(frames.size(), 51u);
  ASSERT_EQ(times.size(), 51u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].timestamp, std::stod(times[i])) << "frame " << i;
  }
  EXPECT_NEAR(source->getFrameRate(), 9.6, 0.3); // KITTI odometry: about 10 Hz with jitter
}

TEST(ImageSourceShared, KittiStartAndMaxFrames)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "kitti06_000-050");
  vpHSlamImageSource::Options options;
  options.startFrame = 10;
  options.maxFrames = 5;
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(seq, options);
  EXPECT_EQ(source->getFrameCount(), 5);
  const std::vector<std::string> times = readLines(seq + "/times.txt");
  const std::vector<vpHSlamImageSource::Frame> frames = readAll(*source, 1226, 370);
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames.front().timestamp, std::stod(times[10]));
  EXPECT_NE(frames.front().name.find("000010.png"), std::string::npos) << frames.front().name;
  EXPECT_NE(frames.back().name.find("000014.png"), std::string::npos) << frames.back().name;
  options.startFrame = 51;
  expectHSlamError([&] { vpHSlamImageSource::create(seq, options); }, vpHSlamException::invalidArgument, {"51"});
}

TEST(ImageSourceShared, EurocAsl)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "euroc_V1_01_easy_first95");
  EXPECT_EQ(vpHSlamImageSource::detectFormat(seq), vpHSlamImageSource::formatEuroc);
  EXPECT_EQ(vpHSlamImageSource::detectFormat(seq + "/mav0"), vpHSlamImageSource::formatEuroc);
  EXPECT_EQ(vpHSlamImageSource::detectFormat(seq + "/mav0/cam0"), vpHSlamImageSource::formatEuroc);
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(seq);
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatEuroc);
  EXPECT_EQ(source->getFrameCount(), 95);
  EXPECT_EQ(source->getCamera().getModel(), vpHSlamCamera::radialTangential);
  EXPECT_NEAR(source->getFrameRate(), 20., 0.01);

  std::vector<std::uint64_t> stamps;
  for (const std::string &line : readLines(seq + "/mav0/cam0/data.csv")) {
    if (!line.empty() && line[0] != '#') {
      stamps.push_back(std::stoull(line.substr(0, line.find(','))));
    }
  }
  const std::vector<vpHSlamImageSource::Frame> frames = readAll(*source, 752, 480);
  ASSERT_EQ(frames.size(), 95u);
  ASSERT_EQ(stamps.size(), 95u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    // Double holds about 0.24 us at 1.4e9 s.
    EXPECT_NEAR(frames[i].timestamp, static_cast<double>(stamps[i]) / 1e9, 1e-6) << "frame " << i;
  }
  // The cam0 folder itself opens the same sequence.
  EXPECT_EQ(vpHSlamImageSource::create(seq + "/mav0/cam0")->getFrameCount(), 95);
}

TEST(ImageSourceBroken, MissingImageFile)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "7scenes_redkitchen_000-299");
  TempDir tmp;
  const std::string copy = makeRgbdCopy(tmp, seq, 5);
  fs::remove(copy + "/rgb/000002.jpg");
  expectHSlamError([&] { vpHSlamImageSource::create(copy); }, vpHSlamException::fileNotFound, {"000002.jpg"});
}

TEST(ImageSourceBroken, TruncatedList)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "euroc_V1_01_easy_first95");
  TempDir tmp;
  std::vector<std::string> lines;
  const std::string csv = makeEurocCopy(tmp, seq, 4, lines);
  // A download cut in the middle of a line: stamp only, no file name.
  writeText(tmp / "mav0/cam0/data.csv", csv + lines[5].substr(0, 12));
  expectHSlamError([&] { vpHSlamImageSource::create(tmp.path); }, vpHSlamException::parseError, {"data.csv:6"});
}

TEST(ImageSourceBroken, CorruptImage)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "euroc_V1_01_easy_first95");
  TempDir tmp;
  std::vector<std::string> lines;
  makeEurocCopy(tmp, seq, 3, lines);
  const std::string corruptName = lines[3].substr(lines[3].find(',') + 1);
  writeText(tmp / ("mav0/cam0/data/" + corruptName), std::string(4096, '\x5a') + "not a png");
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(tmp.path);
  ASSERT_EQ(source->getFrameCount(), 3);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  EXPECT_TRUE(source->acquire(I, frame));
  EXPECT_TRUE(source->acquire(I, frame));
  expectHSlamError([&] { source->acquire(I, frame); }, vpHSlamException::fileUnreadable, {corruptName});
}

TEST(ImageSourceBroken, NonIncreasingTimestamps)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "7scenes_redkitchen_000-299");
  TempDir tmp;
  const std::string copy = makeRgbdCopy(tmp, seq, 4);
  writeText(copy + "/rgb.txt", "# timestamp filename\n0.0 rgb/000000.jpg\n0.066667 rgb/000001.jpg\n"
                               "0.033333 rgb/000002.jpg\n0.1 rgb/000003.jpg\n");
  expectHSlamError([&] { vpHSlamImageSource::create(copy); }, vpHSlamException::invalidTimestamps, {"rgb.txt:4"});
}

TEST(ImageSourceBroken, KittiTimesAndImagesDiffer)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "kitti06_000-050");
  TempDir tmp;
  const std::string copy = tmp / "kitti";
  copyFile(seq + "/calib.txt", copy + "/calib.txt");
  const std::vector<std::string> times = readLines(seq + "/times.txt");
  std::ostringstream list;
  for (int i = 0; i < 5; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "image_0/%06d.png", i);
    copyFile(seq + "/" + name, copy + "/" + name);
    if (i < 4) {
      list << times[static_cast<std::size_t>(i)] << "\n";
    }
  }
  writeText(copy + "/times.txt", list.str());
  expectHSlamError([&] { vpHSlamImageSource::create(copy); }, vpHSlamException::invalidTimestamps, {"times.txt"});
  // The other way round: a time without its image names the missing file.
  list << times[4] << "\n" << times[5] << "\n";
  writeText(copy + "/times.txt", list.str());
  expectHSlamError([&] { vpHSlamImageSource::create(copy); }, vpHSlamException::fileNotFound, {"000005.png"});
}

TEST(ImageSourceBroken, ImageSizeDiffersFromCalibration)
{
  HSLAM_REQUIRE_SHARED_DATA(seq, "7scenes_redkitchen_000-299");
  TempDir tmp;
  const std::string copy = makeRgbdCopy(tmp, seq, 2);
  writeText(copy + "/camera.txt", "Pinhole 262.5 262.5 160 120 0\n320 240\nnone\n320 240\n");
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(copy);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  expectHSlamError([&] { source->acquire(I, frame); }, vpHSlamException::invalidImage, {"000000.jpg"});
}

TEST(ImageSourceSynthetic, TumMonoExposureAndPhotometricCalibration)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, 4);
  EXPECT_EQ(vpHSlamImageSource::detectFormat(dir), vpHSlamImageSource::formatTumMono);
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatTumMono);
  EXPECT_TRUE(source->getPhotometricCalibration().hasResponse());
  EXPECT_FALSE(source->getPhotometricCalibration().hasVignette());
  ASSERT_EQ(source->getPhotometricCalibration().getInverseResponse().size(), 256u);
  EXPECT_NEAR(source->getPhotometricCalibration().getInverseResponse()[128], 255. * std::pow(128. / 255., 1.2), 1e-3);
  const std::vector<vpHSlamImageSource::Frame> frames = readAll(*source, 64, 48);
  ASSERT_EQ(frames.size(), 4u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_NEAR(frames[i].timestamp, 100. + 0.05 * static_cast<double>(i), 1e-12);
    EXPECT_NEAR(frames[i].exposure, 5. + 2.5 * static_cast<double>(i), 1e-12);
  }
  EXPECT_NEAR(source->getFrameRate(), 20., 1e-6);

  // A vignette beside it is loaded too.
  vpImage<unsigned char> V(48, 64, 200);
  V[24][32] = 255;
  vpImageIo::write(V, dir + "/vignette.png");
  EXPECT_TRUE(vpHSlamImageSource::create(dir)->getPhotometricCalibration().hasVignette());
}

TEST(ImageSourceSynthetic, TumMonoTimesAndImagesDiffer)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, 4);
  fs::remove(dir + "/images/00003.png");
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::invalidTimestamps, {"times.txt"});
}

TEST(ImageSourceSynthetic, ImageFolderAndPattern)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, 5);
  const std::string images = dir + "/images";
  vpHSlamImageSource::Options options;
  options.frameRate = 20.;
  // No camera file beside the images and none given: an error that says so.
  expectHSlamError([&] { vpHSlamImageSource::create(images, options); }, vpHSlamException::fileNotFound, {"camera"});

  options.cameraFile = dir + "/camera.txt";
  EXPECT_EQ(vpHSlamImageSource::detectFormat(images), vpHSlamImageSource::formatImages);
  std::unique_ptr<vpHSlamImageSource> folder = vpHSlamImageSource::create(images, options);
  EXPECT_EQ(folder->getFormat(), vpHSlamImageSource::formatImages);
  std::vector<vpHSlamImageSource::Frame> frames = readAll(*folder, 64, 48);
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_NEAR(frames[3].timestamp, 3. / 20., 1e-12);
  EXPECT_NE(frames[3].name.find("00003.png"), std::string::npos);

  options.startFrame = 1;
  options.maxFrames = 3;
  std::unique_ptr<vpHSlamImageSource> pattern = vpHSlamImageSource::create(images + "/%05d.png", options);
  EXPECT_EQ(pattern->getFormat(), vpHSlamImageSource::formatImages);
  frames = readAll(*pattern, 64, 48);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_NEAR(frames[0].timestamp, 1. / 20., 1e-12);
  EXPECT_NE(frames[2].name.find("00003.png"), std::string::npos);

  // A corrupt file in a folder is reported, not skipped.
  writeText(images + "/00002.png", "garbage");
  options.startFrame = 0;
  options.maxFrames = 0;
  std::unique_ptr<vpHSlamImageSource> broken = vpHSlamImageSource::create(images, options);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  EXPECT_TRUE(broken->acquire(I, frame));
  EXPECT_TRUE(broken->acquire(I, frame));
  expectHSlamError([&] { broken->acquire(I, frame); }, vpHSlamException::fileUnreadable, {"00002.png"});
}

TEST(ImageSourceSynthetic, VideoFile)
{
  TempDir tmp;
  const std::string video = tmp / "clip.avi";
  const unsigned int frameCount = 6;
  {
    vpVideoWriter writer;
    // Motion-JPEG in AVI: encoded by OpenCV itself, no external codec needed.
    writer.setCodec(cv::VideoWriter::fourcc('M', 'J', 'P', 'G'));
    writer.setFramerate(25.);
    writer.setFileName(video);
    vpImage<unsigned char> I(48, 64, 0);
    writer.open(I);
    for (unsigned int i = 0; i < frameCount; ++i) {
      I = static_cast<unsigned char>(20 + 40 * i);
      writer.saveFrame(I);
    }
    writer.close();
  }
  ASSERT_TRUE(fs::exists(video));
  EXPECT_EQ(vpHSlamImageSource::detectFormat(video), vpHSlamImageSource::formatVideo);
  writeText(tmp / "camera.txt", "Pinhole 50 50 31.5 23.5 0\n64 48\nnone\n64 48\n");

  vpHSlamImageSource::Options options;
  options.frameRate = 25.;
  options.startFrame = 1;
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(video, options);
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatVideo);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  std::vector<double> stamps;
  std::vector<double> means;
  while (source->acquire(I, frame)) {
    ASSERT_EQ(I.getWidth(), 64u);
    ASSERT_EQ(I.getHeight(), 48u);
    stamps.push_back(frame.timestamp);
    means.push_back(I.getMeanValue());
  }
  ASSERT_EQ(stamps.size(), frameCount - 1);
  for (std::size_t k = 0; k < stamps.size(); ++k) {
    EXPECT_NEAR(stamps[k], static_cast<double>(k + 1) / 25., 1e-12);
    // Frame k+1 was written with grey level 20 + 40 (k+1); JPEG keeps a flat image within a few levels.
    EXPECT_NEAR(means[k], 20. + 40. * static_cast<double>(k + 1), 3.) << "frame " << k + 1;
  }

  // A calibration of another size is reported at the first frame.
  writeText(tmp / "camera.txt", "Pinhole 50 50 31.5 23.5 0\n640 480\nnone\n640 480\n");
  options.startFrame = 0;
  std::unique_ptr<vpHSlamImageSource> wrong = vpHSlamImageSource::create(video, options);
  expectHSlamError([&] { wrong->acquire(I, frame); }, vpHSlamException::invalidImage, {"clip.avi"});
}

TEST(ImageSourceSynthetic, TumViExposuresFromDsoTimes)
{
  TempDir tmp;
  const std::string cam = tmp / "seq/mav0/cam0";
  writeText(cam + "/sensor.yaml",
            "%YAML:1.0\nsensor_type: camera\nrate_hz: 20\nresolution: [64, 48]\n"
            "camera_model: pinhole\nintrinsics: [50.0, 50.0, 31.5, 23.5]\n"
            "distortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n");
  const std::uint64_t t0 = 1520530308199447626ULL, step = 50000000ULL;
  std::ostringstream csv, times;
  csv << "#timestamp [ns],filename\n";
  times << "# timestamp [ns] timestamp [s] exposure [ms]\n";
  for (std::uint64_t i = 0; i < 3; ++i) {
    const std::string stamp = std::to_string(t0 + i * step);
    vpImage<unsigned char> I(48, 64, static_cast<unsigned char>(50 * i));
    fs::create_directories(cam + "/data");
    vpImageIo::write(I, cam + "/data/" + stamp + ".png");
    csv << stamp << "," << stamp << ".png\n";
    times << stamp << " " << std::to_string(static_cast<double>(t0 + i * step) / 1e9) << " " << (4. + i) << "\n";
  }
  writeText(cam + "/data.csv", csv.str());
  writeText(tmp / "seq/dso/cam0/times.txt", times.str());
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(tmp / "seq");
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatEuroc);
  const std::vector<vpHSlamImageSource::Frame> frames = readAll(*source, 64, 48);
  ASSERT_EQ(frames.size(), 3u);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_DOUBLE_EQ(frames[i].exposure, 4. + static_cast<double>(i));
    EXPECT_NEAR(frames[i].timestamp - frames[0].timestamp, 0.05 * static_cast<double>(i), 1e-6);
  }
}
