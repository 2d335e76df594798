// Matching along epipolar lines (mapping/EpipolarMatching.h) on two synthetic frames with exact geometry: it adds
// matches to the brute-force pass, and they are right.
#include "HSlamTestData.h"

#include "features/OrbExtractor.h"
#include "mapping/EpipolarMatching.h"
#include "math/ViSPConversions.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

using namespace hslam;

namespace
{
Eigen::Matrix3d skew(const Eigen::Vector3d &t)
{
  Eigen::Matrix3d S;
  S << 0., -t.z(), t.y(), t.z(), 0., -t.x(), -t.y(), t.x(), 0.;
  return S;
}
} // namespace

TEST(EpipolarMatching, FindsRightMatchesAlongTheTrueEpipolarLines)
{
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found";
  }
  vpHSlamSyntheticScene scene;
  scene.configure(320, 240, 300, 30.0, 1);
  const vpCameraParameters cam = scene.getCameraParameters();
  Eigen::Matrix3d K;
  K << cam.get_px(), 0., cam.get_u0(), 0., cam.get_py(), cam.get_v0(), 0., 0., 1.;
  constexpr unsigned int kSecond = 25;
  vpImage<unsigned char> I0, I1;
  scene.render(0, I0);
  scene.render(kSecond, I1);
  OrbExtractor orb;
  std::vector<cv::KeyPoint> k0, k1;
  cv::Mat d0, d1;
  orb.extract(I0, k0, d0);
  orb.extract(I1, k1, d1);
  const SE3d c1Mc0 = toSE3(scene.getPose(kSecond)).inverse() * toSE3(scene.getPose(0));
  const Eigen::Matrix3d F =
      K.inverse().transpose() * skew(c1Mc0.translation()) * c1Mc0.rotationMatrix() * K.inverse(); // x1^T F x0 = 0
  std::vector<bool> used0(k0.size(), false), used1(k1.size(), false);
  const std::vector<std::pair<int, int>> matches = matchAlongEpipolarLines(F, k0, d0, k1, d1, used0, used1);
  // Right: the first keypoint's scene point, seen from the second camera, lands within a few pixels of its match.
  int right = 0;
  for (const auto &m : matches) {
    const cv::KeyPoint &a = k0[static_cast<size_t>(m.first)], &b = k1[static_cast<size_t>(m.second)];
    const double z = scene.depthAt(a.pt.x, a.pt.y, 0);
    const Eigen::Vector3d X0 = z * (K.inverse() * Eigen::Vector3d(a.pt.x, a.pt.y, 1.));
    const Eigen::Vector3d x1 = K * (c1Mc0 * X0);
    const double error = (x1.head<2>() / x1.z() - Eigen::Vector2d(b.pt.x, b.pt.y)).norm();
    right += error < 3. * std::pow(1.2, b.octave) ? 1 : 0;
    EXPECT_TRUE(used0[static_cast<size_t>(m.first)] && used1[static_cast<size_t>(m.second)]);
  }
  std::printf("[epipolar] %zu and %zu keypoints, %zu matches, %d right\n", k0.size(), k1.size(), matches.size(), right);
  EXPECT_GE(matches.size(), 100u);
  EXPECT_GE(right, static_cast<int>(0.95 * static_cast<double>(matches.size())));
  // Keypoints flagged as used take no part: a second pass pairs only keypoints the first left free.
  const std::vector<bool> before0 = used0, before1 = used1;
  for (const auto &m : matchAlongEpipolarLines(F, k0, d0, k1, d1, used0, used1)) {
    EXPECT_FALSE(before0[static_cast<size_t>(m.first)] || before1[static_cast<size_t>(m.second)]);
  }
  // Descriptors of the wrong size are refused.
  std::vector<bool> none0(k0.size(), false), none1(k1.size(), false);
  EXPECT_THROW(matchAlongEpipolarLines(F, k0, d0.colRange(0, 16), k1, d1, none0, none1), vpHSlamException);
}
