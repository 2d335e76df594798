// vpHSlamLiveView: the composed picture has the camera image with coloured points, a status line and a top view
// with the trajectory, keyframes and camera; descriptor matches are magenta crosses named in the status line; it is
// safe before the first frame.
#include "HSlamTestData.h"

#include <visp3/hslam/vpHSlam.h>
#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamLiveView.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <gtest/gtest.h>

namespace
{
bool isGrey(const vpRGBa &c)
{
  return c.R == c.G && c.G == c.B;
}
bool near(const vpRGBa &c, int r, int g, int b)
{
  return std::abs(c.R - r) + std::abs(c.G - g) + std::abs(c.B - b) < 30;
}

TEST(LiveView, DrawsPointsStatusAndTopViewOfARealRun)
{
  HSLAM_REQUIRE_SHARED_DATA(kitti, "kitti06_000-050");
  vpHSlamImageSource::Options options;
  options.maxFrames = 20;
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(kitti, options);
  vpHSlamParameters parameters;
  parameters.system.deterministic = true;
  vpHSlam slam(*source, parameters);
  vpHSlamLiveView view;
  vpImage<vpRGBa> canvas;

  view.draw(slam, 0, 0., canvas); // before any frame: a black image and an empty panel, no exception
  EXPECT_EQ(canvas.getWidth(), slam.getWidth() + view.getTopViewWidth());
  EXPECT_EQ(canvas.getHeight(), slam.getHeight());

  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  while (source->acquire(I, frame)) {
    slam.track(I, frame.timestamp, frame.exposure);
  }
  ASSERT_EQ(slam.getState(), vpHSlam::stateTracking);
  view.draw(slam, frame.index, 10., canvas, "q: quit");
  const unsigned int w = slam.getWidth(), h = slam.getHeight();
  ASSERT_EQ(canvas.getWidth(), w + view.getTopViewWidth());
  ASSERT_EQ(canvas.getHeight(), h);

  // Image area below the status band: the grey image plus coloured point markers.
  unsigned int coloured = 0;
  for (unsigned int v = 30; v < h; ++v) {
    for (unsigned int u = 0; u < w; ++u) {
      coloured += isGrey(canvas[v][u]) ? 0 : 1;
    }
  }
  EXPECT_GT(coloured, 500u) << "active points are drawn";
  // Status band: white text on black.
  unsigned int text = 0;
  for (unsigned int v = 0; v < 20; ++v) {
    for (unsigned int u = 0; u < w; ++u) {
      text += near(canvas[v][u], 255, 255, 255) ? 1 : 0;
    }
  }
  EXPECT_GT(text, 100u) << "status line is written";
  // Top view: green trajectory, blue keyframes, red camera.
  unsigned int green = 0, blue = 0, red = 0;
  for (unsigned int v = 0; v < h; ++v) {
    for (unsigned int u = w; u < canvas.getWidth(); ++u) {
      green += near(canvas[v][u], 60, 200, 60) ? 1 : 0;
      blue += near(canvas[v][u], 80, 140, 255) ? 1 : 0;
      red += near(canvas[v][u], 255, 60, 60) ? 1 : 0;
    }
  }
  EXPECT_GT(green, 20u);
  EXPECT_GT(blue, 10u);
  EXPECT_GT(red, 10u);

  view.setTopViewWidth(0);
  view.draw(slam, frame.index, 10., canvas);
  EXPECT_EQ(canvas.getWidth(), w);
  EXPECT_THROW(view.setTopViewWidth(10), vpHSlamException);
}

//! Magenta pixels of \e canvas in rows [v0, v1) and columns [0, u1).
unsigned int countMagenta(const vpImage<vpRGBa> &canvas, unsigned int v0, unsigned int v1, unsigned int u1)
{
  unsigned int n = 0;
  for (unsigned int v = v0; v < v1; ++v) {
    for (unsigned int u = 0; u < u1; ++u) {
      n += near(canvas[v][u], 255, 0, 255) ? 1 : 0;
    }
  }
  return n;
}

TEST(LiveView, StatusLineNamesDescriptorMatchesInTheirColourUnlessTrackingIsDirect)
{
  vpHSlamCamera camera(vpHSlamCamera::pinhole, 640, 480, 500., 500., 320., 240.);
  camera.setRectification(vpHSlamCamera::rectifyNone);
  vpHSlamLiveView view;
  vpImage<vpRGBa> canvas;
  vpHSlamParameters parameters;
  parameters.system.deterministic = true;
  parameters.tracking.mode = vpHSlamParameters::trackingHybrid;
  {
    vpHSlam slam(camera, parameters);
    view.draw(slam, 0, 0., canvas, "q: quit");
    EXPECT_GT(countMagenta(canvas, 0, 20, 640), 20u) << "the \"+ orb N\" legend is written in the crosses' colour";
    EXPECT_EQ(countMagenta(canvas, 22, 480, 640), 0u) << "no frame yet: no match drawn";
  }
  parameters.tracking.mode = vpHSlamParameters::trackingDirect;
  vpHSlam slam(camera, parameters);
  view.draw(slam, 0, 0., canvas, "q: quit");
  EXPECT_EQ(countMagenta(canvas, 0, 480, 640), 0u) << "direct tracking has no descriptor matches to name";
}

TEST(LiveView, DrawsDescriptorMatchesAsMagentaCrosses)
{
  HSLAM_REQUIRE_SHARED_DATA(kitti, "kitti06_000-050");
  vpHSlamImageSource::Options options;
  options.maxFrames = 20;
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(kitti, options);
  vpHSlamParameters parameters;
  parameters.system.deterministic = true;
  parameters.tracking.mode = vpHSlamParameters::trackingHybrid;
  vpHSlam slam(*source, parameters);
  vpImage<unsigned char> I;
  vpHSlamImageSource::Frame frame;
  while (source->acquire(I, frame)) {
    slam.track(I, frame.timestamp, frame.exposure);
  }
  const std::vector<vpImagePoint> matches = slam.getDescriptorMatches();
  if (matches.empty()) {
    GTEST_SKIP() << "vpHSlam::getDescriptorMatches() gave nothing after 20 hybrid-tracked KITTI frames (hybrid "
                    "tracking not implemented yet?): no cross to look for";
  }
  vpHSlamLiveView view;
  vpImage<vpRGBa> canvas;
  view.draw(slam, frame.index, 10., canvas);
  const unsigned int w = slam.getWidth(), h = slam.getHeight();
  unsigned int inside = 0;
  for (const vpImagePoint &ip : matches) {
    inside += (ip.get_u() >= 0 && ip.get_u() < w && ip.get_v() >= 22 && ip.get_v() < h) ? 1 : 0;
  }
  // A cross is 13 pixels; neighbouring crosses overlap, a point marker may cover part of one.
  EXPECT_GE(countMagenta(canvas, 22, h, w), 3 * inside) << inside << " matches in the image";
}

TEST(LiveView, InverseDepthColoursRunFromBlueToRed)
{
  const vpRGBa far = vpHSlamLiveView::inverseDepthColor(0.), nearest = vpHSlamLiveView::inverseDepthColor(1.);
  EXPECT_GT(far.B, 100); // dark blue far, dark red near (jet ramp)
  EXPECT_EQ(far.R, 0);
  EXPECT_EQ(far.G, 0);
  EXPECT_GT(nearest.R, 100);
  EXPECT_EQ(nearest.G, 0);
  EXPECT_EQ(nearest.B, 0);
  const vpRGBa middle = vpHSlamLiveView::inverseDepthColor(0.5);
  EXPECT_GT(middle.G, 200);
  const vpRGBa clamped = vpHSlamLiveView::inverseDepthColor(std::nan(""));
  EXPECT_EQ(clamped.B, far.B);
}
} // namespace
