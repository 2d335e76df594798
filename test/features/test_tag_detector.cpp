// AprilTag sightings (features/TagDetector.h) and the tag description (vpHSlamTag): on ViSP's real picture of
// tag36h11 tags against ViSP's reference poses, and on a tag hung in the synthetic room against the rendered truth,
// clean and with noise and motion blur.
#include "HSlamTestData.h"
#include "HSlamTestTags.h"

#include "features/TagDetector.h"
#include "math/ViSPConversions.h"

#include <visp3/core/vpPoseVector.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamTag.h>

#include "io/SourceFiles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>

using namespace hslam;

namespace
{
double angleDeg(const SE3d &a, const SE3d &b)
{
  return (a.unitQuaternion().angularDistance(b.unitQuaternion())) * 180. / M_PI;
}
} // namespace

TEST(TagDescription, ParsesTheCommandLineFormAndRefusesNonsense)
{
  const vpHSlamTag t = vpHSlamTag::parse("tag36h11:0.16:3");
  EXPECT_EQ(t.getFamily(), "tag36h11");
  EXPECT_DOUBLE_EQ(t.getSize(), 0.16);
  EXPECT_EQ(t.getId(), 3);
  EXPECT_EQ(vpHSlamTag::parse(t.toString()).toString(), t.toString());
  EXPECT_FALSE(vpHSlamTag::parse("tag25h9:0.1").hasId());
  EXPECT_FALSE(vpHSlamTag().isSet());
  for (const char *bad : {"tag36h12:0.16", "tag36h11:0", "tag36h11:-0.1", "tag36h11:abc", "tag36h11", "tag36h11:0.1:x",
                          "tag36h11:0.1:-2", "tag36h11:0.1:1:2", "tag36h11:nan", ""}) {
    try {
      vpHSlamTag::parse(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const vpHSlamException &e) {
      EXPECT_EQ(e.getCode(), vpHSlamException::invalidArgument) << bad;
      EXPECT_NE(std::string(e.getMessage()).find("tag"), std::string::npos) << e.getMessage();
    }
  }
}

// ViSP's own regression picture (visp-images-data AprilTag/AprilTag.pgm, its camera and 53 mm tags): every sighting
// handed on is within 5 mm and 0.3 degree of ViSP's reference pose (ground_truth_pose.txt).
TEST(TagDetector, RealPictureMatchesViSPReferencePoses)
{
  const std::string dir = hslam_test::vispImagesDir();
  if (dir.empty()) {
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";
  }
  vpImage<unsigned char> I;
  io::readGreyImage(dir + "/AprilTag/AprilTag.pgm", I);
  std::map<int, SE3d> reference;
  std::ifstream in(dir + "/AprilTag/ground_truth_pose.txt");
  std::string name;
  double p[6];
  while (in >> name >> p[0] >> p[1] >> p[2] >> p[3] >> p[4] >> p[5]) {
    const int id = std::stoi(name.substr(name.rfind('_') + 1));
    reference[id] = toSE3(vpHomogeneousMatrix(vpPoseVector(p[0], p[1], p[2], p[3], p[4], p[5])));
  }
  ASSERT_GE(reference.size(), 10u);
  vpCameraParameters K;
  K.initPersProjWithoutDistortion(615.1674805, 615.1675415, 312.1889954, 243.4373779);
  TagDetector detector(vpHSlamTag("tag36h11", 0.053), K);
  const std::vector<TagSighting> sightings = detector.detect(I);
  EXPECT_GE(sightings.size(), reference.size() / 2) << detector.lastRawDetections() << " tags found before checks";
  for (const TagSighting &s : sightings) {
    ASSERT_TRUE(reference.count(s.id)) << "id " << s.id;
    const SE3d &ref = reference[s.id];
    EXPECT_LT((s.cMt.translation() - ref.translation()).norm(), 0.005) << "id " << s.id;
    EXPECT_LT(angleDeg(s.cMt, ref), 0.3) << "id " << s.id;
    EXPECT_LE(s.projectionErrorPx, TagDetector::kMaxProjectionErrorPx);
  }
  // With an id, only that tag.
  TagDetector one(vpHSlamTag("tag36h11", 0.053, sightings.empty() ? 0 : sightings.front().id), K);
  const std::vector<TagSighting> only = one.detect(I);
  ASSERT_EQ(only.size(), 1u);
  EXPECT_EQ(only.front().id, sightings.front().id);
}

// A 20 cm tag36h11 on the synthetic room's right wall, seen by the outward-looking camera at 640x480 from about
// 2 m (45-60 pixels a side, seen obliquely): the detector pose against the rendered truth (cMt = wMc^-1 wMt). Position
// within 1 % of the distance clean, 2 % with noise (sigma 3 grey levels) and motion blur (measured: 0.3 / 0.4 %);
// rotation within 2 degrees (measured 1.3 / 1.1: the usual accuracy of a tag's orientation at that size).
TEST(TagDetector, SyntheticTagMatchesTheRenderedTruth)
{
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";
  }
  HSLAM_REQUIRE_TAG_IMAGES();
  for (const bool degraded : {false, true}) {
    vpHSlamSyntheticScene scene;
    vpHSlamSyntheticScene::Effects effects;
    if (degraded) {
      effects.noiseSigma = 3.;
      effects.motionBlur = true;
    }
    scene.setLookOutward(true); // films the right wall, where the tag hangs, from about frame 60 to 120
    scene.configure(640, 480, 401, 30., 1, effects);
    vpColVector centre(3);
    centre[0] = 2.5;
    centre[1] = -0.17;
    centre[2] = 0.8;
    const SE3d wMt = toSE3(hslam_test::hangTag36h11(scene, 5, centre, 0.2));
    TagDetector detector(vpHSlamTag("tag36h11", 0.2, 5), scene.getCameraParameters());
    unsigned int seen = 0, frames = 0;
    double worstRel = 0., worstDeg = 0.;
    for (unsigned int i = 72; i <= 112; i += 8, ++frames) {
      vpImage<unsigned char> I;
      scene.render(i, I);
      const SE3d truth = toSE3(scene.getPose(i)).inverse() * wMt;
      for (const TagSighting &s : detector.detect(I)) {
        ++seen;
        worstRel = std::max(worstRel, (s.cMt.translation() - truth.translation()).norm() / truth.translation().norm());
        worstDeg = std::max(worstDeg, angleDeg(s.cMt, truth));
      }
    }
    std::cout << (degraded ? "noise + blur" : "clean") << ": " << seen << " sightings in " << frames
              << " frames, worst position error " << 100. * worstRel << " % of the distance, worst rotation "
              << worstDeg << " deg" << std::endl;
    EXPECT_GE(seen, frames * 3 / 4);
    EXPECT_LT(worstRel, degraded ? 0.02 : 0.01);
    EXPECT_LT(worstDeg, 2.);
  }
}
