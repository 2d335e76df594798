// Trajectory formats: TUM / KITTI round trips, EuRoC ground truth + T_BS against the cam0 TUM file, broken files.
#include "HSlamTestData.h"

#include "io/TrajectoryIo.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamTrajectory.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <unistd.h>

namespace
{
//! Agreement of EuRoC csv + T_BS with the cam0 TUM file: equal up to the files' printed digits.
constexpr double kEurocPositionTolerance = 2e-6; // metres: both files print 6 decimals (measured 8.7e-7)
constexpr double kEurocAngleToleranceDeg = 2e-4; // degrees: 7-decimal quaternions (measured 6.4e-5)

//! A fresh file path in the temporary folder, removed at scope exit.
struct TempFile {
  std::string path;
  explicit TempFile(const std::string &name)
      : path(::testing::TempDir() + "/hslam_" + std::to_string(::getpid()) + "_" + name)
  {
  }
  ~TempFile() { std::remove(path.c_str()); }
  void write(const std::string &content) const
  {
    std::ofstream f(path);
    f << content;
  }
};

std::string readAll(const std::string &path)
{
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

vpHSlamTrajectory randomTrajectory(size_t n, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1., 1.);
  vpHSlamTrajectory trajectory;
  double t = 1403715273.262142976;
  for (size_t i = 0; i < n; ++i) {
    t += 0.05 + 0.01 * uniform(rng);
    trajectory.add(t, vpHomogeneousMatrix(100. * uniform(rng), 10. * uniform(rng), 1e-3 * uniform(rng),
                                          M_PI * uniform(rng), M_PI * uniform(rng), M_PI * uniform(rng)));
  }
  return trajectory;
}

//! The exception's message, for checks on what it names.
template <typename F> std::string errorOf(F f)
{
  try {
    f();
  } catch (const vpHSlamException &e) {
    return e.getStringMessage();
  }
  return "no exception";
}
} // namespace

TEST(TrajectoryIo, TumRoundTripIsExactToPrintedPrecision)
{
  const vpHSlamTrajectory original = randomTrajectory(300, 1);
  TempFile first("tum1.txt"), second("tum2.txt");
  original.saveTum(first.path);
  const vpHSlamTrajectory read = vpHSlamTrajectory::readTum(first.path);
  ASSERT_EQ(read.size(), original.size());
  for (size_t i = 0; i < read.size(); ++i) {
    // 9 decimals of seconds: 0.5e-9 of rounding, plus the double's own resolution at 1.4e9 s (2.4e-7).
    EXPECT_NEAR(read.getTimestamp(i), original.getTimestamp(i), 3e-7);
    for (unsigned int r = 0; r < 3; ++r) {
      // 10 significant digits of translation.
      EXPECT_NEAR(read.get_wMc(i)[r][3], original.get_wMc(i)[r][3], 5e-10 * std::abs(original.get_wMc(i)[r][3]));
      for (unsigned int c = 0; c < 3; ++c) {
        // 9 decimals of a unit quaternion: rotation entries within a few 1e-9.
        EXPECT_NEAR(read.get_wMc(i)[r][c], original.get_wMc(i)[r][c], 5e-9);
      }
    }
  }
  // Writing what was read prints the same text, line for line: no drift through repeated save/load.
  read.saveTum(second.path);
  std::istringstream a(readAll(first.path)), b(readAll(second.path));
  std::string la, lb;
  size_t lines = 0, identical = 0, identicalTimeAndPosition = 0;
  while (std::getline(a, la) && std::getline(b, lb)) {
    ++lines;
    identical += la == lb;
    // Timestamp and translation fields (first 4) are exact; the quaternion may move by one unit in the last
    // decimal through normalisation.
    std::istringstream fa(la), fb(lb);
    std::string xa, xb;
    bool same = true;
    for (int k = 0; k < 4 && (fa >> xa) && (fb >> xb); ++k) {
      same = same && xa == xb;
    }
    identicalTimeAndPosition += same;
  }
  EXPECT_EQ(lines, original.size() + 1);
  EXPECT_EQ(identicalTimeAndPosition, lines);
  EXPECT_GE(identical, lines * 9 / 10);
}

TEST(TrajectoryIo, KittiRoundTripIsBitExact)
{
  const vpHSlamTrajectory original = randomTrajectory(200, 2);
  TempFile first("kitti1.txt"), second("kitti2.txt"), times("times.txt");
  original.saveKitti(first.path);
  const vpHSlamTrajectory read = vpHSlamTrajectory::readKitti(first.path);
  ASSERT_EQ(read.size(), original.size());
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_DOUBLE_EQ(read.getTimestamp(i), static_cast<double>(i)); // row index without times or rate
    for (unsigned int r = 0; r < 3; ++r) {
      for (unsigned int c = 0; c < 4; ++c) {
        EXPECT_NEAR(read.get_wMc(i)[r][c], original.get_wMc(i)[r][c],
                    5e-10 * std::max(1., std::abs(original.get_wMc(i)[r][c])));
      }
    }
  }
  read.saveKitti(second.path);
  EXPECT_EQ(readAll(first.path), readAll(second.path));

  const vpHSlamTrajectory rated = vpHSlamTrajectory::readKitti(first.path, "", 10.);
  EXPECT_DOUBLE_EQ(rated.getTimestamp(7), 0.7);
  std::string timesText;
  for (size_t i = 0; i < original.size(); ++i) {
    timesText += std::to_string(0.25 * i) + "\n";
  }
  times.write(timesText);
  EXPECT_DOUBLE_EQ(vpHSlamTrajectory::readKitti(first.path, times.path).getTimestamp(9), 2.25);
  times.write("0\n0.1\n");
  EXPECT_NE(errorOf([&] { vpHSlamTrajectory::readKitti(first.path, times.path); }).find("2 times for 200 poses"),
            std::string::npos);
}

TEST(TrajectoryIo, KittiSharedGroundTruthMatchesItsTumVersion)
{
  HSLAM_REQUIRE_SHARED_DATA(kittiPath, "kitti06_000-050/groundtruth_kitti.txt");
  HSLAM_REQUIRE_SHARED_DATA(timesPath, "kitti06_000-050/times.txt");
  HSLAM_REQUIRE_SHARED_DATA(tumPath, "kitti06_000-050/groundtruth_tum.txt");
  const vpHSlamTrajectory kitti = vpHSlamTrajectory::readKitti(kittiPath, timesPath);
  const vpHSlamTrajectory tum = vpHSlamTrajectory::readTum(tumPath);
  ASSERT_EQ(kitti.size(), 51u);
  ASSERT_EQ(tum.size(), kitti.size());
  for (size_t i = 0; i < kitti.size(); ++i) {
    EXPECT_NEAR(kitti.getTimestamp(i), tum.getTimestamp(i), 1e-6);
    for (unsigned int r = 0; r < 3; ++r) {
      for (unsigned int c = 0; c < 4; ++c) {
        EXPECT_NEAR(kitti.get_wMc(i)[r][c], tum.get_wMc(i)[r][c], 1e-5);
      }
    }
  }
}

TEST(TrajectoryIo, EurocGroundTruthWithTbsAgreesWithCam0Tum)
{
  HSLAM_REQUIRE_SHARED_DATA(csvPath, "euroc_V1_01_easy_first95/mav0/state_groundtruth_estimate0/data.csv");
  HSLAM_REQUIRE_SHARED_DATA(yamlPath, "euroc_V1_01_easy_first95/mav0/cam0/sensor.yaml");
  HSLAM_REQUIRE_SHARED_DATA(tumPath, "euroc_V1_01_easy_first95/groundtruth_cam0_tum.txt");

  const vpHomogeneousMatrix bMc = vpHSlamTrajectory::readEurocSensorExtrinsics(yamlPath);
  EXPECT_DOUBLE_EQ(bMc[0][0], 0.0148655429818);
  EXPECT_DOUBLE_EQ(bMc[1][3], -0.064676986768);

  const vpHSlamTrajectory body = vpHSlamTrajectory::readEurocGroundTruth(csvPath);
  const vpHSlamTrajectory camera = vpHSlamTrajectory::readEurocGroundTruth(csvPath, yamlPath);
  const vpHSlamTrajectory reference = vpHSlamTrajectory::readTum(tumPath);
  ASSERT_GE(camera.size(), 95u);
  ASSERT_EQ(reference.size(), 95u);
  // The first csv row is the first image's stamp, 1403715273262142976 ns.
  EXPECT_NEAR(body.getTimestamp(0), 1403715273.262142976, 1e-6);

  // wMc = wMb * T_BS at the 95 image stamps must reproduce the cam0 TUM file up to its printed digits.
  double worstPosition = 0., worstAngleDeg = 0., worstBodyPosition = 0.;
  size_t j = 0;
  for (size_t i = 0; i < reference.size(); ++i) {
    while (j + 1 < camera.size() && std::abs(camera.getTimestamp(j + 1) - reference.getTimestamp(i)) <
                                        std::abs(camera.getTimestamp(j) - reference.getTimestamp(i))) {
      ++j;
    }
    ASSERT_NEAR(camera.getTimestamp(j), reference.getTimestamp(i), 1e-3);
    const vpHomogeneousMatrix &wMc = camera.get_wMc(j);
    const vpHomogeneousMatrix &wMr = reference.get_wMc(i);
    const vpTranslationVector dp = wMc.getTranslationVector() - wMr.getTranslationVector();
    worstPosition = std::max(worstPosition, dp.frobeniusNorm());
    const vpTranslationVector db = body.get_wMc(j).getTranslationVector() - wMr.getTranslationVector();
    worstBodyPosition = std::max(worstBodyPosition, db.frobeniusNorm());
    const vpThetaUVector dR((wMc.inverse() * wMr).getRotationMatrix());
    worstAngleDeg = std::max(worstAngleDeg, vpMath::deg(dR.getTheta()));
  }
  RecordProperty("worst_position_m", std::to_string(worstPosition));
  RecordProperty("worst_angle_deg", std::to_string(worstAngleDeg));
  std::cout << "EuRoC csv+T_BS vs cam0 TUM: worst position " << worstPosition << " m, worst angle " << worstAngleDeg
            << " deg (body frame without T_BS: " << worstBodyPosition << " m)" << std::endl;
  EXPECT_LT(worstPosition, kEurocPositionTolerance);
  EXPECT_LT(worstAngleDeg, kEurocAngleToleranceDeg);
  // T_BS must matter: without it the positions are further off than with it.
  EXPECT_GT(worstBodyPosition, 2. * worstPosition);
}

TEST(TrajectoryIo, BrokenFilesNameFileAndLine)
{
  const std::string missing = ::testing::TempDir() + "/hslam_no_such_trajectory.txt";
  EXPECT_NE(errorOf([&] { vpHSlamTrajectory::readTum(missing); }).find(missing), std::string::npos);
  try {
    vpHSlamTrajectory::readTum(missing);
    FAIL() << "no exception";
  } catch (const vpHSlamException &e) {
    EXPECT_EQ(e.getCode(), vpHSlamException::fileNotFound);
  }

  TempFile file("broken.txt");
  file.write("# header\n1.0 0 0 0 0 0 0 1\n\n2.0  0 0 0 0 0 0\n");
  EXPECT_NE(errorOf([&] { vpHSlamTrajectory::readTum(file.path); }).find(file.path + ":4:"), std::string::npos);

  file.write("1.0 0 0 0 0 0 0 1\n2.0 0 0 x 0 0 0 1\n");
  EXPECT_NE(errorOf([&] { vpHSlamTrajectory::readTum(file.path); }).find(file.path + ":2:"), std::string::npos);

  // Non-unit quaternion beyond 1e-3 is an error; within it, it is normalised.
  file.write("1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1.01\n");
  const std::string nonUnit = errorOf([&] { vpHSlamTrajectory::readTum(file.path); });
  EXPECT_NE(nonUnit.find(file.path + ":2:"), std::string::npos) << nonUnit;
  EXPECT_NE(nonUnit.find("norm"), std::string::npos) << nonUnit;
  file.write("   1.0\t0  0 0   0 0 0 1.0005   # trailing comment\n");
  const vpHSlamTrajectory tolerant = vpHSlamTrajectory::readTum(file.path);
  ASSERT_EQ(tolerant.size(), 1u);
  EXPECT_NEAR(tolerant.get_wMc(0)[0][0], 1., 1e-15);

  file.write("1.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n");
  EXPECT_NE(errorOf([&] { vpHSlamTrajectory::readTum(file.path); }).find(file.path + ":2:"), std::string::npos);

  file.write("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 2 0\n");
  EXPECT_NE(errorOf([&] { vpHSlamTrajectory::readKitti(file.path); }).find(file.path + ":2:"), std::string::npos);

  file.write("#timestamp, p, q\n1403715273262142976,0,0,0,1,0,0,0\n1403715273312143104,0,0,0,0.5,0,0,0\n");
  EXPECT_NE(errorOf([&] { vpHSlamTrajectory::readEurocGroundTruth(file.path); }).find(file.path + ":3:"),
            std::string::npos);

  file.write("%YAML:1.0\nrate_hz: 20\n");
  EXPECT_NE(errorOf([&] { vpHSlamTrajectory::readEurocSensorExtrinsics(file.path); }).find("T_BS"), std::string::npos);

  // Writing into a folder that does not exist fails loudly.
  file.write("1.0 0 0 0 0 0 0 1\n");
  const vpHSlamTrajectory one = vpHSlamTrajectory::readTum(file.path);
  EXPECT_THROW(one.saveTum(::testing::TempDir() + "/no_such_dir/x/traj.txt"), vpHSlamException);
}

TEST(TrajectoryIo, TimeSpanKeepsThePosesInsideItsBoundsInOrder)
{
  vpHSlamTrajectory trajectory;
  for (int i = 0; i < 10; ++i) {
    trajectory.add(0.5 * i, vpHomogeneousMatrix(i, 0., 0., 0., 0., 0.));
  }
  const vpHSlamTrajectory span = trajectory.timeSpan(1., 3.);
  ASSERT_EQ(span.size(), 5u); // 1.0, 1.5, 2.0, 2.5, 3.0: both bounds included
  for (size_t i = 0; i < span.size(); ++i) {
    EXPECT_EQ(span.getTimestamp(i), 1. + 0.5 * static_cast<double>(i));
    EXPECT_EQ(span.get_wMc(i)[0][3], 2. + static_cast<double>(i));
  }
  EXPECT_TRUE(trajectory.timeSpan(10., 20.).empty());
  EXPECT_EQ(trajectory.timeSpan(-1., 100.).size(), trajectory.size());
  EXPECT_NE(errorOf([&] { trajectory.timeSpan(3., 1.); }).find("not before"), std::string::npos);
  EXPECT_THROW(trajectory.timeSpan(std::nan(""), 1.), vpHSlamException);
}
