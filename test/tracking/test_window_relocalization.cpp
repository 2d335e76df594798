// Triangulation between two described views with known poses (WindowRelocalization's map of a lost camera): exact
// synthetic scene, right points recovered, wrong matches and views without parallax give none.
#include "tracking/WindowRelocalization.h"

#include "HSlamTestDescriptors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace
{
using hslam::DescribedView;
using hslam::OrbDescriptor;
using hslam::SE3d;

const hslam::PinholeIntrinsics kK{500., 500., 319.5, 239.5};

using hslam_test::flipBits;
using hslam_test::randomDescriptor;

//! cTw of a camera at \e centre looking along +z (world), turned by \e yawRad about y.
SE3d cameraAt(const Eigen::Vector3d &centre, double yawRad)
{
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0., 0., 0., 0., yawRad, 0.;
  const SE3d wRc = SE3d::exp(xi);
  return SE3d(wRc.unitQuaternion(), centre).inverse();
}

//! Points of \e wX seen by a camera \e cTw, with their descriptors (some bits flipped) and pixel noise.
DescribedView view(int id, const SE3d &cTw, const std::vector<Eigen::Vector3d> &wX,
                   const std::vector<OrbDescriptor> &descriptors, double noisePx, std::mt19937_64 &rng)
{
  std::normal_distribution<double> noise(0., noisePx);
  DescribedView out;
  out.id = id;
  out.cMw = cTw;
  for (std::size_t i = 0; i < wX.size(); ++i) {
    const Eigen::Vector3d cX = cTw * wX[i];
    const Eigen::Vector2d uv(kK.fx * cX.x() / cX.z() + kK.cx + noise(rng),
                             kK.fy * cX.y() / cX.z() + kK.cy + noise(rng));
    if (cX.z() <= 0. || uv.x() < 0 || uv.y() < 0 || uv.x() >= 640 || uv.y() >= 480) {
      continue;
    }
    out.uv.push_back(uv);
    out.scale.push_back(1.f);
    out.descriptors.push_back(flipBits(descriptors[i], 6, rng));
  }
  return out;
}

class ViewTriangulation : public ::testing::Test
{
protected:
  void SetUp() override
  {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> spread(-1.5, 1.5), depth(3., 6.);
    for (int i = 0; i < 400; ++i) {
      m_wX.emplace_back(spread(rng), spread(rng), depth(rng));
      m_descriptors.push_back(randomDescriptor(rng));
    }
  }
  std::vector<Eigen::Vector3d> m_wX;
  std::vector<OrbDescriptor> m_descriptors;
};

TEST_F(ViewTriangulation, RecoversThePointsSeenByBothViews)
{
  std::mt19937_64 rng(4);
  // 0.3 m baseline at 3-6 m: 3-6 degrees of parallax.
  const DescribedView a = view(1, cameraAt(Eigen::Vector3d::Zero(), 0.), m_wX, m_descriptors, 0.5, rng);
  const DescribedView b = view(2, cameraAt(Eigen::Vector3d(0.3, 0.05, 0.), -0.03), m_wX, m_descriptors, 0.5, rng);
  std::vector<unsigned char> done;
  std::vector<Eigen::Vector3d> wX;
  std::vector<OrbDescriptor> descriptors;
  const int added = hslam::triangulateViews(a, b, kK, hslam::ViewTriangulationOptions(), done, wX, descriptors);
  ASSERT_EQ(static_cast<std::size_t>(added), wX.size());
  ASSERT_EQ(wX.size(), descriptors.size());
  EXPECT_GE(added, 300); // nearly all of the ~370 points both views see
  ASSERT_EQ(done.size(), a.uv.size());
  EXPECT_EQ(std::count(done.begin(), done.end(), 1), added);
  // Each triangulated point is the true one (found by its descriptor), within the depth noise of 0.5 px (4 sigma).
  int wrong = 0;
  for (std::size_t k = 0; k < wX.size(); ++k) {
    int best = 257, index = -1;
    for (std::size_t i = 0; i < m_descriptors.size(); ++i) {
      const int d = hslam::hammingDistance(descriptors[k], m_descriptors[i]);
      if (d < best) {
        best = d;
        index = static_cast<int>(i);
      }
    }
    ASSERT_GE(index, 0);
    // Inverse depth (the well-conditioned coordinate): 0.5 px on a 0.3 m baseline is 0.0047 / m (1 sigma, two views).
    const double idepthError =
        std::fabs(1. / (a.cMw * wX[k]).z() - 1. / (a.cMw * m_wX[static_cast<std::size_t>(index)]).z());
    wrong += idepthError > 0.02 ? 1 : 0;
  }
  EXPECT_LE(wrong, 2);

  // A second pairing of the same view adds nothing for the keypoints already triangulated.
  const int again = hslam::triangulateViews(a, b, kK, hslam::ViewTriangulationOptions(), done, wX, descriptors);
  EXPECT_EQ(again, 0);
}

TEST_F(ViewTriangulation, MatchesOffTheEpipolarLineAreRefused)
{
  std::mt19937_64 rng(5);
  const DescribedView a = view(1, cameraAt(Eigen::Vector3d::Zero(), 0.), m_wX, m_descriptors, 0.5, rng);
  DescribedView b = view(2, cameraAt(Eigen::Vector3d(0.3, 0.05, 0.), -0.03), m_wX, m_descriptors, 0.5, rng);
  // Moved 40 px across the epipolar lines (which run along u for this sideways baseline): no match can hold.
  for (Eigen::Vector2d &uv : b.uv) {
    uv.y() += 40.;
  }
  std::vector<unsigned char> done;
  std::vector<Eigen::Vector3d> wX;
  std::vector<OrbDescriptor> descriptors;
  EXPECT_EQ(hslam::triangulateViews(a, b, kK, hslam::ViewTriangulationOptions(), done, wX, descriptors), 0);
}

TEST_F(ViewTriangulation, NoDepthWithoutParallax)
{
  std::mt19937_64 rng(6);
  // Same centre, turned by 5 degrees: pure rotation gives no depth (and no baseline at all).
  const DescribedView a = view(1, cameraAt(Eigen::Vector3d::Zero(), 0.), m_wX, m_descriptors, 0.5, rng);
  const DescribedView b = view(2, cameraAt(Eigen::Vector3d::Zero(), 0.09), m_wX, m_descriptors, 0.5, rng);
  std::vector<unsigned char> done;
  std::vector<Eigen::Vector3d> wX;
  std::vector<OrbDescriptor> descriptors;
  EXPECT_EQ(hslam::triangulateViews(a, b, kK, hslam::ViewTriangulationOptions(), done, wX, descriptors), 0);
  // 2 mm of baseline at 3-6 m: under the 1-degree parallax bound for every point.
  const DescribedView c = view(3, cameraAt(Eigen::Vector3d(0.002, 0., 0.), 0.), m_wX, m_descriptors, 0.5, rng);
  EXPECT_EQ(hslam::triangulateViews(a, c, kK, hslam::ViewTriangulationOptions(), done, wX, descriptors), 0);
}
} // namespace
