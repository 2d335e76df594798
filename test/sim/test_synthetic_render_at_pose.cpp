// vpHSlamSyntheticScene::renderAtPose: the room seen from any pose, through the same photometric path as render().
#include "HSlamTestData.h"

#include <visp3/core/vpMath.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

namespace
{
constexpr unsigned int kWidth = 160, kHeight = 120, kFrames = 40;

#define HSLAM_REQUIRE_VISP_IMAGES()                                                                                    \
  if (hslam_test::vispImagesDir().empty()) {                                                                           \
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";                \
  }

//! Number of pixels that differ between two images of the same size.
unsigned int differingPixels(const vpImage<unsigned char> &A, const vpImage<unsigned char> &B)
{
  unsigned int n = 0;
  for (unsigned int p = 0; p < A.getSize(); ++p) {
    n += A.bitmap[p] != B.bitmap[p] ? 1u : 0u;
  }
  return n;
}
} // namespace

TEST(SyntheticRenderAtPose, SameImageAsTheFrameAtItsPose)
{
  HSLAM_REQUIRE_VISP_IMAGES();
  vpHSlamSyntheticScene::Effects effects;
  effects.vignette = true;
  effects.response = true;
  vpHSlamSyntheticScene scene;
  scene.configure(kWidth, kHeight, kFrames, 30.0, 5, effects);
  vpImage<unsigned char> frame, atPose;
  for (unsigned int i : {0u, 13u, 27u}) {
    scene.render(i, frame);
    scene.renderAtPose(scene.getPose(i), atPose);
    ASSERT_EQ(atPose.getWidth(), kWidth);
    ASSERT_EQ(atPose.getHeight(), kHeight);
    EXPECT_EQ(differingPixels(frame, atPose), 0u) << "frame " << i;
  }
  // Another pose gives another image: the pose is used, not a frame index.
  scene.renderAtPose(scene.getPose(0) * vpHomogeneousMatrix(0.05, 0., 0., 0., vpMath::rad(2.), 0.), atPose);
  scene.render(0, frame);
  EXPECT_GT(differingPixels(frame, atPose), kWidth * kHeight / 2);
}

TEST(SyntheticRenderAtPose, NoiseFollowsTheSeedAndExposureIsTheBase)
{
  HSLAM_REQUIRE_VISP_IMAGES();
  vpHSlamSyntheticScene::Effects effects;
  effects.noiseSigma = 3.0;
  vpHSlamSyntheticScene scene;
  scene.configure(kWidth, kHeight, kFrames, 30.0, 5, effects);
  vpImage<unsigned char> a, b, c;
  const vpHomogeneousMatrix wMc = scene.getPose(3);
  scene.renderAtPose(wMc, a, 1);
  scene.renderAtPose(wMc, b, 1);
  scene.renderAtPose(wMc, c, 2);
  EXPECT_EQ(differingPixels(a, b), 0u);
  EXPECT_GT(differingPixels(a, c), kWidth * kHeight / 2);
  double meanDifference = 0.;
  for (unsigned int p = 0; p < a.getSize(); ++p) {
    meanDifference += (static_cast<double>(a.bitmap[p]) - c.bitmap[p]) / a.getSize();
  }
  EXPECT_LT(std::fabs(meanDifference), 0.5); // zero-mean noise, same irradiance

  // With exposure changes configured, a pose is rendered at the base exposure: as a scene without them.
  vpHSlamSyntheticScene::Effects exposure;
  exposure.exposureChanges = true;
  vpHSlamSyntheticScene changing, constant;
  changing.configure(kWidth, kHeight, kFrames, 30.0, 5, exposure);
  constant.configure(kWidth, kHeight, kFrames, 30.0, 5);
  changing.renderAtPose(wMc, a);
  constant.renderAtPose(wMc, b);
  EXPECT_EQ(differingPixels(a, b), 0u);
}

TEST(SyntheticRenderAtPose, RefusedBeforeConfigure)
{
  vpHSlamSyntheticScene scene;
  vpImage<unsigned char> I;
  EXPECT_THROW(scene.renderAtPose(vpHomogeneousMatrix(), I), vpHSlamException);
}
