/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamCamera.h
  \brief Geometric calibration of the input camera and the pinhole image the system works in.
*/
#ifndef VP_HSLAM_CAMERA_H
#define VP_HSLAM_CAMERA_H

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpColVector.h>
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImagePoint.h>

#include <string>
#include <vector>

/*!
  \class vpHSlamCamera
  \ingroup group_hslam
  \brief Geometric calibration of a camera (one of four models) and the rectified pinhole target.

  What it is for: every image source reports one vpHSlamCamera; vpHSlamRectifier turns it into a remap table
  so that tracking and mapping only ever see an ideal pinhole image of the target size.

  Models and their distortion parameters (all pixel quantities in pixels of the input image, pixel centres at
  integer coordinates, (0,0) = centre of the top-left pixel, as in ViSP and OpenCV):
  - pinhole: no distortion parameter.
  - radialTangential: OpenCV's k1 k2 p1 p2 [k3] (4 or 5 values).
  - equidistant: Kannala-Brandt k1 k2 k3 k4 (OpenCV fisheye, EuRoC/TUM-VI "equidistant").
  - fov: the ATAN/FOV model of Devernay and Faugeras, one value omega (radians), as in TUM monoVO.

  The target of rectification (DSO camera.txt's third and fourth lines) is part of the calibration:
  - rectifyCrop: largest pinhole image with only valid pixels (DSO "crop"),
  - rectifyFull: pinhole image that keeps the whole input field of view (DSO "full"),
  - rectifyExplicit: given target intrinsics,
  - rectifyNone: pinhole model only; target = input intrinsics (DSO "none").

  Threading: a value type, no shared state.

  \code
  vpHSlamCamera cam = vpHSlamCamera::load("mav0/cam0/sensor.yaml");
  vpHSlamRectifier rectifier(cam);
  vpCameraParameters K = rectifier.getCameraParameters(); // the pinhole camera the system works with
  \endcode
*/
class VISP_EXPORT vpHSlamCamera
{
public:
  //! Geometric model of the input camera.
  enum Model {
    pinhole,          //!< fx fy cx cy, no distortion
    radialTangential, //!< OpenCV k1 k2 p1 p2 [k3]
    equidistant,      //!< Kannala-Brandt k1 k2 k3 k4
    fov               //!< ATAN / FOV, omega in radians
  };

  //! How the rectified pinhole target is chosen.
  enum RectificationMode {
    rectifyNone,    //!< keep the input intrinsics (only meaningful for a pinhole input)
    rectifyCrop,    //!< largest valid-pixel-only pinhole image (default for distorted models)
    rectifyFull,    //!< pinhole image covering the whole input field of view
    rectifyExplicit //!< intrinsics given with setRectification()
  };

  //! A pinhole 640x480 camera with fx = fy = 500 px and centred principal point.
  vpHSlamCamera();

  /*!
    Build a calibration.
    \param model : geometric model.
    \param width, height : input image size in pixels.
    \param fx, fy, cx, cy : focal lengths and principal point, pixels.
    \param distortion : model parameters, see the class documentation for their count.
    \exception vpHSlamException::invalidCalibration if the parameter count does not match the model or a value
    is out of range (non-positive size or focal length, omega not in (0, pi)).
  */
  vpHSlamCamera(Model model, unsigned int width, unsigned int height, double fx, double fy, double cx, double cy,
                const std::vector<double> &distortion = std::vector<double>());

  /*!
    Load a calibration file, the format chosen from its name and content:
    - `*.xml`: ViSP camera XML (vpXmlParserCamera); first camera, or the one named \e cameraName,
    - `*.yaml` / `*.yml`: EuRoC / TUM-VI / Kalibr-style `sensor.yaml` (camera_model, distortion_model fields),
    - `calib.txt` with a `P0:` line: KITTI odometry (image size from \e width, \e height, required),
    - anything else: DSO `camera.txt`.
    \param path : file to read.
    \param width, height : image size for formats that do not store it (KITTI); 0 otherwise.
    \param cameraName : camera to select in a ViSP XML file (empty: first).
    \exception vpHSlamException naming the file (and line) when missing or malformed.
  */
  static vpHSlamCamera load(const std::string &path, unsigned int width = 0, unsigned int height = 0,
                            const std::string &cameraName = "");

  //! Read a DSO `camera.txt` (all four models, relative or absolute intrinsics, rectification lines).
  static vpHSlamCamera loadDso(const std::string &path);
  //! Read a ViSP camera XML file (vpXmlParserCamera). Size must be stored in the file or given.
  static vpHSlamCamera loadViSPXml(const std::string &path, const std::string &cameraName = "", unsigned int width = 0,
                                   unsigned int height = 0);
  //! Read an EuRoC / TUM-VI `sensor.yaml` (pinhole + radial-tangential or equidistant).
  static vpHSlamCamera loadEurocYaml(const std::string &path);
  //! Read a KITTI odometry `calib.txt` (the \e projection line, default "P0"); image size must be given.
  static vpHSlamCamera loadKittiCalib(const std::string &path, unsigned int width, unsigned int height,
                                      const std::string &projection = "P0");

  Model getModel() const { return m_model; }          //!< geometric model of the input images
  unsigned int getWidth() const { return m_width; }   //!< input width, pixels
  unsigned int getHeight() const { return m_height; } //!< input height, pixels
  double getFx() const { return m_fx; }               //!< pixels
  double getFy() const { return m_fy; }               //!< pixels
  double getCx() const { return m_cx; }               //!< pixels
  double getCy() const { return m_cy; }               //!< pixels
  //! Distortion coefficients in the order of the model (radtan: k1 k2 p1 p2 [k3]; equidistant: k1..k4; FOV: w).
  const std::vector<double> &getDistortion() const { return m_distortion; }

  //! Input intrinsics without distortion, as ViSP camera parameters.
  vpCameraParameters getIntrinsics() const;

  /*!
    Choose the rectified target.
    \param mode : see RectificationMode.
    \param width, height : target size in pixels; 0 keeps the input size.
    \param K : target intrinsics, used only with rectifyExplicit.
  */
  void setRectification(RectificationMode mode, unsigned int width = 0, unsigned int height = 0,
                        const vpCameraParameters &K = vpCameraParameters());
  RectificationMode getRectificationMode() const { return m_rectMode; } //!< see setRectification()
  unsigned int getRectifiedWidth() const { return m_rectWidth; }        //!< pixels
  unsigned int getRectifiedHeight() const { return m_rectHeight; }      //!< pixels
  //! Explicit target intrinsics (rectifyExplicit only).
  const vpCameraParameters &getExplicitRectifiedIntrinsics() const { return m_rectK; }

  /*!
    Project a point given in the camera frame (metres, z forward) to input pixels through the model.
    \return false when the point is behind the camera or outside the model's valid domain.
  */
  bool project(const vpColVector &cP, vpImagePoint &ip) const;
  /*!
    Back-project an input pixel to a viewing ray in the camera frame, normalised to z = 1 (for fov and
    equidistant, rays beyond 90 degrees cannot be normalised this way and return false).
  */
  bool unproject(const vpImagePoint &ip, vpColVector &ray) const;

  //! Model name as used in DSO's camera.txt ("Pinhole", "RadTan", "EquiDistant", "FOV").
  static std::string modelName(Model model);
  //! One-line human-readable summary.
  std::string toString() const;

private:
  Model m_model;
  unsigned int m_width, m_height;
  double m_fx, m_fy, m_cx, m_cy;
  std::vector<double> m_distortion;
  RectificationMode m_rectMode;
  unsigned int m_rectWidth, m_rectHeight;
  vpCameraParameters m_rectK;
};

#endif
