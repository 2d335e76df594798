// The dataset program's live window under a virtual X server (Xvfb): the window opens, frames are drawn, and the
// screenshot of the last view is a real picture (camera image with points, status, top view).
#include "HSlamTestData.h"
#include "HSlamTestPrograms.h"

#include <visp3/core/vpIoTools.h>
#include <visp3/io/vpImageIo.h>

#include <gtest/gtest.h>

#include <cstdlib>

namespace
{
TEST(LiveViewWindow, DatasetProgramDrawsAndSavesAScreenshotUnderXvfb)
{
  HSLAM_REQUIRE_SHARED_DATA(kitti, "kitti06_000-050");
  if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "xvfb-run not installed (Debian packages xvfb and xauth): the window test needs a virtual X "
                    "server";
  }
  const std::string program = hslam_test::builtTutorialPath("tutorial-hslam-dataset");
  ASSERT_FALSE(program.empty());
  const std::string dir = vpIoTools::makeTempDirectory("/tmp/hslam-xvfb-XXXXXX");
  const std::string shot = dir + "/view.png";
  const hslam_test::ProgramRun run =
      hslam_test::runProgram("xvfb-run", "-a -s '-screen 0 1920x1080x24' " + program + " --input " + kitti +
                                             " --max-frames 15 --deterministic --screenshot " + shot);
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_EQ(run.output.find("running without"), std::string::npos) << run.output;
  ASSERT_NE(run.output.find("screenshot: " + shot), std::string::npos) << run.output;

  vpImage<vpRGBa> I;
  vpImageIo::read(I, shot);
  // KITTI 06 rectified is 1226x370 (the size depends on the calibration): the view adds the top-view panel.
  EXPECT_GT(I.getWidth(), 1226u);
  EXPECT_GE(I.getHeight(), 300u);
  unsigned int coloured = 0, distinct = 0;
  vpRGBa previous = I[0][0];
  for (unsigned int v = 0; v < I.getHeight(); ++v) {
    for (unsigned int u = 0; u < I.getWidth(); ++u) {
      const vpRGBa &c = I[v][u];
      coloured += (c.R != c.G || c.G != c.B) ? 1 : 0;
      distinct += (c.R != previous.R || c.G != previous.G || c.B != previous.B) ? 1 : 0;
      previous = c;
    }
  }
  EXPECT_GT(distinct, I.getSize() / 10) << "the screenshot is not a blank window";
  EXPECT_GT(coloured, 500u) << "points and the top view are drawn in colour";
  vpIoTools::remove(dir);
}
} // namespace
