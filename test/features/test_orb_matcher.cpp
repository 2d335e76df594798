// Guided ORB matching: exact synthetic correspondences with distractors and rotation outliers, and a real
// photograph rotated in the image plane (ORB descriptors must survive the rotation and be deterministic).
#include "HSlamTestData.h"

#include "features/OrbExtractor.h"
#include "features/OrbMatcher.h"

#include <visp3/core/vpImageTools.h>
#include <visp3/io/vpImageIo.h>

#include "HSlamTestDescriptors.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>

namespace
{
using hslam::FrameKeypoint;
using hslam::OrbDescriptor;
using hslam::ProjectedPoint;

using hslam_test::flipBits;
using hslam_test::randomDescriptor;

TEST(OrbMatcher, FindsTheTrueKeypointsAmongDistractorsAndDropsRotationOutliers)
{
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> u(20.f, 620.f), v(20.f, 460.f), angle(0.f, 360.f), jitter(-1.f, 1.f);
  std::vector<ProjectedPoint> points;
  std::vector<FrameKeypoint> keypoints;
  std::vector<int> truth; // keypoint of each point, -1 for points whose keypoint rotates inconsistently
  for (int i = 0; i < 400; ++i) {
    ProjectedPoint p;
    p.u = u(rng);
    p.v = v(rng);
    p.angleDeg = angle(rng);
    p.descriptor = randomDescriptor(rng);
    const bool rotationOutlier = i % 20 == 0;
    FrameKeypoint k;
    k.u = p.u + 2.f * jitter(rng);
    k.v = p.v + 2.f * jitter(rng);
    k.angleDeg = rotationOutlier ? p.angleDeg + 180.f : p.angleDeg + 25.f + 3.f * jitter(rng); // the frame rolled 25°
    k.descriptor = flipBits(p.descriptor, 12, rng);
    truth.push_back(rotationOutlier ? -1 : static_cast<int>(keypoints.size()));
    keypoints.push_back(k);
    points.push_back(p);
  }
  for (int i = 0; i < 800; ++i) { // distractors
    FrameKeypoint k;
    k.u = u(rng);
    k.v = v(rng);
    k.angleDeg = angle(rng);
    k.descriptor = randomDescriptor(rng);
    keypoints.push_back(k);
  }
  const hslam::OrbMatcher matcher(keypoints, 640, 480);
  const std::vector<hslam::OrbMatch> matches = matcher.matchProjected(points);
  int correct = 0, wrong = 0, rotationOutliersKept = 0;
  for (const hslam::OrbMatch &m : matches) {
    const int expected = truth[static_cast<std::size_t>(m.point)];
    if (expected < 0) {
      ++rotationOutliersKept;
    } else if (m.keypoint == expected) {
      ++correct;
    } else {
      ++wrong;
    }
  }
  EXPECT_GE(correct, 370); // 380 consistent points
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(rotationOutliersKept, 0);
  for (std::size_t i = 1; i < matches.size(); ++i) {
    EXPECT_LT(matches[i - 1].point, matches[i].point);
  }

  // A radius too small for the 2-px jitter finds fewer; a prediction off by 40 px finds nothing.
  EXPECT_LT(matcher.matchProjected(points, 0.5f).size(), matches.size() / 2);
  std::vector<ProjectedPoint> shifted = points;
  for (ProjectedPoint &p : shifted) {
    p.u += 40.f;
  }
  EXPECT_LT(matcher.matchProjected(shifted).size(), 10u);
}

TEST(OrbMatcher, DescriptorsAreDeterministicAndSurviveAnInPlaneRotation)
{
  const std::string images = hslam_test::vispImagesDir();
  if (images.empty()) {
    GTEST_SKIP() << "visp-images-data not installed";
  }
  vpImage<unsigned char> I;
  vpImageIo::read(I, images + "/Klimt/Klimt.png");
  const cv::Mat src(static_cast<int>(I.getHeight()), static_cast<int>(I.getWidth()), CV_8UC1, I.bitmap);
  const double degrees = 30.;
  const cv::Point2f centre(0.5f * (src.cols - 1), 0.5f * (src.rows - 1));
  const cv::Mat A = cv::getRotationMatrix2D(centre, degrees, 1.0); // counter-clockwise on screen
  cv::Mat rotated;
  cv::warpAffine(src, rotated, A, src.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
  vpImage<unsigned char> J(static_cast<unsigned int>(rotated.rows), static_cast<unsigned int>(rotated.cols));
  std::copy(rotated.data, rotated.data + rotated.total(), J.bitmap);

  hslam::OrbExtractor extractor;
  std::vector<cv::KeyPoint> kp1, kp1again, kp2;
  cv::Mat d1, d1again, d2;
  extractor.extract(I, kp1, d1);
  extractor.extract(I, kp1again, d1again);
  ASSERT_EQ(kp1.size(), kp1again.size());
  EXPECT_EQ(cv::norm(d1, d1again, cv::NORM_HAMMING), 0.);
  extractor.extract(J, kp2, d2);
  ASSERT_GT(kp1.size(), 300u);

  std::vector<ProjectedPoint> points;
  const std::vector<OrbDescriptor> desc1 = hslam::descriptorsFromMat(d1), desc2 = hslam::descriptorsFromMat(d2);
  for (std::size_t i = 0; i < kp1.size(); ++i) {
    ProjectedPoint p;
    p.u = static_cast<float>(A.at<double>(0, 0) * kp1[i].pt.x + A.at<double>(0, 1) * kp1[i].pt.y + A.at<double>(0, 2));
    p.v = static_cast<float>(A.at<double>(1, 0) * kp1[i].pt.x + A.at<double>(1, 1) * kp1[i].pt.y + A.at<double>(1, 2));
    p.angleDeg = kp1[i].angle;
    p.descriptor = desc1[i];
    points.push_back(p);
  }
  std::vector<FrameKeypoint> keypoints;
  for (std::size_t i = 0; i < kp2.size(); ++i) {
    keypoints.push_back({kp2[i].pt.x, kp2[i].pt.y, kp2[i].angle, desc2[i]});
  }
  const std::vector<hslam::OrbMatch> matches =
      hslam::OrbMatcher(keypoints, static_cast<int>(J.getWidth()), static_cast<int>(J.getHeight()))
          .matchProjected(points, 4.f);
  int close = 0;
  for (const hslam::OrbMatch &m : matches) {
    const FrameKeypoint &k = keypoints[static_cast<std::size_t>(m.keypoint)];
    const ProjectedPoint &p = points[static_cast<std::size_t>(m.point)];
    close += std::hypot(k.u - p.u, k.v - p.v) < 3.f ? 1 : 0;
  }
  EXPECT_GT(matches.size(), kp1.size() / 4) << "ORB descriptors survive a 30 degree roll";
  EXPECT_GE(close, static_cast<int>(matches.size()) * 95 / 100);
}
} // namespace
