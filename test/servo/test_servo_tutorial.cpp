// Servoing with H-SLAM in the loop: the Sim(3) that fixes the monocular scale and frame (exact data), and the
// built tutorial-hslam-servo run end to end on a short task, asserting convergence to the goal.
#include "HSlamTestData.h"
#include "HSlamTestPrograms.h"

// The alignment helper lives beside the servo program (header-only, ViSP core only).
#include "../../tutorials/servo/Sim3FromPoses.h"

#include <visp3/core/vpMath.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace
{
//! Value of "key=<number>" at the start of an output line, NaN when absent.
double valueOf(const std::string &output, const std::string &key)
{
  const std::string text = "\n" + output;
  const size_t pos = text.find("\n" + key + "=");
  if (pos == std::string::npos) {
    return std::nan("");
  }
  return std::strtod(text.c_str() + pos + key.size() + 2, nullptr);
}

double angleDeg(const vpRotationMatrix &R)
{
  return vpMath::deg(vpThetaUVector(R).getTheta());
}

#define HSLAM_REQUIRE_SERVO_TUTORIAL(program)                                                                          \
  const std::string program = hslam_test::builtTutorialPath("tutorial-hslam-servo");                                   \
  if (program.empty()) {                                                                                               \
    GTEST_SKIP() << "tutorial-hslam-servo not built next to this test (HSLAM_BUILD_TUTORIALS=ON and ViSP's visp_vs)";  \
  }

// A semicircle with some rotation, mapped into a SLAM frame by a known Sim(3): the alignment must give it back.
std::vector<vpHomogeneousMatrix> semicirclePoses(const vpHomogeneousMatrix &wMc0, unsigned int count)
{
  std::vector<vpHomogeneousMatrix> wMc;
  for (unsigned int i = 0; i < count; ++i) {
    const double a = M_PI * i / (count - 1);
    wMc.push_back(wMc0 * vpHomogeneousMatrix(0.12 * std::sin(a), 0.12 * (1. - std::cos(a)), 0.01 * i / count, 0.,
                                             vpMath::rad(0.1 * i), 0.));
  }
  return wMc;
}
} // namespace

TEST(ServoAlignment, RecoversAKnownSim3FromExactPoses)
{
  const vpHomogeneousMatrix gMc0(0.3, -0.2, 0.1, vpMath::rad(5.), vpMath::rad(-20.), vpMath::rad(3.));
  const std::vector<vpHomogeneousMatrix> gMc = semicirclePoses(gMc0, 46);
  // SLAM world e: rotated, shifted and scaled (SLAM units = metres / 3.5).
  const vpHomogeneousMatrix eMg(0.5, 1., -2., vpMath::rad(40.), vpMath::rad(-70.), vpMath::rad(10.));
  const double metresPerUnit = 3.5;
  std::vector<vpHomogeneousMatrix> eMc;
  for (const vpHomogeneousMatrix &M : gMc) {
    const vpHomogeneousMatrix eMcMetres = eMg * M;
    eMc.push_back(
        vpHomogeneousMatrix(eMcMetres.getTranslationVector() * (1. / metresPerUnit), eMcMetres.getRotationMatrix()));
  }
  const hslam_servo::Sim3 sim3 = hslam_servo::alignSim3(eMc, gMc);
  EXPECT_NEAR(sim3.scale, metresPerUnit, 1e-9);
  EXPECT_LT(sim3.rmseMetres, 1e-9);
  const vpHomogeneousMatrix difference = sim3.gMe * eMg; // identity when gMe = eMg^-1
  EXPECT_LT(std::sqrt(difference.getTranslationVector().sumSquare()), 1e-9);
  EXPECT_LT(angleDeg(difference.getRotationMatrix()), 1e-7);
  for (size_t i = 0; i < eMc.size(); ++i) {
    const vpHomogeneousMatrix error = hslam_servo::toWorld(sim3, eMc[i]).inverse() * gMc[i];
    ASSERT_LT(std::sqrt(error.getTranslationVector().sumSquare()), 1e-9) << "pose " << i;
  }
}

TEST(ServoAlignment, RotationComesFromOrientationsNotFromNoisyPositions)
{
  // Positions disturbed by +-1 mm (about the SLAM's error on the initialisation path), orientations exact: the
  // rotation must stay exact, while the scale and translation absorb the noise only a little.
  const vpHomogeneousMatrix gMc0(0., -0.2, 0., 0., vpMath::rad(10.), 0.);
  const std::vector<vpHomogeneousMatrix> gMc = semicirclePoses(gMc0, 46);
  std::vector<vpHomogeneousMatrix> eMc;
  for (size_t i = 0; i < gMc.size(); ++i) {
    const double wobble = 1e-3 * ((i % 3 == 0) ? 1. : -0.5);
    eMc.push_back(vpHomogeneousMatrix(gMc[i].getTranslationVector() + vpTranslationVector(wobble, -wobble, wobble),
                                      gMc[i].getRotationMatrix()));
  }
  const hslam_servo::Sim3 sim3 = hslam_servo::alignSim3(eMc, gMc);
  EXPECT_LT(angleDeg(sim3.gMe.getRotationMatrix()), 1e-7);
  EXPECT_NEAR(sim3.scale, 1., 0.02);
  EXPECT_GT(sim3.rmseMetres, 1e-4); // the noise is seen in the residual
  EXPECT_LT(sim3.rmseMetres, 2e-3);
}

TEST(ServoAlignment, RefusesDegenerateInput)
{
  const std::vector<vpHomogeneousMatrix> one(1), two(2);
  EXPECT_THROW(hslam_servo::alignSim3(one, one), vpException);
  EXPECT_THROW(hslam_servo::alignSim3(two, one), vpException);
  EXPECT_THROW(hslam_servo::alignSim3(two, two), vpException); // SLAM centres do not move: no scale
}

namespace
{
/*!
  Runs the servo program with \e options on 480x360 images and checks that it converged to the default goal (0.39 m
  and 12.6 degrees from the start, 0.49 m from the end of the initialisation path). 480x360: the two-view
  initialisation failed on one start pose of six at 400x300 and on every one tried at 320x240; at 480x360 it
  succeeded on all eight seeds tried, with and without noise.
*/
void expectConvergence(const std::string &program, const std::string &options)
{
  const std::string plot = ::testing::TempDir() + "/hslam_servo_" + std::to_string(::getpid()) + ".png";
  const hslam_test::ProgramRun run =
      hslam_test::runProgram(program, "--width 480 --height 360 --print-every 10 --plot " + plot + " " + options);
  ASSERT_EQ(run.exitCode, 0) << run.output;
  EXPECT_EQ(valueOf(run.output, "converged"), 1.) << run.output;
  // The Sim(3) came from the whole initialisation path (46 poses: the frames before initialisation are tracked
  // backwards) and fits it to under a millimetre (measured 0.62-0.81 mm over seeds 1-8, noise 0 and 2).
  EXPECT_GE(valueOf(run.output, "sim3_poses"), 40.) << run.output;
  EXPECT_LT(valueOf(run.output, "sim3_rmse_m"), 0.003) << run.output;
  // Convergence in under 3 s of servoing (measured 80-83 iterations): a speed-bounded straight approach, then
  // the exponential tail of the adaptive gain.
  EXPECT_LT(valueOf(run.output, "iterations"), 150.) << run.output;
  // The camera stops where the SLAM says the goal is, so the true error left is the SLAM's error there. Measured
  // at this size over seeds 1-8 without noise and 1, 3, 5, 7 with noise 2: 0.27-1.24 mm and 0.002-0.016 degrees.
  // Tolerances: 5 mm, 4x the worst, is 1.3 % of the start distance (a 2 % scale error in the alignment would
  // exceed it); 0.1 degree, 6x the worst.
  EXPECT_LT(valueOf(run.output, "final_translation_error_m"), 0.005) << run.output;
  EXPECT_LT(valueOf(run.output, "final_rotation_error_deg"), 0.1) << run.output;
  // The SLAM was in the loop: its error is not zero and is of the size of the final error.
  const double slamError = valueOf(run.output, "final_slam_translation_error_m");
  EXPECT_GT(slamError, 0.) << run.output;
  EXPECT_LT(slamError, 0.005) << run.output;
  std::ifstream png(plot, std::ios::binary | std::ios::ate);
  EXPECT_GT(png.tellg(), 10000) << "plot not written: " << plot;
  std::remove(plot.c_str());
}

#define HSLAM_REQUIRE_VISP_IMAGES()                                                                                    \
  if (hslam_test::vispImagesDir().empty()) {                                                                           \
    GTEST_SKIP() << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene";                \
  }
} // namespace

TEST(ServoTutorial, ConvergesToTheGoalWithSlamInTheLoop)
{
  HSLAM_REQUIRE_SERVO_TUTORIAL(program);
  HSLAM_REQUIRE_VISP_IMAGES();
  expectConvergence(program, "--seed 1"); // measured: 80 iterations, 1.24 mm, 0.010 degrees
}

TEST(ServoTutorial, ConvergesFromAnotherStartWithImageNoise)
{
  HSLAM_REQUIRE_SERVO_TUTORIAL(program);
  HSLAM_REQUIRE_VISP_IMAGES();
  expectConvergence(program, "--seed 5 --noise 2"); // measured: 80 iterations, 0.75 mm, 0.003 degrees
}

// Tag mode: the scale and frame come from a 40 cm tag on the wall, about 3.3 m away (vpHSlam::setTag), instead of
// the semicircle's known poses. The goal is the semicircle mode's physical goal, given in the tag's frame: the servo
// must converge at least as fast (same path, same law: measured 80 iterations in both modes, 10 % allowed). Where
// it stops is where the tag's frame says the goal is: measured 7.1 mm and 0.78 degree from the true goal, the
// frame's own error after three keyframe sightings of a 45-pixel tag in the 1.5 s path (the semicircle mode's
// frame comes from the simulator's exact poses: 1.2 mm, 0.01 degree). The 5 mm and 0.1 degree are NOT
// reached (docs/metric-tag-frame.md); the bounds here, 2 cm and 1.5 degrees, catch a frame that is wrong.
TEST(ServoTutorial, TagModeConvergesToAGoalInTheTagFrameAsFastAsTheSemicircle)
{
  HSLAM_REQUIRE_SERVO_TUTORIAL(program);
  HSLAM_REQUIRE_VISP_IMAGES();
  const std::string common = "--width 480 --height 360 --print-every 20 --plot '' --seed 1 ";
  const hslam_test::ProgramRun tag = hslam_test::runProgram(program, common + "--tag 0.4");
  if (tag.output.find("cannot draw the tag") != std::string::npos) {
    GTEST_SKIP() << "libapriltag-dev not found at build time: tutorial-hslam-servo has no tag mode";
  }
  ASSERT_EQ(tag.exitCode, 0) << tag.output;
  EXPECT_NE(tag.output.find("mode=tag"), std::string::npos) << tag.output;
  EXPECT_EQ(valueOf(tag.output, "converged"), 1.) << tag.output;
  EXPECT_LT(valueOf(tag.output, "final_translation_error_m"), 0.02) << tag.output;
  EXPECT_LT(valueOf(tag.output, "final_rotation_error_deg"), 1.5) << tag.output;
  const hslam_test::ProgramRun semicircle = hslam_test::runProgram(program, common);
  ASSERT_EQ(semicircle.exitCode, 0) << semicircle.output;
  const double tagIterations = valueOf(tag.output, "iterations");
  const double semicircleIterations = valueOf(semicircle.output, "iterations");
  std::cout << "tag mode: " << tagIterations << " iterations, final error "
            << valueOf(tag.output, "final_translation_error_m") << " m "
            << valueOf(tag.output, "final_rotation_error_deg") << " deg; semicircle: " << semicircleIterations
            << " iterations, " << valueOf(semicircle.output, "final_translation_error_m") << " m" << std::endl;
  EXPECT_LE(tagIterations, 1.1 * semicircleIterations);
}

TEST(ServoTutorial, RefusesBadOptions)
{
  HSLAM_REQUIRE_SERVO_TUTORIAL(program);
  const hslam_test::ProgramRun unknown = hslam_test::runProgram(program, "--no-such-option 1");
  EXPECT_EQ(unknown.exitCode, 1) << unknown.output;
  EXPECT_NE(unknown.output.find("Unknown option"), std::string::npos) << unknown.output;
  const hslam_test::ProgramRun badGoal = hslam_test::runProgram(program, "--goal-translation 0.1,0.2");
  EXPECT_EQ(badGoal.exitCode, 1) << badGoal.output;
  EXPECT_NE(badGoal.output.find("Bad value for --goal-translation"), std::string::npos) << badGoal.output;
  // An initialisation path faster than the tracker is tested for (2 cm per frame) is refused before any rendering.
  const hslam_test::ProgramRun fast = hslam_test::runProgram(program, "--init-frames 10 --init-radius 0.3 --plot ''");
  EXPECT_EQ(fast.exitCode, 1) << fast.output;
  EXPECT_NE(fast.output.find("initialisation path would move"), std::string::npos) << fast.output;
  const hslam_test::ProgramRun tagGoal = hslam_test::runProgram(program, "--tag-goal-translation 0,0,1 --plot ''");
  EXPECT_EQ(tagGoal.exitCode, 1) << tagGoal.output;
  EXPECT_NE(tagGoal.output.find("need --tag"), std::string::npos) << tagGoal.output;
  const hslam_test::ProgramRun badTag = hslam_test::runProgram(program, "--tag -0.2");
  EXPECT_EQ(badTag.exitCode, 1) << badTag.output;
  EXPECT_NE(badTag.output.find("Bad value for --tag"), std::string::npos) << badTag.output;
  const hslam_test::ProgramRun help = hslam_test::runProgram(program, "--help");
  EXPECT_EQ(help.exitCode, 0);
  EXPECT_NE(help.output.find("Sim(3)"), std::string::npos) << "the help explains how the scale is fixed";
}
