// On a synthetic closed loop (the generator's path ends where it starts), the last frames must retrieve the first
// frames at rank 1 from a database of the frames before them, with the shipped vocabulary.
#include "HSlamTestData.h"
#include "PlaceRecognitionEval.h"

#include "features/VocabularyFiles.h"

#include <visp3/hslam/vpHSlamSyntheticScene.h>
#include <visp3/hslam/vpHSlamVocabulary.h>

#include <gtest/gtest.h>

namespace
{
TEST(PlaceRecognitionSynthetic, LastFramesOfAClosedLoopRetrieveTheFirstFrames)
{
  if (hslam_test::vispImagesDir().empty()) {
    GTEST_SKIP() << "visp-images-data not installed (textures of the synthetic room)";
  }
  if (vpHSlamVocabulary::defaultPath().empty()) {
    GTEST_SKIP() << "no default vocabulary (data/hslam-orb.hvoc)";
  }
  const hslam::OrbVocabulary vocabulary = hslam::loadVocabulary(vpHSlamVocabulary::defaultPath());
  vpHSlamSyntheticScene scene;
  const unsigned int frames = 160;
  scene.configure(640, 480, frames, 30.0, 3);

  // Database: every 4th frame of the first 130 (the loop's start and the far side of the room); queries: the
  // last 6 frames, which come back to the start.
  hslam::OrbExtractor extractor;
  hslam::KeyframeDatabase database(vocabulary.wordCount());
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  vpImage<unsigned char> I;
  hslam::BowVector bow;
  for (unsigned int i = 0; i < 130; i += 4) {
    scene.render(i, I);
    extractor.extract(I, keypoints, descriptors);
    vocabulary.transform(hslam::descriptorsFromMat(descriptors), bow);
    database.add(static_cast<int>(i), bow);
  }
  for (unsigned int q = frames - 6; q < frames; ++q) {
    scene.render(q, I);
    extractor.extract(I, keypoints, descriptors);
    vocabulary.transform(hslam::descriptorsFromMat(descriptors), bow);
    const auto candidates = database.query(bow, hslam::KeyframeDatabase::Query());
    ASSERT_FALSE(candidates.empty()) << "frame " << q;
    const int best = candidates.front().id;
    EXPECT_LE(best, 12) << "frame " << q << " retrieved frame " << best << " (score " << candidates.front().score
                        << ")";
    EXPECT_TRUE(hslam_test::samePlace(scene.getPose(q), scene.getPose(static_cast<unsigned int>(best)), 0.3, 20.0));
  }
}
} // namespace
