// TUM layouts beyond the plain folders: TUM monoVO's images.zip read in place (stored entries written by the test,
// deflated ones by the zip tool when installed), and the H-SLAM extension of the TUM RGB-D layout (photometric
// calibration and exposures beside rgb.txt) as tutorial-hslam-synthetic writes it.
#include "HSlamTestData.h"
#include "HSlamTestErrors.h"
#include "ImageSourceFixtures.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>
#include <visp3/io/vpImageIo.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using hslam_test::expectHSlamError;
using namespace hslam_test;

namespace
{
const unsigned int kZipFrames = 4;

//! Offset of entry \e name's data in a stored-entry archive written by writeStoredZip().
std::size_t storedEntryDataOffset(const std::vector<unsigned char> &zip, const std::string &name)
{
  const std::string text(zip.begin(), zip.end());
  const std::size_t nameAt = text.find(name); // the local header comes first, its data right after the name
  return nameAt == std::string::npos ? std::string::npos : nameAt + name.size();
}

std::unique_ptr<vpHSlamImageSource> openAndReadFrames(const std::string &dir, unsigned int frames)
{
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  for (unsigned int i = 0; i < frames; ++i) {
    EXPECT_TRUE(source->acquire(I, frame)) << "frame " << i;
  }
  return source;
}
} // namespace

TEST(ImageSourceTumZip, EntriesAreSortedAndDecodedExactly)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kZipFrames);
  std::vector<std::string> names;
  std::vector<ZipEntry> entries = {{"notes.txt", {'h', 'i', '\n'}}, {"sub/", {}}};
  for (unsigned int i = kZipFrames; i-- > 0;) { // stored in reverse order: the reader must sort
    char name[32];
    std::snprintf(name, sizeof(name), "%05u.png", i);
    entries.push_back({name, readBytes(dir + "/images/" + name)});
  }
  fs::remove_all(dir + "/images");
  writeStoredZip(dir + "/images.zip", entries);

  EXPECT_EQ(vpHSlamImageSource::detectFormat(dir), vpHSlamImageSource::formatTumMono);
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatTumMono);
  EXPECT_EQ(source->getFrameCount(), static_cast<int>(kZipFrames));
  EXPECT_TRUE(source->getPhotometricCalibration().hasResponse());
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  for (unsigned int i = 0; i < kZipFrames; ++i) {
    ASSERT_TRUE(source->acquire(I, frame)) << "frame " << i;
    char entry[32];
    std::snprintf(entry, sizeof(entry), "images.zip:%05u.png", i);
    EXPECT_NE(frame.name.find(entry), std::string::npos) << frame.name;
    EXPECT_TRUE(I == patternImage(i)) << "pixels of frame " << i << " differ from the PNG put in the archive";
    EXPECT_NEAR(frame.timestamp, tumMonoTime(i), 1e-12);
    EXPECT_NEAR(frame.exposure, tumMonoExposure(i), 1e-12);
  }
  EXPECT_FALSE(source->acquire(I, frame));
}

TEST(ImageSourceTumZip, StartFrameAndMaxFrames)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kZipFrames);
  zipTumMonoImages(dir);
  vpHSlamImageSource::Options options;
  options.startFrame = 1;
  options.maxFrames = 2;
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir, options);
  const std::vector<vpHSlamImageSource::Frame> frames = readAll(*source, 64, 48);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_NEAR(frames[0].timestamp, tumMonoTime(1), 1e-12);
  EXPECT_NE(frames[1].name.find("images.zip:00002.png"), std::string::npos) << frames[1].name;
}

TEST(ImageSourceTumZip, ImagesFolderWinsOverTheArchive)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kZipFrames);
  writeText(dir + "/images.zip", "not even a zip"); // never opened while images/ exists
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  const std::vector<vpHSlamImageSource::Frame> frames = readAll(*source, 64, 48);
  ASSERT_EQ(frames.size(), kZipFrames);
  EXPECT_EQ(frames[0].name.find("images.zip"), std::string::npos) << frames[0].name;
}

TEST(ImageSourceTumZip, CountDifferentFromTimesIsAnError)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kZipFrames);
  fs::remove(dir + "/images/00003.png");
  zipTumMonoImages(dir);
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::invalidTimestamps,
                   {"times.txt", "images.zip", "4 lines", "3 images"});
}

TEST(ImageSourceTumZip, TruncatedOrGarbageEntryNamesTheEntry)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kZipFrames);
  truncateToHalf(dir + "/images/00002.png");
  writeText(dir + "/images/00003.png", std::string(2048, '\x5a'));
  zipTumMonoImages(dir);
  std::unique_ptr<vpHSlamImageSource> source = openAndReadFrames(dir, 2);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  expectHSlamError([&] { source->acquire(I, frame); }, vpHSlamException::fileUnreadable, {"images.zip:00002.png"});

  vpHSlamImageSource::Options options;
  options.startFrame = 3;
  std::unique_ptr<vpHSlamImageSource> garbage = vpHSlamImageSource::create(dir, options);
  expectHSlamError([&] { garbage->acquire(I, frame); }, vpHSlamException::fileUnreadable, {"images.zip:00003.png"});
}

TEST(ImageSourceTumZip, TruncatedJpegEntryIsNotDecodedSilently)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, 2);
  for (unsigned int i = 0; i < 2; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "%05u", i);
    const std::string stem = dir + "/images/" + name;
    vpImageIo::write(patternImage(i), stem + ".jpg");
    fs::remove(stem + ".png");
  }
  truncateToHalf(dir + "/images/00001.jpg"); // libjpeg alone would fill the missing half with grey
  zipTumMonoImages(dir);
  std::unique_ptr<vpHSlamImageSource> source = openAndReadFrames(dir, 1);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  expectHSlamError([&] { source->acquire(I, frame); }, vpHSlamException::fileUnreadable,
                   {"images.zip:00001.jpg", "truncated"});
}

TEST(ImageSourceTumZip, DamagedEntryDataFailsItsCrc)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kZipFrames);
  const std::size_t pngSize = readBytes(dir + "/images/00001.png").size();
  zipTumMonoImages(dir);
  std::vector<unsigned char> zip = readBytes(dir + "/images.zip");
  const std::size_t data = storedEntryDataOffset(zip, "00001.png");
  ASSERT_NE(data, std::string::npos);
  zip[data + pngSize / 2] ^= 0xFF; // in the middle of the entry's bytes
  writeBytes(dir + "/images.zip", zip);
  std::unique_ptr<vpHSlamImageSource> source = openAndReadFrames(dir, 1);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  expectHSlamError([&] { source->acquire(I, frame); }, vpHSlamException::fileUnreadable, {"images.zip:00001.png"});
}

TEST(ImageSourceTumZip, TruncatedArchiveFailsAtOpen)
{
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kZipFrames);
  zipTumMonoImages(dir);
  truncateToHalf(dir + "/images.zip"); // the central directory is at the end: gone
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::fileUnreadable, {"images.zip"});
}

TEST(ImageSourceTumZip, DeflatedArchiveOfTheZipTool)
{
  if (std::system("zip -v > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "the zip program is not installed; stored entries are covered by the other tests";
  }
  TempDir tmp;
  const std::string dir = makeTumMono(tmp, kZipFrames);
  // -9: deflate even small files; -j: entry names without the folder, as in TUM monoVO's archives.
  const std::string command = "cd '" + dir + "' && zip -q -9 -j images.zip images/*.png";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  fs::remove_all(dir + "/images");
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  for (unsigned int i = 0; i < kZipFrames; ++i) {
    ASSERT_TRUE(source->acquire(I, frame)) << "frame " << i;
    EXPECT_TRUE(I == patternImage(i)) << "frame " << i;
  }
  EXPECT_FALSE(source->acquire(I, frame));
}

namespace
{
//! A small synthetic sequence with every photometric effect, written in \e dir (TUM RGB-D layout).
bool writeSyntheticPhotometricSequence(const std::string &dir, vpHSlamSyntheticScene &scene)
{
  if (hslam_test::vispImagesDir().empty()) {
    return false;
  }
  vpHSlamSyntheticScene::Effects effects;
  effects.vignette = true;
  effects.response = true;
  effects.exposureChanges = true;
  scene.configure(64, 48, 6, 30.0, 2, effects);
  scene.writeSequence(dir);
  return true;
}
} // namespace

TEST(ImageSourceTumRgbdExtension, SyntheticExposuresAndPhotometricCalibration)
{
  TempDir tmp;
  const std::string dir = tmp / "synthetic";
  vpHSlamSyntheticScene scene;
  if (!writeSyntheticPhotometricSequence(dir, scene)) {
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";
  }
  EXPECT_EQ(vpHSlamImageSource::detectFormat(dir), vpHSlamImageSource::formatTumRgbd);
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  EXPECT_EQ(source->getFormat(), vpHSlamImageSource::formatTumRgbd);
  const vpHSlamPhotometricCalibration &photometric = source->getPhotometricCalibration();
  EXPECT_FALSE(photometric.isEmpty());
  EXPECT_TRUE(photometric.hasResponse());
  EXPECT_TRUE(photometric.hasVignette());
  const std::vector<double> inverseResponse = scene.getInverseResponse();
  ASSERT_EQ(photometric.getInverseResponse().size(), inverseResponse.size());
  for (std::size_t k = 0; k < inverseResponse.size(); k += 51) {
    EXPECT_NEAR(photometric.getInverseResponse()[k], inverseResponse[k], 1e-4) << "G^-1(" << k << ")"; // float
  }
  const std::vector<vpHSlamImageSource::Frame> frames = readAll(*source, 64, 48);
  ASSERT_EQ(frames.size(), scene.getFrameCount());
  double lowest = frames[0].exposure, highest = frames[0].exposure;
  for (unsigned int i = 0; i < frames.size(); ++i) {
    EXPECT_NEAR(frames[i].exposure, scene.getExposure(i), 1e-6) << "frame " << i; // written with 6 decimals
    EXPECT_NEAR(frames[i].timestamp, scene.getTimestamp(i), 1e-6) << "frame " << i;
    lowest = std::min(lowest, frames[i].exposure);
    highest = std::max(highest, frames[i].exposure);
  }
  EXPECT_GT(highest - lowest, 0.1) << "--exposure-changes should vary the exposure over 6 frames";
}

TEST(ImageSourceTumRgbdExtension, TimesNotMatchingRgbListIsAnError)
{
  TempDir tmp;
  const std::string dir = tmp / "synthetic";
  vpHSlamSyntheticScene scene;
  if (!writeSyntheticPhotometricSequence(dir, scene)) {
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";
  }
  const std::vector<std::string> times = readLines(dir + "/times.txt");
  ASSERT_EQ(times.size(), 6u);
  std::string text;
  for (std::size_t i = 0; i + 1 < times.size(); ++i) {
    text += times[i] + "\n";
  }
  writeText(dir + "/times.txt", text); // one line short
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::invalidTimestamps,
                   {"times.txt", "5 lines", "6 images"});

  // Frame 3's time shifted by a frame: the lists are out of step from there.
  std::istringstream fields(times[3]);
  std::string id, time, exposure;
  fields >> id >> time >> exposure;
  text.clear();
  for (std::size_t i = 0; i < times.size(); ++i) {
    text += (i == 3 ? id + " " + std::to_string(std::stod(time) + 1. / 30.) + " " + exposure : times[i]) + "\n";
  }
  writeText(dir + "/times.txt", text);
  expectHSlamError([&] { vpHSlamImageSource::create(dir); }, vpHSlamException::invalidTimestamps,
                   {"times.txt:4", "rgb.txt:6"});

  // Without times.txt the sequence still opens, exposures unknown.
  fs::remove(dir + "/times.txt");
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(dir);
  EXPECT_LE(readAll(*source, 64, 48).at(0).exposure, 0.);
  EXPECT_TRUE(source->getPhotometricCalibration().hasVignette());
}
