// The module's own image codec (io/ImageCodec.h) against ViSP's vpImageIo::read, which the readers used before:
// the same pixels for every frame of the shared sequences and for generated JPEG, PNG (grey, colour, 16-bit,
// alpha), PGM and PPM files; 16-bit samples kept by decodeGreyAnyDepth; clear errors on bad data.
#include "HSlamTestData.h"

#include "io/ImageCodec.h"
#include "io/SourceFiles.h"

#include <visp3/io/vpImageIo.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>
#include <random>

namespace
{
namespace fs = std::filesystem;

std::vector<unsigned char> encode(const std::string &ext, const cv::Mat &m, const std::vector<int> &params = {})
{
  std::vector<unsigned char> bytes;
  EXPECT_TRUE(cv::imencode(ext, m, bytes, params)) << ext;
  return bytes;
}

//! Number of pixels where our decoding of the file \e path differs from vpImageIo::read's.
int differencesFromViSP(const std::string &path)
{
  vpImage<unsigned char> ref, I;
  vpImageIo::read(ref, path);
  const std::vector<unsigned char> bytes = hslam::io::readFileBytes(path);
  hslam::io::decodeGrey8(bytes.data(), bytes.size(), path, I);
  if (ref.getWidth() != I.getWidth() || ref.getHeight() != I.getHeight()) {
    ADD_FAILURE() << path << ": size differs from vpImageIo's";
    return -1;
  }
  int bad = 0;
  for (unsigned int i = 0; i < ref.getSize(); ++i) {
    bad += ref.bitmap[i] != I.bitmap[i];
  }
  return bad;
}

cv::Mat randomImage(int rows, int cols, int type, unsigned seed)
{
  cv::Mat m(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65536 : 256);
  // Smooth texture as well as noise, so JPEG's colour subsampling has something to do.
  cv::GaussianBlur(m, m, cv::Size(5, 5), 1.5);
  return m;
}

class ImageCodecFiles : public ::testing::Test
{
protected:
  void SetUp() override
  {
    m_dir = fs::temp_directory_path() / ("hslam_codec_" + std::to_string(::getpid()));
    fs::create_directories(m_dir);
  }
  void TearDown() override { fs::remove_all(m_dir); }
  std::string path(const std::string &name) const { return (m_dir / name).string(); }
  fs::path m_dir;
};
} // namespace

TEST_F(ImageCodecFiles, GeneratedFilesDecodeLikeViSP)
{
  const cv::Mat grey = randomImage(61, 83, CV_8UC1, 1);
  const cv::Mat colour = randomImage(61, 83, CV_8UC3, 2);
  cv::Mat bgra;
  cv::cvtColor(colour, bgra, cv::COLOR_BGR2BGRA);
  const cv::Mat grey16 = randomImage(61, 83, CV_16UC1, 3);
  const struct {
    std::string name;
    cv::Mat image;
    std::vector<int> params;
  } cases[] = {{"grey.jpg", grey, {}},
               {"colour.jpg", colour, {}},
               {"progressive.jpg", colour, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
               {"grey.png", grey, {}},
               {"colour.png", colour, {}},
               {"alpha.png", bgra, {}},
               {"grey16.png", grey16, {}},
               {"grey.pgm", grey, {}},
               {"colour.ppm", colour, {}}};
  for (const auto &c : cases) {
    ASSERT_TRUE(cv::imwrite(path(c.name), c.image, c.params)) << c.name;
    EXPECT_EQ(differencesFromViSP(path(c.name)), 0) << c.name;
  }
  // Plain (ASCII) Netpbm files, which ViSP does not read: the same pixels as the binary ones.
  ASSERT_TRUE(cv::imwrite(path("plain.pgm"), grey, {cv::IMWRITE_PXM_BINARY, 0}));
  ASSERT_TRUE(cv::imwrite(path("plain.ppm"), colour, {cv::IMWRITE_PXM_BINARY, 0}));
  vpImage<unsigned char> binary, plain;
  hslam::io::readGreyImage(path("grey.pgm"), binary);
  hslam::io::readGreyImage(path("plain.pgm"), plain);
  EXPECT_TRUE(binary == plain);
  hslam::io::readGreyImage(path("colour.ppm"), binary);
  hslam::io::readGreyImage(path("plain.ppm"), plain);
  EXPECT_TRUE(binary == plain);
}

TEST(ImageCodec, SixteenBitSamplesAreKept)
{
  const cv::Mat grey16 = randomImage(37, 45, CV_16UC1, 5);
  for (const std::string ext : {".png", ".pgm"}) {
    const std::vector<unsigned char> bytes = encode(ext, grey16);
    std::vector<std::uint16_t> samples;
    unsigned int w = 0, h = 0;
    int depth = 0;
    hslam::io::decodeGreyAnyDepth(bytes.data(), bytes.size(), ext, samples, w, h, depth);
    ASSERT_EQ(w, 45u) << ext;
    ASSERT_EQ(h, 37u) << ext;
    EXPECT_EQ(depth, 16) << ext;
    int bad = 0;
    for (int y = 0; y < grey16.rows; ++y) {
      for (int x = 0; x < grey16.cols; ++x) {
        bad += samples[static_cast<size_t>(y * grey16.cols + x)] != grey16.at<std::uint16_t>(y, x);
      }
    }
    EXPECT_EQ(bad, 0) << ext;
  }
  const cv::Mat grey = randomImage(9, 7, CV_8UC1, 6);
  const std::vector<unsigned char> bytes = encode(".png", grey);
  std::vector<std::uint16_t> samples;
  unsigned int w = 0, h = 0;
  int depth = 0;
  hslam::io::decodeGreyAnyDepth(bytes.data(), bytes.size(), "grey.png", samples, w, h, depth);
  EXPECT_EQ(depth, 8);
  EXPECT_EQ(samples[10], grey.at<unsigned char>(1, 3));
}

TEST(ImageCodec, BadDataGivesClearErrors)
{
  const cv::Mat grey = randomImage(40, 50, CV_8UC1, 7);
  vpImage<unsigned char> I;
  const auto expectError = [&I](const std::vector<unsigned char> &bytes, const std::string &needle) {
    try {
      hslam::io::decodeGrey8(bytes.data(), bytes.size(), "frame", I);
      ADD_FAILURE() << "no error for data expected to fail with '" << needle << "'";
    } catch (const vpHSlamException &e) {
      EXPECT_NE(e.getStringMessage().find("'frame'"), std::string::npos) << e.getStringMessage();
      EXPECT_NE(e.getStringMessage().find(needle), std::string::npos) << e.getStringMessage();
    }
  };
  expectError({}, "empty");
  expectError({'B', 'M', 0, 0, 0, 0}, "convert");
  std::vector<unsigned char> png = encode(".png", grey);
  png.resize(png.size() / 2);
  expectError(png, "truncated");
  std::vector<unsigned char> pgm = encode(".pgm", grey);
  pgm.resize(pgm.size() - 10);
  expectError(pgm, "truncated");
  expectError({'P', '5', '\n', 'x'}, "header");
  const std::vector<unsigned char> jpg = encode(".jpg", grey);
  expectError(std::vector<unsigned char>(jpg.begin(), jpg.begin() + 4), "cannot decode"); // libjpeg's own message
  // Headers asking for more than the data holds, or than any camera gives, are refused before anything is allocated
  // (a fuzzer's plain PGM of 22554 x 56196 pixels once made us allocate 2.5 GB).
  const auto bytesOf = [](const std::string &text) { return std::vector<unsigned char>(text.begin(), text.end()); };
  expectError(bytesOf("P2\n22554 56196 255\n1 2 3\n"), "out of range");
  expectError(bytesOf("P2\n4000 4000 255\n1 2 3\n"), "ends early");
  expectError(bytesOf("P5\n8000 8000 65535\n" + std::string(64, 'x')), "ends early");
  expectError(encode(".png", cv::Mat::zeros(9000, 9000, CV_8UC1)), "bad image size");
}

TEST_F(ImageCodecFiles, PngWriteRoundTrips)
{
  vpImage<unsigned char> grey(23, 31);
  vpImage<vpRGBa> colour(23, 31);
  for (unsigned int i = 0; i < grey.getSize(); ++i) {
    grey.bitmap[i] = static_cast<unsigned char>(i * 7);
    colour.bitmap[i] = vpRGBa(static_cast<unsigned char>(i), static_cast<unsigned char>(2 * i),
                              static_cast<unsigned char>(3 * i), 255);
  }
  hslam::io::writePng(path("grey.png"), grey);
  hslam::io::writePng(path("colour.png"), colour);
  vpImage<unsigned char> back;
  hslam::io::readGreyImage(path("grey.png"), back);
  EXPECT_TRUE(back == grey);
  const cv::Mat rgb = cv::imread(path("colour.png"), cv::IMREAD_COLOR);
  ASSERT_EQ(rgb.rows, 23);
  EXPECT_EQ(rgb.at<cv::Vec3b>(2, 5), cv::Vec3b(static_cast<unsigned char>(3 * 67), static_cast<unsigned char>(2 * 67),
                                               static_cast<unsigned char>(67))); // BGR in OpenCV
  EXPECT_THROW(hslam::io::writePng(path("missing-folder/x.png"), grey), vpHSlamException);
}

TEST(ImageCodec, SharedSequencesDecodeLikeViSP)
{
  HSLAM_REQUIRE_SHARED_DATA(root, "");
  // Every image of every shared sequence: colour JPEG (TUM RGB-D layout), grey PNG (KITTI, EuRoC).
  int files = 0;
  for (const auto &entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file() || !hslam::io::hasImageExtension(entry.path().string())) {
      continue;
    }
    EXPECT_EQ(differencesFromViSP(entry.path().string()), 0) << entry.path();
    ++files;
  }
  EXPECT_GT(files, 500);
}
