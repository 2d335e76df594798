/*
 * H-SLAM for ViSP.
 */
/*!
  \file CameraModel.h
  \brief Internal geometric camera models (pinhole, radial-tangential, equidistant, FOV) on Eigen doubles.
*/
#ifndef HSLAM_CAMERA_MODEL_H
#define HSLAM_CAMERA_MODEL_H

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamCamera.h>

#include <Eigen/Core>

#include <memory>

namespace hslam
{

/*!
  Abstract geometric camera model: maps a 3D point in the camera frame (z forward) to input pixels and a pixel
  back to a viewing ray. Pixel convention: (0,0) is the centre of the top-left pixel (ViSP, OpenCV).

  Models are immutable after construction (safe to share between threads). project() and unproject() are virtual:
  call them per point or to build tables, never per pixel in a hot loop (vpHSlamRectifier precomputes a remap).

  Exported (VISP_EXPORT) because the camera tests instantiate the models directly.
*/
class VISP_EXPORT CameraModel
{
public:
  CameraModel(double fx, double fy, double cx, double cy);
  virtual ~CameraModel();

  /*!
    Project a point of the camera frame to input pixels.
    \param p : point in the camera frame (any unit; only its direction matters).
    \param uv : pixel (u right, v down).
    \param J_p : if not null, receives d(uv)/d(p).
    \return false when p is outside the model's valid domain (behind the camera for pinhole, radtan, fov;
    beyond the largest angle where the distortion stays monotonic for radtan and equidistant). uv and J_p are
    then unspecified. A true result does not mean uv lies inside the image.
  */
  virtual bool project(const Eigen::Vector3d &p, Eigen::Vector2d &uv,
                       Eigen::Matrix<double, 2, 3> *J_p = nullptr) const = 0;

  /*!
    Back-project a pixel to a viewing ray of UNIT norm in the camera frame (z may be <= 0 for wide fisheye
    equidistant lenses).
    \return false when the pixel is outside the model's valid domain or the iterative inversion did not converge.
  */
  virtual bool unproject(const Eigen::Vector2d &uv, Eigen::Vector3d &ray) const = 0;

  //! Which model this is.
  virtual vpHSlamCamera::Model model() const = 0;

  double fx() const { return m_fx; } //!< pixels
  double fy() const { return m_fy; } //!< pixels
  double cx() const { return m_cx; } //!< pixels
  double cy() const { return m_cy; } //!< pixels

protected:
  //! Normalised image coordinates of a pixel (distorted plane).
  Eigen::Vector2d pixelToNormalised(const Eigen::Vector2d &uv) const
  {
    return Eigen::Vector2d((uv.x() - m_cx) / m_fx, (uv.y() - m_cy) / m_fy);
  }

  //! Pixel Jacobian from the Jacobian \e Jm of the normalised image point: rows scaled by fx and fy.
  Eigen::Matrix<double, 2, 3> scaleToPixels(const Eigen::Matrix<double, 2, 3> &Jm) const
  {
    Eigen::Matrix<double, 2, 3> J;
    J.row(0) = m_fx * Jm.row(0);
    J.row(1) = m_fy * Jm.row(1);
    return J;
  }

  //! The undistorted perspective projection (pinhole model, and every model on its optical axis).
  bool projectPerspective(const Eigen::Vector3d &p, Eigen::Vector2d &uv, Eigen::Matrix<double, 2, 3> *J_p) const;

  double m_fx, m_fy, m_cx, m_cy;
};

//! Ideal perspective camera: u = fx x/z + cx.
class VISP_EXPORT PinholeModel : public CameraModel
{
public:
  PinholeModel(double fx, double fy, double cx, double cy);
  bool project(const Eigen::Vector3d &p, Eigen::Vector2d &uv,
               Eigen::Matrix<double, 2, 3> *J_p = nullptr) const override;
  bool unproject(const Eigen::Vector2d &uv, Eigen::Vector3d &ray) const override;
  vpHSlamCamera::Model model() const override { return vpHSlamCamera::pinhole; }
};

/*!
  OpenCV's radial-tangential ("plumb bob") model, k1 k2 p1 p2 [k3] (OpenCV calib3d documentation, EuRoC
  "radial-tangential"). The valid domain is the disc of undistorted radius where the radial map
  r (1 + k1 r^2 + k2 r^4 + k3 r^6) is still increasing, so that unprojection is unique.
*/
class VISP_EXPORT RadTanModel : public CameraModel
{
public:
  RadTanModel(double fx, double fy, double cx, double cy, double k1, double k2, double p1, double p2, double k3 = 0.0);
  bool project(const Eigen::Vector3d &p, Eigen::Vector2d &uv,
               Eigen::Matrix<double, 2, 3> *J_p = nullptr) const override;
  bool unproject(const Eigen::Vector2d &uv, Eigen::Vector3d &ray) const override;
  vpHSlamCamera::Model model() const override { return vpHSlamCamera::radialTangential; }

  //! Largest valid undistorted radius in the z = 1 plane (infinity when the radial map never folds).
  double maxRadius() const { return m_maxRadius; }

  /*!
    Distort a point of the z = 1 plane.
    \param m : undistorted normalised point.
    \param J : if not null, receives d(distorted)/d(m).
  */
  Eigen::Vector2d distort(const Eigen::Vector2d &m, Eigen::Matrix2d *J = nullptr) const;

private:
  double m_k1, m_k2, m_p1, m_p2, m_k3;
  double m_maxRadius;
};

/*!
  Kannala-Brandt equidistant fisheye model as in OpenCV's fisheye module and EuRoC/TUM-VI "equidistant":
  theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8), distorted point = theta_d * (x, y) / r.
  theta is measured from the optical axis with atan2(r, z), so rays beyond 90 degrees are handled (TUM-VI lenses
  see about 195 degrees); for z > 0 it equals OpenCV's atan(r / z). Valid domain: theta up to the first angle
  where theta_d stops increasing (at most pi).
*/
class VISP_EXPORT EquidistantModel : public CameraModel
{
public:
  EquidistantModel(double fx, double fy, double cx, double cy, double k1, double k2, double k3, double k4);
  bool project(const Eigen::Vector3d &p, Eigen::Vector2d &uv,
               Eigen::Matrix<double, 2, 3> *J_p = nullptr) const override;
  bool unproject(const Eigen::Vector2d &uv, Eigen::Vector3d &ray) const override;
  vpHSlamCamera::Model model() const override { return vpHSlamCamera::equidistant; }

  //! Largest valid angle from the optical axis, radians.
  double maxTheta() const { return m_maxTheta; }

private:
  double thetaD(double theta) const;
  double thetaDDerivative(double theta) const;

  double m_k1, m_k2, m_k3, m_k4;
  double m_maxTheta;
  double m_maxThetaD;
};

/*!
  FOV / ATAN model of Devernay and Faugeras as used by TUM monoVO and DSO (UndistortFOV):
  r_d = atan(2 r tan(omega / 2)) / omega, r the undistorted radius in the z = 1 plane. It saturates at 90 degrees:
  valid domain z > 0; unprojection is closed form, r = tan(r_d omega) / (2 tan(omega / 2)), valid while
  r_d omega < pi / 2. Unlike DSO, the centre pixel uses the exact limit 2 tan(omega/2) / omega of the radial
  factor (DSO sets it to 1 there).
*/
class VISP_EXPORT FovModel : public CameraModel
{
public:
  FovModel(double fx, double fy, double cx, double cy, double omega);
  bool project(const Eigen::Vector3d &p, Eigen::Vector2d &uv,
               Eigen::Matrix<double, 2, 3> *J_p = nullptr) const override;
  bool unproject(const Eigen::Vector2d &uv, Eigen::Vector3d &ray) const override;
  vpHSlamCamera::Model model() const override { return vpHSlamCamera::fov; }

  double omega() const { return m_omega; } //!< radians

private:
  double m_omega;
  double m_twoTanHalfOmega; //!< 2 tan(omega / 2), DSO's "d2t"
};

/*!
  Build the model described by a calibration.
  \exception vpHSlamException::invalidCalibration when the calibration's distortion count does not fit its model
  (cannot happen for a validated vpHSlamCamera).
*/
VISP_EXPORT std::unique_ptr<CameraModel> makeCameraModel(const vpHSlamCamera &cam);

} // namespace hslam

#endif
