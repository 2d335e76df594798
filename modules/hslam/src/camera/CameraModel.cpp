#include "camera/CameraModel.h"

#include <visp3/hslam/vpHSlamException.h>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <sstream>

namespace hslam
{
namespace
{
//! Points closer than this to the z = 0 plane (camera-frame units) cannot be projected by z-dividing models.
constexpr double kMinDepth = 1e-12;
//! Bound on Newton iterations when inverting radtan / equidistant; they converge in < 10 for real lenses.
constexpr int kMaxNewtonIterations = 50;
//! Newton stops when the residual (normalised image units, ~1e-14 * f pixels) is below this.
constexpr double kNewtonStopResidual = 1e-15;
//! Newton result accepted when the residual is below this (1e-11 * f is far below 1e-6 px for any f < 1e5).
constexpr double kNewtonAcceptResidual = 1e-11;
//! Samples used to find where a radial distortion polynomial stops being monotonic, then refined by bisection.
constexpr int kDomainScanSteps = 512;
constexpr int kDomainBisectionSteps = 60;
//! Radtan is never calibrated beyond ~87 degrees (r = 20 in the z = 1 plane); the domain search stops there.
constexpr double kRadTanScanMaxRadius = 20.0;
//! Below this sin(angle to the optical axis) the equidistant map is the pinhole map to machine precision.
constexpr double kEquidistantAxisSin = 1e-9;
//! Below this radius the FOV radial factor and its derivative use their Taylor series (error < 1e-12).
constexpr double kFovSeriesRadius = 1e-3;

constexpr double kPi = 3.14159265358979323846;

/*!
  Smallest x in (0, xMax] where f(x) <= 0, for a function with f(0) > 0; xMax when f stays positive.
  Scan then bisection: a fold is detected unless two roots lie closer than xMax / kDomainScanSteps.
*/
template <typename F> double firstNonPositive(const F &f, double xMax)
{
  double prev = 0.0;
  for (int i = 1; i <= kDomainScanSteps; ++i) {
    const double x = xMax * i / kDomainScanSteps;
    if (f(x) <= 0.0) {
      double lo = prev, hi = x;
      for (int k = 0; k < kDomainBisectionSteps; ++k) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) > 0.0 ? lo : hi) = mid;
      }
      return lo;
    }
    prev = x;
  }
  return xMax;
}

//! d(p / z)/dp: Jacobian of the perspective division.
Eigen::Matrix<double, 2, 3> perspectiveJacobian(const Eigen::Vector3d &p)
{
  const double iz = 1.0 / p.z();
  Eigen::Matrix<double, 2, 3> J;
  J << iz, 0.0, -p.x() * iz * iz, 0.0, iz, -p.y() * iz * iz;
  return J;
}

Eigen::Vector3d unitRay(const Eigen::Vector2d &m)
{
  return Eigen::Vector3d(m.x(), m.y(), 1.0).normalized();
}
} // namespace

// ---------------------------------------------------------------------------------------------------------------
CameraModel::CameraModel(double fx, double fy, double cx, double cy) : m_fx(fx), m_fy(fy), m_cx(cx), m_cy(cy) {}

CameraModel::~CameraModel() = default;

bool CameraModel::projectPerspective(const Eigen::Vector3d &p, Eigen::Vector2d &uv,
                                     Eigen::Matrix<double, 2, 3> *J_p) const
{
  if (p.z() <= kMinDepth) {
    return false;
  }
  uv << m_fx * p.x() / p.z() + m_cx, m_fy * p.y() / p.z() + m_cy;
  if (J_p) {
    *J_p = scaleToPixels(perspectiveJacobian(p));
  }
  return true;
}

// ---------------------------------------------------------------------------------------------------------------
PinholeModel::PinholeModel(double fx, double fy, double cx, double cy) : CameraModel(fx, fy, cx, cy) {}

bool PinholeModel::project(const Eigen::Vector3d &p, Eigen::Vector2d &uv, Eigen::Matrix<double, 2, 3> *J_p) const
{
  return projectPerspective(p, uv, J_p);
}

bool PinholeModel::unproject(const Eigen::Vector2d &uv, Eigen::Vector3d &ray) const
{
  ray = unitRay(pixelToNormalised(uv));
  return true;
}

// ---------------------------------------------------------------------------------------------------------------
RadTanModel::RadTanModel(double fx, double fy, double cx, double cy, double k1, double k2, double p1, double p2,
                         double k3)
    : CameraModel(fx, fy, cx, cy), m_k1(k1), m_k2(k2), m_p1(p1), m_p2(p2), m_k3(k3)
{
  // d/dr [r (1 + k1 r^2 + k2 r^4 + k3 r^6)] = 1 + 3 k1 r^2 + 5 k2 r^4 + 7 k3 r^6: the radial map folds where it
  // vanishes, and unprojection stops being unique beyond.
  const auto slope = [this](double r) {
    const double s = r * r;
    return 1.0 + s * (3.0 * m_k1 + s * (5.0 * m_k2 + s * 7.0 * m_k3));
  };
  m_maxRadius = firstNonPositive(slope, kRadTanScanMaxRadius);
}

Eigen::Vector2d RadTanModel::distort(const Eigen::Vector2d &m, Eigen::Matrix2d *J) const
{
  // OpenCV calib3d ("Detailed description" of the camera model), without the rational and thin-prism terms.
  const double x = m.x(), y = m.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (m_k1 + r2 * (m_k2 + r2 * m_k3));
  const double xy2 = 2.0 * x * y;
  Eigen::Vector2d md(x * radial + m_p1 * xy2 + m_p2 * (r2 + 2.0 * x * x),
                     y * radial + m_p1 * (r2 + 2.0 * y * y) + m_p2 * xy2);
  if (J) {
    const double dRadial_dr2 = m_k1 + r2 * (2.0 * m_k2 + 3.0 * r2 * m_k3);
    (*J)(0, 0) = radial + 2.0 * x * x * dRadial_dr2 + 2.0 * m_p1 * y + 6.0 * m_p2 * x;
    (*J)(0, 1) = 2.0 * x * y * dRadial_dr2 + 2.0 * m_p1 * x + 2.0 * m_p2 * y;
    (*J)(1, 0) = 2.0 * x * y * dRadial_dr2 + 2.0 * m_p1 * x + 2.0 * m_p2 * y;
    (*J)(1, 1) = radial + 2.0 * y * y * dRadial_dr2 + 6.0 * m_p1 * y + 2.0 * m_p2 * x;
  }
  return md;
}

bool RadTanModel::project(const Eigen::Vector3d &p, Eigen::Vector2d &uv, Eigen::Matrix<double, 2, 3> *J_p) const
{
  if (p.z() <= kMinDepth) {
    return false;
  }
  const Eigen::Vector2d m(p.x() / p.z(), p.y() / p.z());
  if (m.squaredNorm() > m_maxRadius * m_maxRadius) {
    return false;
  }
  Eigen::Matrix2d Jd;
  const Eigen::Vector2d md = distort(m, J_p ? &Jd : nullptr);
  uv << m_fx * md.x() + m_cx, m_fy * md.y() + m_cy;
  if (J_p) {
    *J_p = scaleToPixels(Jd * perspectiveJacobian(p));
  }
  return true;
}

bool RadTanModel::unproject(const Eigen::Vector2d &uv, Eigen::Vector3d &ray) const
{
  // No closed form: Newton on distort(m) = md, started at md, with the step halved whenever it would leave the
  // monotonic disc (where the inverse is unique).
  const Eigen::Vector2d md = pixelToNormalised(uv);
  Eigen::Vector2d m = md;
  if (m.norm() >= m_maxRadius) {
    m *= 0.5 * m_maxRadius / m.norm();
  }
  Eigen::Matrix2d J;
  Eigen::Vector2d residual = distort(m, &J) - md;
  for (int it = 0; it < kMaxNewtonIterations && residual.norm() > kNewtonStopResidual; ++it) {
    const double det = J.determinant();
    if (!(std::abs(det) > std::numeric_limits<double>::min())) {
      return false;
    }
    Eigen::Vector2d step = -J.inverse() * residual;
    while ((m + step).norm() >= m_maxRadius) {
      step *= 0.5;
      if (step.norm() < kNewtonStopResidual) {
        return false;
      }
    }
    m += step;
    residual = distort(m, &J) - md;
  }
  if (!(residual.norm() <= kNewtonAcceptResidual)) {
    return false;
  }
  ray = unitRay(m);
  return true;
}

// ---------------------------------------------------------------------------------------------------------------
EquidistantModel::EquidistantModel(double fx, double fy, double cx, double cy, double k1, double k2, double k3,
                                   double k4)
    : CameraModel(fx, fy, cx, cy), m_k1(k1), m_k2(k2), m_k3(k3), m_k4(k4)
{
  m_maxTheta = firstNonPositive([this](double th) { return thetaDDerivative(th); }, kPi);
  m_maxThetaD = thetaD(m_maxTheta);
}

double EquidistantModel::thetaD(double theta) const
{
  // OpenCV fisheye: theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8).
  const double t2 = theta * theta;
  return theta * (1.0 + t2 * (m_k1 + t2 * (m_k2 + t2 * (m_k3 + t2 * m_k4))));
}

double EquidistantModel::thetaDDerivative(double theta) const
{
  const double t2 = theta * theta;
  return 1.0 + t2 * (3.0 * m_k1 + t2 * (5.0 * m_k2 + t2 * (7.0 * m_k3 + t2 * 9.0 * m_k4)));
}

bool EquidistantModel::project(const Eigen::Vector3d &p, Eigen::Vector2d &uv, Eigen::Matrix<double, 2, 3> *J_p) const
{
  const double r2 = p.x() * p.x() + p.y() * p.y();
  const double r = std::sqrt(r2);
  const double rho2 = r2 + p.z() * p.z();
  if (!(rho2 > 0.0)) {
    return false;
  }
  if (r <= kEquidistantAxisSin * std::sqrt(rho2)) {
    // On the optical axis the model is the pinhole model (theta_d / r -> 1 / z); behind the camera the direction
    // of the distorted point is undefined.
    return projectPerspective(p, uv, J_p);
  }
  const double theta = std::atan2(r, p.z());
  if (theta > m_maxTheta) {
    return false;
  }
  const double td = thetaD(theta);
  const double s = td / r;
  uv << m_fx * s * p.x() + m_cx, m_fy * s * p.y() + m_cy;
  if (J_p) {
    // m = s (x, y), s = theta_d(theta) / r, theta = atan2(r, z): dm/dp = s [I 0] + (x, y)^T ds/dp.
    const Eigen::Vector3d dtheta(p.z() * p.x() / (r * rho2), p.z() * p.y() / (r * rho2), -r / rho2);
    const Eigen::Vector3d dr(p.x() / r, p.y() / r, 0.0);
    const Eigen::Vector3d ds = (thetaDDerivative(theta) / r) * dtheta - (td / r2) * dr;
    Eigen::Matrix<double, 2, 3> Jm = Eigen::Vector2d(p.x(), p.y()) * ds.transpose();
    Jm(0, 0) += s;
    Jm(1, 1) += s;
    *J_p = scaleToPixels(Jm);
  }
  return true;
}

bool EquidistantModel::unproject(const Eigen::Vector2d &uv, Eigen::Vector3d &ray) const
{
  const Eigen::Vector2d md = pixelToNormalised(uv);
  const double td = md.norm();
  if (td > m_maxThetaD) {
    return false;
  }
  if (td <= kEquidistantAxisSin) {
    ray = unitRay(md);
    return true;
  }
  // theta_d(theta) increases on [0, maxTheta]: Newton safeguarded by the bracket [lo, hi] (falls back to
  // bisection when a Newton step leaves it), so it always converges.
  double lo = 0.0, hi = m_maxTheta;
  double theta = std::min(td, m_maxTheta);
  double f = thetaD(theta) - td;
  for (int it = 0; it < kMaxNewtonIterations && std::abs(f) > kNewtonStopResidual; ++it) {
    (f > 0.0 ? hi : lo) = theta;
    const double slope = thetaDDerivative(theta);
    double next = slope > 0.0 ? theta - f / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) {
      next = 0.5 * (lo + hi);
    }
    theta = next;
    f = thetaD(theta) - td;
  }
  if (!(std::abs(f) <= kNewtonAcceptResidual)) {
    return false;
  }
  const double sinTheta = std::sin(theta);
  ray << sinTheta * md.x() / td, sinTheta * md.y() / td, std::cos(theta);
  return true;
}

// ---------------------------------------------------------------------------------------------------------------
FovModel::FovModel(double fx, double fy, double cx, double cy, double omega)
    : CameraModel(fx, fy, cx, cy), m_omega(omega), m_twoTanHalfOmega(2.0 * std::tan(0.5 * omega))
{
}

bool FovModel::project(const Eigen::Vector3d &p, Eigen::Vector2d &uv, Eigen::Matrix<double, 2, 3> *J_p) const
{
  if (p.z() <= kMinDepth) {
    return false;
  }
  const Eigen::Vector2d m(p.x() / p.z(), p.y() / p.z());
  const double r = m.norm();
  const double c = m_twoTanHalfOmega;
  // Radial factor F(r) = r_d / r = atan(c r) / (omega r) (DSO UndistortFOV) and G(r) = F'(r) / r.
  double F, G;
  if (r < kFovSeriesRadius) {
    const double c2 = c * c, r2 = r * r;
    F = c * (1.0 - c2 * r2 / 3.0 + c2 * c2 * r2 * r2 / 5.0) / m_omega;
    G = c * c2 * (-2.0 / 3.0 + 4.0 * c2 * r2 / 5.0) / m_omega;
  } else {
    const double a = std::atan(c * r);
    F = a / (m_omega * r);
    G = (c * r / (1.0 + c * c * r * r) - a) / (m_omega * r * r * r);
  }
  uv << m_fx * F * m.x() + m_cx, m_fy * F * m.y() + m_cy;
  if (J_p) {
    Eigen::Matrix2d Jd = G * m * m.transpose();
    Jd(0, 0) += F;
    Jd(1, 1) += F;
    *J_p = scaleToPixels(Jd * perspectiveJacobian(p));
  }
  return true;
}

bool FovModel::unproject(const Eigen::Vector2d &uv, Eigen::Vector3d &ray) const
{
  const Eigen::Vector2d md = pixelToNormalised(uv);
  const double rd = md.norm();
  const double angle = rd * m_omega;
  // r = tan(r_d omega) / (2 tan(omega / 2)) exists while r_d omega < pi / 2 (the model's 90 degree horizon).
  if (!(angle < 0.5 * kPi)) {
    return false;
  }
  double ratio; // r / r_d
  if (rd < kFovSeriesRadius) {
    const double a2 = angle * angle;
    ratio = m_omega * (1.0 + a2 / 3.0 + 2.0 * a2 * a2 / 15.0) / m_twoTanHalfOmega;
  } else {
    ratio = std::tan(angle) / (m_twoTanHalfOmega * rd);
  }
  ray = unitRay(ratio * md);
  return true;
}

// ---------------------------------------------------------------------------------------------------------------
std::unique_ptr<CameraModel> makeCameraModel(const vpHSlamCamera &cam)
{
  const std::vector<double> &d = cam.getDistortion();
  const auto badCount = [&cam, &d]() {
    std::ostringstream os;
    os << __FILE__ << ":" << __LINE__ << ": " << vpHSlamCamera::modelName(cam.getModel()) << " model given " << d.size()
       << " distortion values";
    return vpHSlamException(vpHSlamException::invalidCalibration, os.str());
  };
  const double fx = cam.getFx(), fy = cam.getFy(), cx = cam.getCx(), cy = cam.getCy();
  switch (cam.getModel()) {
  case vpHSlamCamera::pinhole:
    if (!d.empty()) {
      throw badCount();
    }
    return std::make_unique<PinholeModel>(fx, fy, cx, cy);
  case vpHSlamCamera::radialTangential:
    if (d.size() != 4 && d.size() != 5) {
      throw badCount();
    }
    return std::make_unique<RadTanModel>(fx, fy, cx, cy, d[0], d[1], d[2], d[3], d.size() == 5 ? d[4] : 0.0);
  case vpHSlamCamera::equidistant:
    if (d.size() != 4) {
      throw badCount();
    }
    return std::make_unique<EquidistantModel>(fx, fy, cx, cy, d[0], d[1], d[2], d[3]);
  case vpHSlamCamera::fov:
    if (d.size() != 1) {
      throw badCount();
    }
    return std::make_unique<FovModel>(fx, fy, cx, cy, d[0]);
  }
  throw vpHSlamException(vpHSlamException::unsupported,
                         std::string(__FILE__) + ": unknown camera model " + std::to_string(int(cam.getModel())));
}

} // namespace hslam
