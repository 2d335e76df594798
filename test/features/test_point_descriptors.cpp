// Oriented ORB descriptors at chosen pixels: deterministic, stable when the image rolls, distinct between
// different places, none too close to the border.
#include "HSlamTestData.h"

#include "features/PointDescriptors.h"

#include <visp3/io/vpImageIo.h>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <random>

namespace
{
vpImage<unsigned char> toVisp(const cv::Mat &m)
{
  vpImage<unsigned char> I(static_cast<unsigned int>(m.rows), static_cast<unsigned int>(m.cols));
  for (int r = 0; r < m.rows; ++r) {
    std::copy(m.ptr<unsigned char>(r), m.ptr<unsigned char>(r) + m.cols, I[static_cast<unsigned int>(r)]);
  }
  return I;
}

TEST(PointDescriptors, StableUnderInPlaneRotationAndDeterministic)
{
  const std::string images = hslam_test::vispImagesDir();
  if (images.empty()) {
    GTEST_SKIP() << "visp-images-data not installed";
  }
  vpImage<unsigned char> I;
  vpImageIo::read(I, images + "/Klimt/Klimt.png");
  const cv::Mat src(static_cast<int>(I.getHeight()), static_cast<int>(I.getWidth()), CV_8UC1, I.bitmap);
  // Corners AND plain gradient pixels: descriptor sharing describes both.
  std::vector<cv::KeyPoint> fast;
  cv::FAST(src, fast, 20, true);
  std::mt19937 rng(1);
  std::shuffle(fast.begin(), fast.end(), rng);
  std::vector<cv::Point2f> pixels;
  for (std::size_t i = 0; i < fast.size() && pixels.size() < 400; ++i) {
    pixels.push_back(fast[i].pt);
  }
  const cv::Point2f centre(0.5f * (src.cols - 1), 0.5f * (src.rows - 1));
  for (double degrees : {0., 25., 90.}) {
    const cv::Mat A = cv::getRotationMatrix2D(centre, degrees, 1.0);
    cv::Mat rotated;
    cv::warpAffine(src, rotated, A, src.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    const vpImage<unsigned char> J = toVisp(rotated);
    std::vector<cv::Point2f> moved;
    for (const cv::Point2f &p : pixels) {
      moved.emplace_back(static_cast<float>(A.at<double>(0, 0) * p.x + A.at<double>(0, 1) * p.y + A.at<double>(0, 2)),
                         static_cast<float>(A.at<double>(1, 0) * p.x + A.at<double>(1, 1) * p.y + A.at<double>(1, 2)));
    }
    hslam::PointDescriptors describer;
    std::vector<hslam::OrbDescriptor> d1, d2;
    std::vector<bool> v1, v2;
    describer.compute(I, pixels, d1, v1);
    describer.compute(J, moved, d2, v2);
    std::vector<int> same, other;
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      if (v1[i] && v2[i]) {
        same.push_back(hslam::hammingDistance(d1[i], d2[i]));
        other.push_back(hslam::hammingDistance(d1[i], d2[(i + 1) % pixels.size()]));
      }
    }
    ASSERT_GT(same.size(), 150u) << degrees << " degrees";
    std::sort(same.begin(), same.end());
    std::sort(other.begin(), other.end());
    const int medianSame = same[same.size() / 2], medianOther = other[other.size() / 2];
    if (degrees == 0.) {
      EXPECT_EQ(medianSame, 0); // the same image: identical descriptors
      EXPECT_EQ(same.back(), 0);
    } else {
      EXPECT_LT(medianSame, 50) << degrees << " degrees"; // of 256 bits
    }
    EXPECT_GT(medianOther, 90) << degrees << " degrees"; // unrelated pixels: about half the bits differ
  }
}

TEST(PointDescriptors, NoDescriptorTooCloseToTheBorder)
{
  vpImage<unsigned char> I(100, 120, 0);
  for (unsigned int v = 0; v < I.getHeight(); ++v) {
    for (unsigned int u = 0; u < I.getWidth(); ++u) {
      I[v][u] = static_cast<unsigned char>((u * 7 + v * 13) % 251);
    }
  }
  hslam::PointDescriptors describer;
  std::vector<hslam::OrbDescriptor> d;
  std::vector<bool> valid;
  std::vector<float> angles;
  describer.compute(I, {{5.f, 50.f}, {60.f, 50.f}, {60.f, 95.f}, {19.f, 19.f}, {20.f, 20.f}}, d, valid, &angles);
  EXPECT_EQ(valid, (std::vector<bool>{false, true, false, false, true}));
  EXPECT_GE(angles[1], 0.f);
  EXPECT_LT(angles[1], 360.f);
  EXPECT_EQ(d[0], hslam::OrbDescriptor());
}
} // namespace

TEST(PointDescriptors, HammingDistanceCountsEveryDifferingBit)
{
  // Against a bit-by-bit count: the inline popcount (baseline x86-64 has no popcnt instruction) must be exact.
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 2000; ++trial) {
    hslam::OrbDescriptor a, b;
    for (int w = 0; w < 4; ++w) {
      a.words[static_cast<size_t>(w)] = rng();
      // Sparse and dense differences both: every fourth trial differs in all bits of a word.
      b.words[static_cast<size_t>(w)] = trial % 4 == 0 ? ~a.words[static_cast<size_t>(w)] : rng();
    }
    int expected = 0;
    for (int bit = 0; bit < 256; ++bit) {
      expected += a.bit(bit) != b.bit(bit) ? 1 : 0;
    }
    ASSERT_EQ(hslam::hammingDistance(a, b), expected) << "trial " << trial;
  }
  EXPECT_EQ(hslam::popcount64(0), 0);
  EXPECT_EQ(hslam::popcount64(~0ull), 64);
  EXPECT_EQ(hslam::popcount64(0x8000000000000001ull), 2);
}
