// Photometric calibration: identity without files, exact irradiance from known G and V (8- and 16-bit vignettes),
// and the error code plus file name for every kind of malformed input.
#include "HSlamTestData.h"
#include "HSlamTestErrors.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamPhotometricCalibration.h>
#include <visp3/io/vpImageIo.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <unistd.h>

using hslam_test::expectHSlamError;

namespace
{
constexpr unsigned int kWidth = 32;
constexpr unsigned int kHeight = 24;
// Float results of G(I) * (1/t) * (1/V): a few roundings of float, far below the 1/256 an 8-bit vignette loses.
constexpr double kRelTol = 1e-6;

//! A non-linear, strictly increasing raw inverse response, on an arbitrary scale (as in real pcalib.txt files).
double rawResponse(int i)
{
  return 12.5 + 3.0 * i + 0.01 * i * i;
}

std::vector<double> rawResponseTable()
{
  std::vector<double> G(256);
  for (int i = 0; i < 256; ++i) {
    G[i] = rawResponse(i);
  }
  return G;
}

//! DSO rescaling to [0, 255], in double.
double rescaledResponse(int i)
{
  return 255.0 * (rawResponse(i) - rawResponse(0)) / (rawResponse(255) - rawResponse(0));
}

//! Test image covering all 256 intensities.
vpImage<unsigned char> makeImage()
{
  vpImage<unsigned char> I(kHeight, kWidth);
  for (unsigned int v = 0; v < kHeight; ++v) {
    for (unsigned int u = 0; u < kWidth; ++u) {
      I[v][u] = static_cast<unsigned char>((u * 7 + v * 13 + u * v) % 256);
    }
  }
  return I;
}

//! 8-bit vignette: falls off from the centre, maximum 255 at one pixel.
unsigned char vignette8(unsigned int u, unsigned int v)
{
  const int du = static_cast<int>(u) - 16, dv = static_cast<int>(v) - 12;
  return static_cast<unsigned char>(255 - (du * du + dv * dv) / 2);
}

//! 16-bit vignette: neighbouring values differ by less than one 8-bit step, maximum 65000.
unsigned short vignette16(unsigned int u, unsigned int v)
{
  const int du = static_cast<int>(u) - 16, dv = static_cast<int>(v) - 12;
  return static_cast<unsigned short>(65000 - 37 * (du * du + dv * dv));
}

class PhotometricCalibrationTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    const ::testing::TestInfo *info = ::testing::UnitTest::GetInstance()->current_test_info();
    m_dir = std::filesystem::temp_directory_path() /
            ("hslam_photometric_" + std::to_string(::getpid()) + "_" + info->name());
    std::filesystem::create_directories(m_dir);
  }
  void TearDown() override
  {
    std::error_code ec;
    std::filesystem::remove_all(m_dir, ec);
  }

  std::string path(const std::string &name) const { return (m_dir / name).string(); }

  std::string writeText(const std::string &name, const std::string &text) const
  {
    std::ofstream(path(name)) << text;
    return path(name);
  }

  std::string writeResponse(const std::string &name, const std::vector<double> &G) const
  {
    std::ostringstream text;
    text.precision(17);
    for (double g : G) {
      text << g << " ";
    }
    text << "\n";
    return writeText(name, text.str());
  }

  std::string writeVignette8(const std::string &name, unsigned int w = kWidth, unsigned int h = kHeight) const
  {
    vpImage<unsigned char> V(h, w);
    for (unsigned int v = 0; v < h; ++v) {
      for (unsigned int u = 0; u < w; ++u) {
        V[v][u] = vignette8(u, v);
      }
    }
    vpImageIo::write(V, path(name));
    return path(name);
  }

  std::string writeVignette16(const std::string &name, int zeroU = -1, int zeroV = -1) const
  {
    cv::Mat V(kHeight, kWidth, CV_16UC1);
    for (unsigned int v = 0; v < kHeight; ++v) {
      for (unsigned int u = 0; u < kWidth; ++u) {
        V.at<unsigned short>(v, u) = vignette16(u, v);
      }
    }
    if (zeroU >= 0) {
      V.at<unsigned short>(zeroV, zeroU) = 0;
    }
    EXPECT_TRUE(cv::imwrite(path(name), V));
    return path(name);
  }

  std::filesystem::path m_dir;
};

//! B must equal G(I) / (t V / Vmax) to float precision at every pixel.
template <typename VignetteFn>
void expectIrradiance(const vpHSlamPhotometricCalibration &calib, double exposure, VignetteFn vignette, double vMax)
{
  const vpImage<unsigned char> I = makeImage();
  vpImage<float> B;
  calib.toIrradiance(I, exposure, B);
  ASSERT_EQ(B.getWidth(), kWidth);
  ASSERT_EQ(B.getHeight(), kHeight);
  double worst = 0.0;
  for (unsigned int v = 0; v < kHeight; ++v) {
    for (unsigned int u = 0; u < kWidth; ++u) {
      const double V = static_cast<double>(vignette(u, v)) / vMax;
      const double expected = rescaledResponse(I[v][u]) / (exposure * V);
      const double err = std::abs(B[v][u] - expected);
      worst = std::max(worst, err / std::max(1.0, std::abs(expected)));
      ASSERT_LE(err, kRelTol * std::max(1.0, std::abs(expected))) << "pixel (" << u << ", " << v << ")";
    }
  }
  ::testing::Test::RecordProperty("worst_relative_error", std::to_string(worst));
}
} // namespace

TEST_F(PhotometricCalibrationTest, EmptyIsIdentity)
{
  vpHSlamPhotometricCalibration calib;
  EXPECT_TRUE(calib.isEmpty());
  EXPECT_FALSE(calib.hasResponse());
  EXPECT_FALSE(calib.hasVignette());
  EXPECT_TRUE(calib.getInverseResponse().empty());
  EXPECT_EQ(calib.getStatus(), "photometric calibration: none (affine brightness estimated)");

  calib.load("", "", kWidth, kHeight); // both parts absent is valid
  EXPECT_TRUE(calib.isEmpty());

  const vpImage<unsigned char> I = makeImage();
  vpImage<float> B;
  for (double unknownExposure : {0.0, -3.0, std::numeric_limits<double>::quiet_NaN()}) {
    calib.toIrradiance(I, unknownExposure, B);
    for (unsigned int k = 0; k < I.getSize(); ++k) {
      ASSERT_EQ(B.bitmap[k], static_cast<float>(I.bitmap[k])) << "exposure " << unknownExposure;
    }
  }
  // A known exposure still applies (linear response): halving is exact in float.
  calib.toIrradiance(I, 2.0, B);
  for (unsigned int k = 0; k < I.getSize(); ++k) {
    ASSERT_EQ(B.bitmap[k], 0.5f * I.bitmap[k]);
  }
}

TEST_F(PhotometricCalibrationTest, ResponseIsRescaledToDsoRange)
{
  vpHSlamPhotometricCalibration calib;
  calib.load(writeResponse("pcalib.txt", rawResponseTable()), "", 0, 0);
  EXPECT_TRUE(calib.hasResponse());
  EXPECT_FALSE(calib.hasVignette());
  EXPECT_FALSE(calib.isEmpty());
  const std::vector<float> &G = calib.getInverseResponse();
  ASSERT_EQ(G.size(), 256u);
  EXPECT_EQ(G[0], 0.0f);
  EXPECT_FLOAT_EQ(G[255], 255.0f);
  for (int i = 0; i < 256; ++i) {
    EXPECT_NEAR(G[i], rescaledResponse(i), 1e-4) << "G(" << i << ")";
  }
  EXPECT_NE(calib.getStatus().find(path("pcalib.txt")), std::string::npos) << calib.getStatus();
}

TEST_F(PhotometricCalibrationTest, ResponseOverSeveralLinesWithFlatStepsIsAccepted)
{
  std::vector<double> G = rawResponseTable();
  G[10] = G[9]; // non-decreasing, not strictly increasing: accepted
  std::ostringstream text;
  text.precision(17);
  for (int i = 0; i < 256; ++i) {
    text << G[i] << ((i % 16 == 15) ? "\n" : "\t");
  }
  vpHSlamPhotometricCalibration calib;
  calib.load(writeText("pcalib.txt", text.str()), "", 0, 0);
  ASSERT_TRUE(calib.hasResponse());
  EXPECT_EQ(calib.getInverseResponse()[10], calib.getInverseResponse()[9]);
}

TEST_F(PhotometricCalibrationTest, IrradianceWith8BitVignette)
{
  vpHSlamPhotometricCalibration calib;
  calib.load(writeResponse("pcalib.txt", rawResponseTable()), writeVignette8("vignette.png"), kWidth, kHeight);
  EXPECT_TRUE(calib.hasResponse());
  EXPECT_TRUE(calib.hasVignette());
  EXPECT_NE(calib.getStatus().find("vignette.png"), std::string::npos) << calib.getStatus();
  expectIrradiance(calib, 4.0, vignette8, 255.0);
  expectIrradiance(calib, 0.37, vignette8, 255.0);
}

TEST_F(PhotometricCalibrationTest, IrradianceWith16BitVignetteKeepsFullPrecision)
{
  vpHSlamPhotometricCalibration calib;
  calib.load(writeResponse("pcalib.txt", rawResponseTable()), writeVignette16("vignette16.png"), kWidth, kHeight);
  ASSERT_TRUE(calib.hasVignette());
  // An 8-bit reduction of this vignette would be off by up to 1/256 relative, 4000 times the tolerance.
  expectIrradiance(calib, 12.5, vignette16, 65000.0);
}

TEST_F(PhotometricCalibrationTest, VignetteOnlyUsesLinearResponse)
{
  vpHSlamPhotometricCalibration calib;
  calib.load("", writeVignette8("vignette.png"), kWidth, kHeight);
  EXPECT_FALSE(calib.hasResponse());
  EXPECT_TRUE(calib.hasVignette());
  const vpImage<unsigned char> I = makeImage();
  vpImage<float> B;
  calib.toIrradiance(I, 1.0, B);
  for (unsigned int v = 0; v < kHeight; ++v) {
    for (unsigned int u = 0; u < kWidth; ++u) {
      const double expected = I[v][u] * 255.0 / vignette8(u, v);
      ASSERT_NEAR(B[v][u], expected, kRelTol * std::max(1.0, expected));
    }
  }
}

TEST_F(PhotometricCalibrationTest, SettersMatchFiles)
{
  vpHSlamPhotometricCalibration calib;
  calib.setInverseResponse(rawResponseTable());
  vpImage<float> V(kHeight, kWidth);
  for (unsigned int v = 0; v < kHeight; ++v) {
    for (unsigned int u = 0; u < kWidth; ++u) {
      V[v][u] = 0.5f * vignette8(u, v); // any scale: normalised to a maximum of 1
    }
  }
  calib.setVignette(V);
  EXPECT_NE(calib.getStatus().find("set directly"), std::string::npos) << calib.getStatus();
  expectIrradiance(calib, 3.0, vignette8, 255.0);
}

TEST_F(PhotometricCalibrationTest, OutputBufferIsReusedAndWrongSizeIsRejected)
{
  vpHSlamPhotometricCalibration calib;
  calib.load("", writeVignette8("vignette.png"), kWidth, kHeight);
  const vpImage<unsigned char> I = makeImage();
  vpImage<float> B(kHeight, kWidth);
  const float *before = B.bitmap;
  calib.toIrradiance(I, 1.0, B);
  EXPECT_EQ(B.bitmap, before) << "B was reallocated although it had the right size";

  const vpImage<unsigned char> small(kHeight / 2, kWidth / 2, 100);
  expectHSlamError([&] { calib.toIrradiance(small, 1.0, B); }, vpHSlamException::invalidImage, {"16x12", "32x24"});
}

TEST_F(PhotometricCalibrationTest, MalformedResponseFiles)
{
  vpHSlamPhotometricCalibration calib;
  const std::string missing = path("no_such_pcalib.txt");
  expectHSlamError([&] { calib.load(missing, "", 0, 0); }, vpHSlamException::fileNotFound, {missing});

  std::vector<double> G = rawResponseTable();
  G.pop_back();
  const std::string tooFew = writeResponse("few.txt", G);
  expectHSlamError([&] { calib.load(tooFew, "", 0, 0); }, vpHSlamException::invalidCalibration, {tooFew, "found 255"});

  G = rawResponseTable();
  G.push_back(2000.0);
  const std::string tooMany = writeResponse("many.txt", G);
  expectHSlamError([&] { calib.load(tooMany, "", 0, 0); }, vpHSlamException::invalidCalibration,
                   {tooMany, "found 257"});

  G = rawResponseTable();
  G[100] = G[99] - 1.0;
  const std::string decreasing = writeResponse("decreasing.txt", G);
  expectHSlamError([&] { calib.load(decreasing, "", 0, 0); }, vpHSlamException::invalidCalibration,
                   {decreasing, "G(100)", "non-decreasing"});

  G = rawResponseTable();
  G[42] = std::numeric_limits<double>::quiet_NaN();
  const std::string withNan = writeResponse("nan.txt", G);
  expectHSlamError([&] { calib.load(withNan, "", 0, 0); }, vpHSlamException::invalidCalibration, {withNan, "G(42)"});

  const std::string constant = writeResponse("constant.txt", std::vector<double>(256, 7.0));
  expectHSlamError([&] { calib.load(constant, "", 0, 0); }, vpHSlamException::invalidCalibration,
                   {constant, "constant"});

  const std::string garbage = writeText("garbage.txt", "0 1 2\n3 four 5\n");
  expectHSlamError([&] { calib.load(garbage, "", 0, 0); }, vpHSlamException::parseError, {garbage + ":2:", "'four'"});

  const std::string empty = writeText("empty.txt", "");
  expectHSlamError([&] { calib.load(empty, "", 0, 0); }, vpHSlamException::invalidCalibration, {empty, "found 0"});

  expectHSlamError([&] { calib.setInverseResponse(std::vector<double>(10, 1.0)); },
                   vpHSlamException::invalidCalibration, {"setInverseResponse", "found 10"});
  EXPECT_TRUE(calib.isEmpty()) << "a failed load or set must not leave a partial calibration";
}

TEST_F(PhotometricCalibrationTest, MalformedVignetteFiles)
{
  vpHSlamPhotometricCalibration calib;
  const std::string missing = path("no_such_vignette.png");
  expectHSlamError([&] { calib.load("", missing, kWidth, kHeight); }, vpHSlamException::fileNotFound, {missing});

  const std::string wrongSize = writeVignette8("wrong_size.png", kWidth + 1, kHeight);
  expectHSlamError([&] { calib.load("", wrongSize, kWidth, kHeight); }, vpHSlamException::invalidCalibration,
                   {wrongSize, "33x24", "expected 32x24"});

  vpImage<unsigned char> V8(kHeight, kWidth, 200);
  V8[2][3] = 0;
  const std::string zero8 = path("zero8.png");
  vpImageIo::write(V8, zero8);
  expectHSlamError([&] { calib.load("", zero8, kWidth, kHeight); }, vpHSlamException::invalidCalibration,
                   {zero8, "x=3, y=2"});

  const std::string zero16 = writeVignette16("zero16.png", 5, 7);
  expectHSlamError([&] { calib.load("", zero16, kWidth, kHeight); }, vpHSlamException::invalidCalibration,
                   {zero16, "x=5, y=7"});

  const std::string corrupt = writeText("corrupt.png", "this is not a PNG file\n");
  expectHSlamError([&] { calib.load("", corrupt, kWidth, kHeight); }, vpHSlamException::fileUnreadable, {corrupt});

  vpImage<float> negative(kHeight, kWidth, 1.0f);
  negative[0][1] = -0.5f;
  expectHSlamError([&] { calib.setVignette(negative); }, vpHSlamException::invalidCalibration,
                   {"setVignette", "x=1, y=0"});
}

TEST_F(PhotometricCalibrationTest, FailedLoadKeepsPreviousCalibration)
{
  vpHSlamPhotometricCalibration calib;
  const std::string good = writeResponse("pcalib.txt", rawResponseTable());
  const std::string vignette = writeVignette8("vignette.png");
  calib.load(good, vignette, kWidth, kHeight);
  const std::string status = calib.getStatus();

  // A valid response with an invalid vignette: nothing of the new load is kept.
  const std::string missing = path("missing.png");
  expectHSlamError([&] { calib.load(good, missing, kWidth, kHeight); }, vpHSlamException::fileNotFound, {missing});
  EXPECT_EQ(calib.getStatus(), status);
  expectIrradiance(calib, 2.0, vignette8, 255.0);
}
