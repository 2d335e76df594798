/*
 * H-SLAM for ViSP.
 */
#include "mapping/MarginalizationPrior.h"

#include <visp3/hslam/vpHSlamException.h>

#include <Eigen/Eigenvalues>

#include <string>

namespace hslam
{
namespace
{
//! Eigenvalues of the (Jacobi-scaled) block to eliminate below this fraction of the largest are treated as zero
//! (pseudo-inverse): a direction the keyframe's data did not constrain carries no information to pass on.
constexpr double kPseudoInverseRelativeEigenvalue = 1e-12;

//! Remove rows and columns [i*8, i*8+8) of a square matrix / vector.
void eraseBlock(Eigen::MatrixXd &H, Eigen::VectorXd &b, int i)
{
  const int n = static_cast<int>(b.size());
  const int s = i * kFrameDims;
  const int tail = n - s - kFrameDims;
  Eigen::MatrixXd Hn(n - kFrameDims, n - kFrameDims);
  Eigen::VectorXd bn(n - kFrameDims);
  Hn.topLeftCorner(s, s) = H.topLeftCorner(s, s);
  Hn.topRightCorner(s, tail) = H.topRightCorner(s, tail);
  Hn.bottomLeftCorner(tail, s) = H.bottomLeftCorner(tail, s);
  Hn.bottomRightCorner(tail, tail) = H.bottomRightCorner(tail, tail);
  bn.head(s) = b.head(s);
  bn.tail(tail) = b.tail(tail);
  H.swap(Hn);
  b.swap(bn);
}
} // namespace

Vec8d stateDeviation(const KeyframeState &current, const KeyframeState &zero)
{
  Vec8d d;
  d.head<6>() = (current.cMw * zero.cMw.inverse()).log();
  d[6] = current.a - zero.a;
  d[7] = current.b - zero.b;
  return d;
}

void MarginalizationPrior::addFrame()
{
  const int n = static_cast<int>(m_b.size());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n + kFrameDims, n + kFrameDims);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + kFrameDims);
  H.topLeftCorner(n, n) = m_H;
  b.head(n) = m_b;
  m_H.swap(H);
  m_b.swap(b);
  m_linearized.push_back(false);
  m_zero.emplace_back();
}

Eigen::VectorXd MarginalizationPrior::deviation(const std::vector<KeyframeState> &states) const
{
  if (states.size() != m_linearized.size()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                                                                  ": " + std::to_string(states.size()) +
                                                                  " states for a prior over " +
                                                                  std::to_string(m_linearized.size()) + " keyframes");
  }
  Eigen::VectorXd D = Eigen::VectorXd::Zero(m_b.size());
  for (size_t i = 0; i < states.size(); ++i) {
    if (m_linearized[i]) {
      D.segment<kFrameDims>(static_cast<Eigen::Index>(i) * kFrameDims) = stateDeviation(states[i], m_zero[i]);
    }
  }
  return D;
}

void MarginalizationPrior::add(const Eigen::MatrixXd &Hadd, const Eigen::VectorXd &gAdd,
                               const std::vector<KeyframeState> &states)
{
  if (Hadd.rows() != m_H.rows() || gAdd.size() != m_b.size()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                                                                  ": information of the wrong size for the prior");
  }
  for (size_t i = 0; i < m_linearized.size(); ++i) {
    const Eigen::Index s = static_cast<Eigen::Index>(i) * kFrameDims;
    if (!m_linearized[i] && Hadd.block<kFrameDims, kFrameDims>(s, s).diagonal().sum() > 0.) {
      m_linearized[i] = true;
      m_zero[i] = states[i];
    }
  }
  // FEJ: the new information is a quadratic around the current state; express it around the fixed points.
  const Eigen::VectorXd D = deviation(states);
  m_H += Hadd;
  m_b += gAdd - Hadd * D;
  m_H = 0.5 * (m_H + m_H.transpose()).eval();
  m_hasInformation = true;
}

void MarginalizationPrior::removeFrame(int i, bool fixedGauge)
{
  const int n = numFrames();
  if (i < 0 || i >= n) {
    throw vpHSlamException(vpHSlamException::invalidArgument, std::string(__FILE__) + ":" + std::to_string(__LINE__) +
                                                                  ": no keyframe " + std::to_string(i) +
                                                                  " in the prior");
  }
  const Eigen::Index s = static_cast<Eigen::Index>(i) * kFrameDims;
  const Mat8d Hff = m_H.block<kFrameDims, kFrameDims>(s, s);
  if (!fixedGauge && m_linearized[static_cast<size_t>(i)] && Hff.diagonal().maxCoeff() > 0.) {
    // Schur complement with a Jacobi-scaled pseudo-inverse of the 8x8 block (DSO scales the same way).
    Vec8d scale;
    for (int k = 0; k < kFrameDims; ++k) {
      scale[k] = Hff(k, k) > 0. ? 1. / std::sqrt(Hff(k, k)) : 1.;
    }
    const Mat8d Hs = scale.asDiagonal() * Hff * scale.asDiagonal();
    Eigen::SelfAdjointEigenSolver<Mat8d> eig(Hs);
    const double maxEig = eig.eigenvalues().maxCoeff();
    Vec8d invEig;
    for (int k = 0; k < kFrameDims; ++k) {
      const double e = eig.eigenvalues()[k];
      invEig[k] = e > kPseudoInverseRelativeEigenvalue * maxEig ? 1. / e : 0.;
    }
    const Mat8d HffInv = scale.asDiagonal() * eig.eigenvectors() * invEig.asDiagonal() *
                         eig.eigenvectors().transpose() * scale.asDiagonal();
    const Eigen::MatrixXd Hrf = m_H.middleCols<kFrameDims>(s);
    const Eigen::MatrixXd HrfInv = Hrf * HffInv;
    const Vec8d bf = m_b.segment<kFrameDims>(s);
    m_H -= HrfInv * Hrf.transpose();
    m_b -= HrfInv * bf;
  }
  eraseBlock(m_H, m_b, i);
  m_H = 0.5 * (m_H + m_H.transpose()).eval();
  m_linearized.erase(m_linearized.begin() + i);
  m_zero.erase(m_zero.begin() + i);
}

double MarginalizationPrior::energy(const std::vector<KeyframeState> &states) const
{
  if (!m_hasInformation) {
    return 0.;
  }
  const Eigen::VectorXd D = deviation(states);
  return 2. * m_b.dot(D) + D.dot(m_H * D);
}

Eigen::VectorXd MarginalizationPrior::gradient(const std::vector<KeyframeState> &states) const
{
  return m_b + m_H * deviation(states);
}
} // namespace hslam
