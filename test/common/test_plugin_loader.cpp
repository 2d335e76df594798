// The module's plug-ins (common/PluginLoader.h): a program linking visp_hslam starts without the image and video I/O
// libraries and ViSP's detection module, which come when a tag is described; a missing plug-in or entry point is a
// message naming each place tried.
#include "common/PluginLoader.h"
#include "features/AprilTagPlugin.h"
#include "features/TagDetector.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamTag.h>

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

using namespace hslam;

namespace
{
//! The shared objects mapped into this process (/proc/self/maps).
std::string mappedFiles()
{
  std::ifstream in("/proc/self/maps");
  std::stringstream all;
  all << in.rdbuf();
  return all.str();
}

bool mapped(const std::string &maps, const std::string &library)
{
  return maps.find("/" + library) != std::string::npos;
}
} // namespace

// First in this file: no other test of the process may have loaded a plug-in yet.
TEST(PluginLoader, AProgramStartsWithoutTheIoLibrariesAndATagBringsTheDetector)
{
  const std::string before = mappedFiles();
  if (before.empty()) {
    GTEST_SKIP() << "/proc/self/maps not readable here";
  }
  ASSERT_TRUE(mapped(before, "libvisp_hslam.so")) << "the test program does not run the module";
  for (const char *heavy : {"libvisp_detection.so", "libvisp_io.so", "libopencv_imgcodecs.so", "libopencv_videoio.so",
                            "libvisp_hslam_tag.so", "libvisp_hslam_video.so"}) {
    EXPECT_FALSE(mapped(before, heavy)) << heavy << " is loaded by a program that only links visp_hslam";
  }
#ifdef VISP_HAVE_APRILTAG
  vpCameraParameters K;
  K.initPersProjWithoutDistortion(500., 500., 320., 240.);
  TagDetector detector(vpHSlamTag("tag36h11", 0.1), K);
  vpImage<unsigned char> grey(240, 320, 128);
  EXPECT_TRUE(detector.detect(grey).empty());
  const std::string after = mappedFiles();
  EXPECT_TRUE(mapped(after, "libvisp_hslam_tag.so"));
  EXPECT_TRUE(mapped(after, "libvisp_detection.so"));
#endif
}

TEST(PluginLoader, AMissingPluginOrEntryPointIsAClearMessage)
{
  std::string error;
  EXPECT_EQ(loadPluginSymbol("libvisp_hslam_nothing.so", "entry", "HSLAM_TEST_NO_SUCH_VARIABLE", error), nullptr);
  EXPECT_NE(error.find("libvisp_hslam_nothing.so"), std::string::npos) << error;
  EXPECT_NE(error.find("HSLAM_TEST_NO_SUCH_VARIABLE"), std::string::npos) << error;
  // Asked again: the same answer, without trying again.
  std::string again;
  EXPECT_EQ(loadPluginSymbol("libvisp_hslam_nothing.so", "entry", "HSLAM_TEST_NO_SUCH_VARIABLE", again), nullptr);
  EXPECT_EQ(again, error);
#ifdef VISP_HAVE_APRILTAG
  EXPECT_NE(loadPluginSymbol(kTagPluginFile, kTagPluginFactory, "HSLAM_TAG_PLUGIN", error), nullptr) << error;
  EXPECT_EQ(loadPluginSymbol(kTagPluginFile, "hslamNoSuchEntry", "HSLAM_TAG_PLUGIN", error), nullptr);
  EXPECT_NE(error.find("no hslamNoSuchEntry in it"), std::string::npos) << error;
#endif
}

#ifdef VISP_HAVE_APRILTAG
TEST(PluginLoader, AnUnknownTagFamilyIsRefusedByThePlugin)
{
  // vpHSlamTag refuses unknown families itself; the plug-in checks again what reaches it from elsewhere.
  using Factory = AprilTagBackend *(*)(const char *, std::string *);
  std::string error;
  const auto factory = loadPluginFunction<Factory>(kTagPluginFile, kTagPluginFactory, "HSLAM_TAG_PLUGIN", error);
  ASSERT_NE(factory, nullptr) << error;
  EXPECT_EQ(factory("tag99h1", &error), nullptr);
  EXPECT_NE(error.find("unknown family 'tag99h1'"), std::string::npos) << error;
  AprilTagBackend *backend = factory("tag36h11", &error);
  ASSERT_NE(backend, nullptr) << error;
  delete backend;
}
#endif
