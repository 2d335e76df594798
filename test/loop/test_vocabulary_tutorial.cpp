// tutorial-hslam-vocabulary end to end: training on an image folder and a dataset folder, conversion between
// formats, and its errors; the public vpHSlamVocabulary on the result.
#include "HSlamTestData.h"
#include "HSlamTestPrograms.h"

#include <visp3/core/vpIoTools.h>
#include <visp3/hslam/vpHSlamVocabulary.h>
#include <visp3/io/vpImageIo.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

namespace
{
class VocabularyTutorial : public ::testing::Test
{
protected:
  void SetUp() override
  {
    m_program = hslam_test::builtTutorialPath("tutorial-hslam-vocabulary");
    if (m_program.empty()) {
      GTEST_SKIP() << "tutorial-hslam-vocabulary not built";
    }
    m_dir = vpIoTools::makeTempDirectory("/tmp/hslam-voctut-XXXXXX");
  }
  void TearDown() override
  {
    if (!m_dir.empty()) {
      vpIoTools::remove(m_dir);
    }
  }
  std::string m_program, m_dir;
};

TEST_F(VocabularyTutorial, TrainsOnAFolderDeterministicallyAndConverts)
{
  const std::string images = hslam_test::vispImagesDir();
  if (images.empty()) {
    GTEST_SKIP() << "visp-images-data not installed";
  }
  // A small, quick training set: the Klimt and Solvay photographs (sub-folders searched recursively).
  vpIoTools::makeDirectory(m_dir + "/train/a");
  for (const std::string &file :
       {std::string("/Klimt/Klimt.png"), std::string("/Solvay/Solvay_conference_1927_Version2_640x440.png")}) {
    vpImage<unsigned char> I;
    vpImageIo::read(I, images + file);
    vpImageIo::write(I, m_dir + "/train/a/" + vpIoTools::getName(file));
  }
  vpIoTools::makeDirectory(m_dir + "/train/b");
  std::ofstream(m_dir + "/train/b/broken.png") << "broken";

  const std::string args = "--images " + m_dir + "/train --branching 8 --levels 4 --output ";
  const hslam_test::ProgramRun first = hslam_test::runProgram(m_program, args + m_dir + "/one.hvoc");
  ASSERT_EQ(first.exitCode, 0) << first.output;
  EXPECT_NE(first.output.find("1 unreadable images skipped"), std::string::npos) << first.output;
  EXPECT_NE(first.output.find("100 %"), std::string::npos) << first.output;
  const hslam_test::ProgramRun second = hslam_test::runProgram(m_program, args + m_dir + "/two.hvoc");
  ASSERT_EQ(second.exitCode, 0) << second.output;
  const vpHSlamVocabulary one = vpHSlamVocabulary::load(m_dir + "/one.hvoc");
  EXPECT_EQ(one.getBranching(), 8u);
  EXPECT_EQ(one.getLevels(), 4u);
  EXPECT_GT(one.getWordCount(), 20u);
  EXPECT_EQ(vpHSlamVocabulary::load(m_dir + "/two.hvoc").getFingerprint(), one.getFingerprint());

  const hslam_test::ProgramRun convert = hslam_test::runProgram(
      m_program, "--convert " + m_dir + "/one.hvoc --format text --output " + m_dir + "/one.txt");
  ASSERT_EQ(convert.exitCode, 0) << convert.output;
  EXPECT_EQ(vpHSlamVocabulary::load(m_dir + "/one.txt").getFingerprint(), one.getFingerprint());

  // The score of an image with itself is 1, with another image lower.
  vpImage<unsigned char> klimt, solvay;
  vpImageIo::read(klimt, m_dir + "/train/a/Klimt.png");
  vpImageIo::read(solvay, m_dir + "/train/a/Solvay_conference_1927_Version2_640x440.png");
  EXPECT_NEAR(one.score(klimt, klimt), 1.0, 1e-12);
  EXPECT_LT(one.score(klimt, solvay), 0.5);
}

TEST_F(VocabularyTutorial, TrainsOnADatasetFolderWithAStep)
{
  HSLAM_REQUIRE_SHARED_DATA(kitti, "kitti06_000-050");
  const hslam_test::ProgramRun run = hslam_test::runProgram(
      m_program, "--images " + kitti + " --step 10 --branching 5 --levels 2 --output " + m_dir + "/k.hvoc");
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("6 images"), std::string::npos) << run.output; // frames 0, 10, ..., 50
  EXPECT_FALSE(vpHSlamVocabulary::load(m_dir + "/k.hvoc").empty());
}

TEST_F(VocabularyTutorial, TrainsOnAVideoUntilItsEnd)
{
  const std::string images = hslam_test::vispImagesDir();
  if (images.empty()) {
    GTEST_SKIP() << "visp-images-data not installed";
  }
  // cube.mpeg does not store its frame count: the program must stop at the end of the stream by itself.
  const hslam_test::ProgramRun run = hslam_test::runProgram(
      "timeout 120 " + m_program,
      "--images " + images + "/video/cube.mpeg --step 5 --branching 5 --levels 3 --output " + m_dir + "/v.hvoc");
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_NE(run.output.find("video frames"), std::string::npos) << run.output;
  EXPECT_FALSE(vpHSlamVocabulary::load(m_dir + "/v.hvoc").empty());
}

TEST_F(VocabularyTutorial, ClearErrors)
{
  hslam_test::ProgramRun run = hslam_test::runProgram(m_program, "--images " + m_dir + "/nothing --output x.hvoc");
  EXPECT_NE(run.exitCode, 0);
  EXPECT_NE(run.output.find("not found"), std::string::npos) << run.output;
  vpIoTools::makeDirectory(m_dir + "/empty");
  run = hslam_test::runProgram(m_program, "--images " + m_dir + "/empty --output " + m_dir + "/x.hvoc");
  EXPECT_NE(run.exitCode, 0);
  EXPECT_NE(run.output.find("need at least"), std::string::npos) << run.output;
  EXPECT_FALSE(vpIoTools::checkFilename(m_dir + "/x.hvoc"));
  run = hslam_test::runProgram(m_program, "--convert " + m_dir + "/missing.txt --output " + m_dir + "/x.hvoc");
  EXPECT_NE(run.exitCode, 0);
  EXPECT_NE(run.output.find("missing.txt"), std::string::npos) << run.output;
  run = hslam_test::runProgram(m_program, "--images a --levels 0 --output b");
  EXPECT_NE(run.exitCode, 0);
  run = hslam_test::runProgram(m_program, "--help");
  EXPECT_EQ(run.exitCode, 0);
  EXPECT_NE(run.output.find("--branching"), std::string::npos);
}

TEST(VocabularyDefault, DefaultPathHonoursTheEnvironment)
{
  const std::string shipped = vpHSlamVocabulary::defaultPath();
  ::setenv("HSLAM_VOCABULARY", "/some/where.hvoc", 1);
  EXPECT_EQ(vpHSlamVocabulary::defaultPath(), "/some/where.hvoc");
  ::unsetenv("HSLAM_VOCABULARY");
  EXPECT_EQ(vpHSlamVocabulary::defaultPath(), shipped);
  if (!shipped.empty()) {
    EXPECT_NE(shipped.find("hslam-orb.hvoc"), std::string::npos);
  }
}
} // namespace
