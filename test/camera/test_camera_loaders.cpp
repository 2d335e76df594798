// Calibration file readers of vpHSlamCamera (DSO camera.txt, ViSP XML, EuRoC/Kalibr YAML, KITTI calib.txt) on the
// shared sequences and on files written here, plus the line-parsing helpers they share. Broken files must give the
// documented error code and a message naming the file.
#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamException.h>

#include <visp3/core/vpColVector.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/core/vpMeterPixelConversion.h>
#include <visp3/core/vpXmlParserCamera.h>

#include "HSlamTestData.h"
#include "HSlamTestErrors.h"
#include "common/TextParsing.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

using hslam_test::expectHSlamError;

namespace
{
const double kTol = 1e-9; // values are read from text: exact up to double rounding

// A fresh temporary folder, removed with its content at the end of the test.
class TempDir
{
public:
  TempDir()
  {
    std::string pattern = (std::filesystem::temp_directory_path() / "hslam_loaders_XXXXXX").string();
    if (::mkdtemp(&pattern[0]) != nullptr) {
      m_path = pattern;
    }
  }
  ~TempDir()
  {
    std::error_code ec;
    if (!m_path.empty()) {
      std::filesystem::remove_all(m_path, ec);
    }
  }
  std::string write(const std::string &name, const std::string &content) const
  {
    const std::string path = m_path + "/" + name;
    std::ofstream out(path.c_str());
    out << content;
    return path;
  }
  std::string path(const std::string &name) const { return m_path + "/" + name; }
  bool ok() const { return !m_path.empty(); }

private:
  std::string m_path;
};

void expectIntrinsics(const vpHSlamCamera &cam, unsigned int w, unsigned int h, double fx, double fy, double cx,
                      double cy)
{
  EXPECT_EQ(cam.getWidth(), w);
  EXPECT_EQ(cam.getHeight(), h);
  EXPECT_NEAR(cam.getFx(), fx, kTol);
  EXPECT_NEAR(cam.getFy(), fy, kTol);
  EXPECT_NEAR(cam.getCx(), cx, kTol);
  EXPECT_NEAR(cam.getCy(), cy, kTol);
}

void expectDistortion(const vpHSlamCamera &cam, const std::vector<double> &expected)
{
  ASSERT_EQ(cam.getDistortion().size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NEAR(cam.getDistortion()[i], expected[i], kTol) << "coefficient " << i;
  }
}

void expectRectification(const vpHSlamCamera &cam, vpHSlamCamera::RectificationMode mode, unsigned int w,
                         unsigned int h)
{
  EXPECT_EQ(cam.getRectificationMode(), mode);
  EXPECT_EQ(cam.getRectifiedWidth(), w);
  EXPECT_EQ(cam.getRectifiedHeight(), h);
}
} // namespace

// ---------------------------------------------------------------------------------------------- shared data

TEST(CameraLoaders, sevenScenesTxtAndXmlAgree)
{
  HSLAM_REQUIRE_SHARED_DATA(txt, "7scenes_redkitchen_000-299/camera.txt");
  HSLAM_REQUIRE_SHARED_DATA(xml, "7scenes_redkitchen_000-299/camera.xml");
  const vpHSlamCamera a = vpHSlamCamera::loadDso(txt);
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  const vpHSlamCamera b = vpHSlamCamera::loadViSPXml(xml);
  const std::string printed = testing::internal::GetCapturedStdout() + testing::internal::GetCapturedStderr();
  EXPECT_EQ(printed, "") << "library code must not print";
  for (const vpHSlamCamera *cam : {&a, &b}) {
    EXPECT_EQ(cam->getModel(), vpHSlamCamera::pinhole);
    expectIntrinsics(*cam, 640, 480, 525, 525, 320, 240);
    EXPECT_TRUE(cam->getDistortion().empty());
    expectRectification(*cam, vpHSlamCamera::rectifyNone, 640, 480);
  }
  // load() picks the reader from the name.
  expectIntrinsics(vpHSlamCamera::load(txt), 640, 480, 525, 525, 320, 240);
  expectIntrinsics(vpHSlamCamera::load(xml), 640, 480, 525, 525, 320, 240);
}

TEST(CameraLoaders, tsukubaCameraTxt)
{
  HSLAM_REQUIRE_SHARED_DATA(txt, "tsukuba_cg_000-149/camera.txt");
  const vpHSlamCamera cam = vpHSlamCamera::load(txt);
  EXPECT_EQ(cam.getModel(), vpHSlamCamera::pinhole);
  expectIntrinsics(cam, 640, 480, 615, 615, 320, 240);
  EXPECT_EQ(cam.getRectificationMode(), vpHSlamCamera::rectifyNone);
}

TEST(CameraLoaders, kittiCalib)
{
  HSLAM_REQUIRE_SHARED_DATA(calib, "kitti06_000-050/calib.txt");
  const vpHSlamCamera cam = vpHSlamCamera::loadKittiCalib(calib, 1226, 370);
  EXPECT_EQ(cam.getModel(), vpHSlamCamera::pinhole);
  expectIntrinsics(cam, 1226, 370, 707.0912, 707.0912, 601.8873, 183.1104);
  EXPECT_EQ(cam.getRectificationMode(), vpHSlamCamera::rectifyNone);
  // P1 (right camera) shares K; only its fourth column differs.
  expectIntrinsics(vpHSlamCamera::loadKittiCalib(calib, 1226, 370, "P1"), 1226, 370, 707.0912, 707.0912, 601.8873,
                   183.1104);
  // load() recognises the P0 line; the size is required.
  expectIntrinsics(vpHSlamCamera::load(calib, 1226, 370), 1226, 370, 707.0912, 707.0912, 601.8873, 183.1104);
  expectHSlamError([&] { vpHSlamCamera::load(calib); }, vpHSlamException::invalidArgument, {calib});
  expectHSlamError([&] { vpHSlamCamera::loadKittiCalib(calib, 1226, 370, "P7"); }, vpHSlamException::parseError,
                   {calib, "P7:"});
}

TEST(CameraLoaders, eurocSensorYaml)
{
  HSLAM_REQUIRE_SHARED_DATA(yaml, "euroc_V1_01_easy_first95/mav0/cam0/sensor.yaml");
  for (const vpHSlamCamera &cam : {vpHSlamCamera::loadEurocYaml(yaml), vpHSlamCamera::load(yaml)}) {
    EXPECT_EQ(cam.getModel(), vpHSlamCamera::radialTangential);
    expectIntrinsics(cam, 752, 480, 458.654, 457.296, 367.215, 248.375);
    expectDistortion(cam, {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
    expectRectification(cam, vpHSlamCamera::rectifyCrop, 752, 480);
  }
}

// ---------------------------------------------------------------------------------------------- DSO camera.txt

TEST(CameraLoaders, dsoEachModel)
{
  TempDir dir;
  ASSERT_TRUE(dir.ok());
  {
    const vpHSlamCamera cam = vpHSlamCamera::loadDso(dir.write("pinhole.txt", "Pinhole 500 510 320 240 0\n640 480\n"));
    EXPECT_EQ(cam.getModel(), vpHSlamCamera::pinhole);
    expectIntrinsics(cam, 640, 480, 500, 510, 320, 240);
    EXPECT_TRUE(cam.getDistortion().empty());
    EXPECT_EQ(cam.getRectificationMode(), vpHSlamCamera::rectifyNone); // default for pinhole
  }
  {
    const vpHSlamCamera cam = vpHSlamCamera::loadDso(
        dir.write("radtan.txt", "RadTan 458.654 457.296 367.215 248.375 -0.28 0.07 0.0002 1.8e-05\n752 480\n"));
    EXPECT_EQ(cam.getModel(), vpHSlamCamera::radialTangential);
    expectIntrinsics(cam, 752, 480, 458.654, 457.296, 367.215, 248.375);
    expectDistortion(cam, {-0.28, 0.07, 0.0002, 1.8e-05});
    expectRectification(cam, vpHSlamCamera::rectifyCrop, 752, 480); // default for distorted models
  }
  for (const char *keyword : {"EquiDistant", "KannalaBrandt"}) {
    const vpHSlamCamera cam = vpHSlamCamera::loadDso(dir.write(
        "equi.txt", std::string(keyword) + " 190.97 190.97 254.93 256.89 0.0034 0.0007 -0.0020 0.0002\n512 512\n"));
    EXPECT_EQ(cam.getModel(), vpHSlamCamera::equidistant) << keyword;
    expectIntrinsics(cam, 512, 512, 190.97, 190.97, 254.93, 256.89);
    expectDistortion(cam, {0.0034, 0.0007, -0.0020, 0.0002});
  }
  {
    const vpHSlamCamera cam = vpHSlamCamera::loadDso(dir.write("fov.txt", "FOV 300 300 320 240 0.9\n640 480\n"));
    EXPECT_EQ(cam.getModel(), vpHSlamCamera::fov);
    expectIntrinsics(cam, 640, 480, 300, 300, 320, 240);
    expectDistortion(cam, {0.9});
  }
}

TEST(CameraLoaders, dsoRelativeIntrinsics)
{
  TempDir dir;
  ASSERT_TRUE(dir.ok());
  // DSO: relative fx*w, fy*h, cx*w - 0.5, cy*h - 0.5.
  const vpHSlamCamera cam = vpHSlamCamera::loadDso(dir.write("rel.txt", "Pinhole 0.5 0.6 0.5 0.25 0\n640 480\n"));
  expectIntrinsics(cam, 640, 480, 320.0, 288.0, 319.5, 119.5);

  // TUM monoVO's legacy keyword-less ATAN line (sequence_01), relative, with crop.
  const vpHSlamCamera tum = vpHSlamCamera::loadDso(
      dir.write("tum.txt", "0.349153000000000 0.436593000000000 0.493140000000000 0.499021000000000 "
                           "0.933271000000000\n1280 1024\ncrop\n640 480\n"));
  EXPECT_EQ(tum.getModel(), vpHSlamCamera::fov);
  expectIntrinsics(tum, 1280, 1024, 0.349153 * 1280, 0.436593 * 1024, 0.49314 * 1280 - 0.5, 0.499021 * 1024 - 0.5);
  expectDistortion(tum, {0.933271});
  expectRectification(tum, vpHSlamCamera::rectifyCrop, 640, 480);

  // cx >= 1: absolute, untouched even when fx < 1 would look relative on its own.
  expectIntrinsics(vpHSlamCamera::loadDso(dir.write("abs.txt", "Pinhole 0.9 0.9 1.5 0.5 0\n640 480\n")), 640, 480, 0.9,
                   0.9, 1.5, 0.5);
}

TEST(CameraLoaders, dsoLegacyForms)
{
  TempDir dir;
  ASSERT_TRUE(dir.ok());
  // Five bare numbers with omega 0: pinhole.
  const vpHSlamCamera pin = vpHSlamCamera::loadDso(dir.write("p.txt", "500 500 320 240 0\n640 480\nnone\n640 480\n"));
  EXPECT_EQ(pin.getModel(), vpHSlamCamera::pinhole);
  expectIntrinsics(pin, 640, 480, 500, 500, 320, 240);
  EXPECT_TRUE(pin.getDistortion().empty());
  // Eight bare numbers: DSO's backward-compatible RadTan.
  const vpHSlamCamera rt =
      vpHSlamCamera::loadDso(dir.write("r.txt", "500 500 320 240 -0.1 0.01 0.001 0.002\n640 480\n"));
  EXPECT_EQ(rt.getModel(), vpHSlamCamera::radialTangential);
  expectDistortion(rt, {-0.1, 0.01, 0.001, 0.002});
  // Windows line ends and trailing blank lines are tolerated.
  const vpHSlamCamera crlf =
      vpHSlamCamera::loadDso(dir.write("crlf.txt", "FOV 300 300 320 240 0.9\r\n640 480\r\n\r\n"));
  EXPECT_EQ(crlf.getModel(), vpHSlamCamera::fov);
  EXPECT_EQ(crlf.getWidth(), 640u);
}

TEST(CameraLoaders, dsoRectificationLines)
{
  TempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string radtan = "RadTan 458.654 457.296 367.215 248.375 -0.28 0.07 0.0002 1.8e-05\n752 480\n";

  const vpHSlamCamera full = vpHSlamCamera::loadDso(dir.write("full.txt", radtan + "full\n640 400\n"));
  expectRectification(full, vpHSlamCamera::rectifyFull, 640, 400);

  const vpHSlamCamera crop = vpHSlamCamera::loadDso(dir.write("crop.txt", radtan + "crop\n"));
  expectRectification(crop, vpHSlamCamera::rectifyCrop, 752, 480); // no fourth line: input size

  // Explicit and relative: scaled by the OUTPUT size, -0.5 on the principal point (DSO).
  const vpHSlamCamera rel = vpHSlamCamera::loadDso(dir.write("rel.txt", radtan + "0.4 0.6 0.5 0.5 0\n640 480\n"));
  expectRectification(rel, vpHSlamCamera::rectifyExplicit, 640, 480);
  const vpCameraParameters &K = rel.getExplicitRectifiedIntrinsics();
  EXPECT_NEAR(K.get_px(), 256.0, kTol);
  EXPECT_NEAR(K.get_py(), 288.0, kTol);
  EXPECT_NEAR(K.get_u0(), 319.5, kTol);
  EXPECT_NEAR(K.get_v0(), 239.5, kTol);

  // Explicit in pixels.
  const vpHSlamCamera abs = vpHSlamCamera::loadDso(dir.write("abs.txt", radtan + "300 310 320 240 0\n640 480\n"));
  EXPECT_EQ(abs.getRectificationMode(), vpHSlamCamera::rectifyExplicit);
  EXPECT_NEAR(abs.getExplicitRectifiedIntrinsics().get_px(), 300.0, kTol);
  EXPECT_NEAR(abs.getExplicitRectifiedIntrinsics().get_py(), 310.0, kTol);
  EXPECT_NEAR(abs.getExplicitRectifiedIntrinsics().get_u0(), 320.0, kTol);
  EXPECT_NEAR(abs.getExplicitRectifiedIntrinsics().get_v0(), 240.0, kTol);
}

TEST(CameraLoaders, dsoBrokenFiles)
{
  TempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string missing = dir.path("absent_camera.txt");
  expectHSlamError([&] { vpHSlamCamera::loadDso(missing); }, vpHSlamException::fileNotFound, {missing});
  expectHSlamError([&] { vpHSlamCamera::load(missing); }, vpHSlamException::fileNotFound, {missing});

  struct Case {
    const char *name;
    const char *content;
    vpHSlamException::ErrorCode code;
    const char *where; // ":line" expected in the message, or ""
  };
  const Case cases[] = {
      {"empty.txt", "", vpHSlamException::parseError, ":1"},
      {"blank.txt", "\n  \n", vpHSlamException::parseError, ":1"},
      {"truncated.txt", "Pinhole 500 500 320\n640 480\n", vpHSlamException::parseError, ":1"},
      {"extra.txt", "Pinhole 500 500 320 240 0 7\n640 480\n", vpHSlamException::parseError, ":1"},
      {"text.txt", "Pinhole 500 abc 320 240 0\n640 480\n", vpHSlamException::parseError, ":1"},
      {"legacy6.txt", "500 500 320 240 0 1\n640 480\n", vpHSlamException::parseError, ":1"},
      {"unknown.txt", "Mei 500 500 320 240 0.9\n640 480\n", vpHSlamException::unsupported, ":1"},
      {"nosize.txt", "Pinhole 500 500 320 240 0\n", vpHSlamException::parseError, ":2"},
      {"badsize.txt", "Pinhole 500 500 320 240 0\n640 x\n", vpHSlamException::parseError, ":2"},
      {"fracsize.txt", "Pinhole 500 500 320 240 0\n640.5 480\n", vpHSlamException::parseError, ":2"},
      {"negsize.txt", "Pinhole 500 500 320 240 0\n-640 480\n", vpHSlamException::parseError, ":2"},
      {"zerosize.txt", "Pinhole 500 500 320 240 0\n0 480\n", vpHSlamException::invalidCalibration, ":2"},
      {"zerooutsize.txt", "Pinhole 500 500 320 240 0\n640 480\ncrop\n640 0\n", vpHSlamException::invalidCalibration,
       ":4"},
      {"pinhole5.txt", "Pinhole 500 500 320 240 0.5\n640 480\n", vpHSlamException::invalidCalibration, ":1"},
      {"badrect.txt", "Pinhole 500 500 320 240 0\n640 480\nrectify\n640 480\n", vpHSlamException::parseError, ":3"},
      {"shortrect.txt", "Pinhole 500 500 320 240 0\n640 480\n300 300 320\n640 480\n", vpHSlamException::parseError,
       ":3"},
      {"gaprect.txt", "Pinhole 500 500 320 240 0\n640 480\n\n640 480\n", vpHSlamException::parseError, ":3"},
      {"none.txt", "Pinhole 500 500 320 240 0\n640 480\nnone\n320 240\n", vpHSlamException::invalidCalibration, ":4"},
      {"nanfocal.txt", "Pinhole nan 500 320 240 0\n640 480\n", vpHSlamException::parseError, ":1"},
      {"negfocal.txt", "Pinhole -500 500 320 240 0\n640 480\n", vpHSlamException::invalidCalibration, ""},
      {"radtan3.txt", "RadTan 500 500 320 240 0.1 0.2 0.3\n640 480\n", vpHSlamException::parseError, ":1"},
  };
  for (const Case &c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = dir.write(c.name, c.content);
    expectHSlamError([&] { vpHSlamCamera::loadDso(path); }, c.code, {path + c.where});
    expectHSlamError([&] { vpHSlamCamera::load(path); }, c.code, {path});
  }
  // A folder is not a file.
  expectHSlamError([&] { vpHSlamCamera::loadDso(dir.path("")); }, vpHSlamException::fileUnreadable, {dir.path("")});
}

// ---------------------------------------------------------------------------------------------- KITTI

TEST(CameraLoaders, kittiBrokenFiles)
{
  TempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string p0 = "P0: 7.0e+02 0 6.0e+02 0 0 7.0e+02 1.8e+02 0 0 0 1 0\n";
  const std::string good = dir.write("calib.txt", p0);
  expectIntrinsics(vpHSlamCamera::loadKittiCalib(good, 1226, 370), 1226, 370, 700, 700, 600, 180);
  expectHSlamError([&] { vpHSlamCamera::loadKittiCalib(good, 0, 370); }, vpHSlamException::invalidArgument, {good});
  expectHSlamError([&] { vpHSlamCamera::loadKittiCalib(good, 1226, 0); }, vpHSlamException::invalidArgument, {good});
  const std::string missing = dir.path("nocalib.txt");
  expectHSlamError([&] { vpHSlamCamera::loadKittiCalib(missing, 1226, 370); }, vpHSlamException::fileNotFound,
                   {missing});

  const std::string shortLine = dir.write("short.txt", "P0: 7.0e+02 0 6.0e+02 0 0 7.0e+02 1.8e+02 0 0 0 1\n");
  expectHSlamError([&] { vpHSlamCamera::loadKittiCalib(shortLine, 1226, 370); }, vpHSlamException::parseError,
                   {shortLine + ":1"});
  const std::string text = dir.write("text.txt", "P1: 1 2 3\nP0: 7.0e+02 0 6.0e+02 0 0 fx 1.8e+02 0 0 0 1 0\n");
  expectHSlamError([&] { vpHSlamCamera::loadKittiCalib(text, 1226, 370); }, vpHSlamException::parseError,
                   {text + ":2"});
  const std::string noP0 = dir.write("nop0.txt", "P1: 7.0e+02 0 6.0e+02 0 0 7.0e+02 1.8e+02 0 0 0 1 0\n");
  expectHSlamError([&] { vpHSlamCamera::loadKittiCalib(noP0, 1226, 370); }, vpHSlamException::parseError,
                   {noP0, "P0:"});
  const std::string skew = dir.write("skew.txt", "P0: 7.0e+02 3 6.0e+02 0 0 7.0e+02 1.8e+02 0 0 0 1 0\n");
  expectHSlamError([&] { vpHSlamCamera::loadKittiCalib(skew, 1226, 370); }, vpHSlamException::invalidCalibration,
                   {skew + ":1"});
}

// ---------------------------------------------------------------------------------------------- YAML

TEST(CameraLoaders, yamlVariantsAndErrors)
{
  TempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string head = "%YAML:1.0\ncamera_model: pinhole\nintrinsics: [190.97, 190.98, 254.93, 256.89]\n"
                           "resolution: [512, 512]\n";
  const vpHSlamCamera equi = vpHSlamCamera::loadEurocYaml(
      dir.write("equi.yaml", head + "distortion_model: equidistant\n"
                                    "distortion_coefficients: [0.0034, 0.0007, -0.0020, 0.0002]\n"));
  EXPECT_EQ(equi.getModel(), vpHSlamCamera::equidistant);
  expectIntrinsics(equi, 512, 512, 190.97, 190.98, 254.93, 256.89);
  expectDistortion(equi, {0.0034, 0.0007, -0.0020, 0.0002});

  const vpHSlamCamera none = vpHSlamCamera::loadEurocYaml(dir.write("none.yml", head + "distortion_model: none\n"));
  EXPECT_EQ(none.getModel(), vpHSlamCamera::pinhole);
  EXPECT_EQ(none.getRectificationMode(), vpHSlamCamera::rectifyNone);

  // Kalibr camchain (TUM-VI style): no %YAML directive, camera under cam0, distortion_coeffs.
  const vpHSlamCamera kalibr =
      vpHSlamCamera::load(dir.write("camchain.yaml", "cam0:\n  cam_overlaps: [1]\n  camera_model: pinhole\n"
                                                     "  distortion_coeffs: [0.0034, 0.0007, -0.0020, 0.0002]\n"
                                                     "  distortion_model: equidistant\n"
                                                     "  intrinsics: [190.97, 190.98, 254.93, 256.89]\n"
                                                     "  resolution: [512, 512]\n  rostopic: /cam0/image_raw\n"));
  EXPECT_EQ(kalibr.getModel(), vpHSlamCamera::equidistant);
  expectIntrinsics(kalibr, 512, 512, 190.97, 190.98, 254.93, 256.89);
  expectDistortion(kalibr, {0.0034, 0.0007, -0.0020, 0.0002});

  const std::string missing = dir.path("absent.yaml");
  expectHSlamError([&] { vpHSlamCamera::loadEurocYaml(missing); }, vpHSlamException::fileNotFound, {missing});
  struct Case {
    const char *name;
    std::string content;
    vpHSlamException::ErrorCode code;
  };
  const Case cases[] = {
      {"unknown.yaml", head + "distortion_model: mei\ndistortion_coefficients: [0.1]\n", vpHSlamException::unsupported},
      {"omni.yaml", "%YAML:1.0\ncamera_model: omni\nintrinsics: [1, 2, 3, 4, 5]\nresolution: [512, 512]\n",
       vpHSlamException::unsupported},
      {"nointr.yaml", "%YAML:1.0\ncamera_model: pinhole\nresolution: [512, 512]\n", vpHSlamException::parseError},
      {"textintr.yaml", "%YAML:1.0\ncamera_model: pinhole\nintrinsics: [1, abc, 3, 4]\nresolution: [512, 512]\n",
       vpHSlamException::parseError},
      {"nomodel.yaml", "%YAML:1.0\nfoo: 1\n", vpHSlamException::parseError},
      {"radtan3.yaml", head + "distortion_model: radtan\ndistortion_coefficients: [0.1, 0.2, 0.3]\n",
       vpHSlamException::invalidCalibration},
      {"nonezero.yaml", head + "distortion_model: none\ndistortion_coefficients: [0.1, 0, 0, 0]\n",
       vpHSlamException::invalidCalibration},
      {"zerores.yaml", "%YAML:1.0\ncamera_model: pinhole\nintrinsics: [1, 2, 3, 4]\nresolution: [0, 512]\n",
       vpHSlamException::invalidCalibration},
      {"syntax.yaml", "%YAML:1.0\ncamera_model: [pinhole\nintrinsics: {\n", vpHSlamException::parseError},
  };
  for (const Case &c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = dir.write(c.name, c.content);
    expectHSlamError([&] { vpHSlamCamera::loadEurocYaml(path); }, c.code, {path});
  }
}

// ---------------------------------------------------------------------------------------------- ViSP XML

TEST(CameraLoaders, vispXmlModels)
{
  TempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string xml = dir.write(
      "cams.xml", "<?xml version=\"1.0\"?>\n<root>\n"
                  "  <!-- <camera><name>commented</name></camera> -->\n"
                  "  <camera>\n    <name>plain</name>\n    <image_width>320</image_width>\n"
                  "    <image_height>240</image_height>\n    <model>\n"
                  "      <type>perspectiveProjWithoutDistortion</type>\n      <px>300</px>\n      <py>301</py>\n"
                  "      <u0>160</u0>\n      <v0>120</v0>\n    </model>\n  </camera>\n"
                  "  <camera>\n    <name>kud</name>\n    <image_width>640</image_width>\n"
                  "    <image_height>480</image_height>\n    <model>\n"
                  "      <type>perspectiveProjWithoutDistortion</type>\n      <px>600</px>\n      <py>600</py>\n"
                  "      <u0>320</u0>\n      <v0>240</v0>\n    </model>\n    <model>\n"
                  "      <type>perspectiveProjWithDistortion</type>\n      <px>610</px>\n      <py>611</py>\n"
                  "      <u0>321</u0>\n      <v0>241</v0>\n      <kud>-0.2</kud>\n      <kdu>0.21</kdu>\n"
                  "    </model>\n  </camera>\n"
                  "  <camera>\n    <name>kb</name>\n    <image_width>512</image_width>\n"
                  "    <image_height>512</image_height>\n    <model>\n"
                  "      <type>ProjWithKannalaBrandtDistortion</type>\n      <px>190</px>\n      <py>191</py>\n"
                  "      <u0>254</u0>\n      <v0>256</v0>\n      <k1>0.003</k1>\n      <k2>0.0007</k2>\n"
                  "      <k3>-0.002</k3>\n      <k4>0.0002</k4>\n      <k5>0</k5>\n    </model>\n  </camera>\n"
                  "</root>\n");
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  const vpHSlamCamera first = vpHSlamCamera::loadViSPXml(xml);
  const vpHSlamCamera kud = vpHSlamCamera::loadViSPXml(xml, "kud");
  const vpHSlamCamera kb = vpHSlamCamera::load(xml, 0, 0, "kb");
  EXPECT_EQ(testing::internal::GetCapturedStdout() + testing::internal::GetCapturedStderr(), "");

  EXPECT_EQ(first.getModel(), vpHSlamCamera::pinhole); // first non-commented camera
  expectIntrinsics(first, 320, 240, 300, 301, 160, 120);

  // The distorted model wins over the undistorted one of the same camera; kud is radtan's k1.
  EXPECT_EQ(kud.getModel(), vpHSlamCamera::radialTangential);
  expectIntrinsics(kud, 640, 480, 610, 611, 321, 241);
  expectDistortion(kud, {-0.2, 0.0, 0.0, 0.0});
  EXPECT_EQ(kud.getRectificationMode(), vpHSlamCamera::rectifyCrop);

  EXPECT_EQ(kb.getModel(), vpHSlamCamera::equidistant);
  expectIntrinsics(kb, 512, 512, 190, 191, 254, 256);
  expectDistortion(kb, {0.003, 0.0007, -0.002, 0.0002});

  // The mapping reproduces ViSP's own projection (vpMeterPixelConversion) exactly.
  vpCameraParameters vispKud;
  vispKud.initPersProjWithDistortion(610, 611, 321, 241, -0.2, 0.21);
  std::vector<double> kbCoeffs = {0.003, 0.0007, -0.002, 0.0002, 0.0};
  vpCameraParameters vispKb;
  vispKb.initProjWithKannalaBrandtDistortion(190, 191, 254, 256, kbCoeffs);
  const double points[][2] = {{0.0, 0.0}, {0.1, -0.05}, {-0.3, 0.25}, {0.4, 0.3}};
  for (const auto &xy : points) {
    vpColVector cP(3);
    cP[0] = xy[0];
    cP[1] = xy[1];
    cP[2] = 1.0;
    for (const auto &pair : {std::make_pair(&kud, &vispKud), std::make_pair(&kb, &vispKb)}) {
      vpImagePoint ours, visp;
      ASSERT_TRUE(pair.first->project(cP, ours));
      vpMeterPixelConversion::convertPoint(*pair.second, xy[0], xy[1], visp);
      EXPECT_NEAR(ours.get_u(), visp.get_u(), 1e-9);
      EXPECT_NEAR(ours.get_v(), visp.get_v(), 1e-9);
    }
  }
}

TEST(CameraLoaders, vispXmlSizesAndErrors)
{
  TempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string model = "    <model>\n      <type>perspectiveProjWithoutDistortion</type>\n      <px>300</px>\n"
                            "      <py>300</py>\n      <u0>160</u0>\n      <v0>120</v0>\n    </model>\n";
  const std::string nosize = dir.write("nosize.xml", "<?xml version=\"1.0\"?>\n<root>\n  <camera>\n"
                                                     "    <name>cam</name>\n" +
                                                         model + "  </camera>\n</root>\n");
  // Size not stored: taken from the arguments, required.
  expectIntrinsics(vpHSlamCamera::loadViSPXml(nosize, "", 320, 240), 320, 240, 300, 300, 160, 120);
  expectHSlamError([&] { vpHSlamCamera::loadViSPXml(nosize); }, vpHSlamException::invalidArgument, {nosize});

  const std::string sized = dir.write("sized.xml", "<?xml version=\"1.0\"?>\n<root>\n  <camera>\n"
                                                   "    <name>cam</name>\n    <image_width>320</image_width>\n"
                                                   "    <image_height>240</image_height>\n" +
                                                       model + "  </camera>\n</root>\n");
  expectIntrinsics(vpHSlamCamera::loadViSPXml(sized, "cam", 320, 240), 320, 240, 300, 300, 160, 120);
  expectHSlamError([&] { vpHSlamCamera::loadViSPXml(sized, "", 640, 480); }, vpHSlamException::invalidArgument,
                   {sized, "640x480"});
  expectHSlamError([&] { vpHSlamCamera::loadViSPXml(sized, "other"); }, vpHSlamException::invalidArgument,
                   {sized, "other"});

  const std::string missing = dir.path("absent.xml");
  expectHSlamError([&] { vpHSlamCamera::loadViSPXml(missing); }, vpHSlamException::fileNotFound, {missing});
  expectHSlamError([&] { vpHSlamCamera::load(missing); }, vpHSlamException::fileNotFound, {missing});

  const std::string nocam = dir.write("nocam.xml", "<?xml version=\"1.0\"?>\n<root>\n</root>\n");
  expectHSlamError([&] { vpHSlamCamera::loadViSPXml(nocam); }, vpHSlamException::parseError, {nocam});
  const std::string badtype =
      dir.write("badtype.xml", "<?xml version=\"1.0\"?>\n<root>\n  <camera>\n    <model>\n      <type>mei</type>\n"
                               "    </model>\n  </camera>\n</root>\n");
  expectHSlamError([&] { vpHSlamCamera::loadViSPXml(badtype, "", 320, 240); }, vpHSlamException::unsupported,
                   {badtype});
  const std::string nopx =
      dir.write("nopx.xml", "<?xml version=\"1.0\"?>\n<root>\n  <camera>\n    <image_width>320</image_width>\n"
                            "    <image_height>240</image_height>\n    <model>\n"
                            "      <type>perspectiveProjWithoutDistortion</type>\n      <py>300</py>\n"
                            "      <u0>160</u0>\n      <v0>120</v0>\n    </model>\n  </camera>\n</root>\n");
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  expectHSlamError([&] { vpHSlamCamera::loadViSPXml(nopx); }, vpHSlamException::parseError, {nopx});
  EXPECT_EQ(testing::internal::GetCapturedStdout() + testing::internal::GetCapturedStderr(), "");
  const std::string badwidth = dir.write("badwidth.xml", "<?xml version=\"1.0\"?>\n<root>\n  <camera>\n"
                                                         "    <image_width>wide</image_width>\n" +
                                                             model + "  </camera>\n</root>\n");
  expectHSlamError([&] { vpHSlamCamera::loadViSPXml(badwidth); }, vpHSlamException::parseError, {badwidth + ":4"});
}

// ---------------------------------------------------------------------------------------------- text helpers

TEST(TextParsing, numbersAndTokens)
{
  double v = 0.0;
  EXPECT_TRUE(hslam::tryParseDouble("1e-3", v));
  EXPECT_DOUBLE_EQ(v, 1e-3);
  EXPECT_TRUE(hslam::tryParseDouble("+2.5", v));
  EXPECT_DOUBLE_EQ(v, 2.5);
  EXPECT_TRUE(hslam::tryParseDouble("-7.070912000000e+02", v));
  EXPECT_DOUBLE_EQ(v, -707.0912);
  for (const char *bad : {"", "+", "abc", "1.5x", "1,5", "nan", "inf", " 1"}) {
    EXPECT_FALSE(hslam::tryParseDouble(bad, v)) << "'" << bad << "'";
  }
  EXPECT_EQ(hslam::parseUnsigned("640", "f.txt", 2, "width"), 640u);
  expectHSlamError([] { hslam::parseUnsigned("-3", "f.txt", 2, "width"); }, vpHSlamException::parseError,
                   {"f.txt:2", "width", "-3"});
  expectHSlamError([] { hslam::parseUnsigned("99999999999", "f.txt", 2, "width"); }, vpHSlamException::parseError,
                   {"f.txt:2"});
  expectHSlamError([] { hslam::parseDouble("x1", "g.csv", 17, "timestamp"); }, vpHSlamException::parseError,
                   {"g.csv:17", "timestamp", "'x1'"});

  const std::vector<std::string> tokens = hslam::splitWhitespace("  a\tbb   c \r");
  ASSERT_EQ(tokens.size(), 3u);
  EXPECT_EQ(tokens[1], "bb");
  EXPECT_EQ(tokens[2], "c");
  const std::vector<std::string> fields = hslam::splitFields("1403636579763555584, a.png,,x ", ',');
  ASSERT_EQ(fields.size(), 4u);
  EXPECT_EQ(fields[1], "a.png");
  EXPECT_EQ(fields[2], "");
  EXPECT_EQ(fields[3], "x");
  expectHSlamError([&] { hslam::expectTokenCount(tokens, 4, "h.txt", 9, "pose"); }, vpHSlamException::parseError,
                   {"h.txt:9", "expected 4", "found 3"});
}
