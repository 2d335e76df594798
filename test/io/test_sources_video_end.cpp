// A video whose container stores no frame count (ViSP's cube.mpeg, MPEG-1) ends at its last frame: ViSP 3.5's
// vpVideoReader would deliver the last image again and again (100000 frames); the video source must not.
#include "HSlamTestData.h"

#include <visp3/core/vpIoTools.h>
#include <visp3/hslam/vpHSlamImageSource.h>

#include <gtest/gtest.h>

#include <fstream>

TEST(ImageSourceVideo, StreamWithoutFrameCountEndsAtItsLastFrame)
{
  const std::string images = hslam_test::vispImagesDir();
  if (images.empty() || !vpIoTools::checkFilename(images + "/video/cube.mpeg")) {
    GTEST_SKIP() << "visp-images-data (video/cube.mpeg) not installed";
  }
  const std::string dir = vpIoTools::makeTempDirectory("/tmp/hslam-video-XXXXXX");
  std::ofstream(dir + "/camera.txt") << "Pinhole 500 500 192 144 0\n384 288\ncrop\n384 288\n";
  vpHSlamImageSource::Options options;
  options.cameraFile = dir + "/camera.txt";
  std::unique_ptr<vpHSlamImageSource> source = vpHSlamImageSource::create(images + "/video/cube.mpeg", options);
  vpImage<unsigned char> I, previous;
  vpHSlamImageSource::Frame frame;
  unsigned int frames = 0, repeats = 0;
  while (frames < 1000 && source->acquire(I, frame)) {
    EXPECT_EQ(frame.index, frames);
    repeats += (frames > 0 && I == previous) ? 1 : 0;
    previous = I;
    ++frames;
  }
  EXPECT_GT(frames, 50u);
  EXPECT_LT(frames, 200u) << "the source did not stop at the end of the stream";
  EXPECT_LT(repeats, 5u);
  EXPECT_FALSE(source->acquire(I, frame)); // and stays at the end
  vpIoTools::remove(dir);
}
