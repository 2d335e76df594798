/*
 * H-SLAM for ViSP.
 */
/*!
  \file NormalEquations8.h
  \brief Accumulator of 8-dimensional Gauss-Newton normal equations (SE(3) twist + affine a, b) from weighted
  residuals.

  Terms are summed in single precision over short blocks (fast, vectorisable 9x9 outer products of (J, r)) and
  the blocks are added in double precision, so thousands of terms do not lose the small ones (DSO's Accumulator
  does the same). Several accumulators (one per worker range) combine with operator+=.
*/
#ifndef HSLAM_TRACKING_NORMAL_EQUATIONS8_H
#define HSLAM_TRACKING_NORMAL_EQUATIONS8_H

#include <Eigen/Core>

namespace hslam
{
class NormalEquations8
{
public:
  using Vec9f = Eigen::Matrix<float, 9, 1>;
  //! Terms summed in float before the block is flushed to double.
  static constexpr int kBlockSize = 128;

  NormalEquations8() { reset(); }

  void reset()
  {
    m_blockSum.setZero();
    m_sum.setZero();
    m_inBlock = 0;
    m_numTerms = 0;
  }

  /*!
    Add weight * (J, r)(J, r)^T for the Jacobian \e J (first 8 entries of \e Jr) and the residual r (entry 8).
  */
  void add(const Vec9f &Jr, float weight)
  {
    m_blockSum.noalias() += (weight * Jr) * Jr.transpose();
    ++m_numTerms;
    if (++m_inBlock == kBlockSize) {
      flush();
    }
  }

  //! Finish the pending block (call before reading H() / b() or combining).
  void flush()
  {
    m_sum += m_blockSum.cast<double>();
    m_blockSum.setZero();
    m_inBlock = 0;
  }

  NormalEquations8 &operator+=(NormalEquations8 &other)
  {
    flush();
    other.flush();
    m_sum += other.m_sum;
    m_numTerms += other.m_numTerms;
    return *this;
  }

  //! Sum of w J^T J (after flush()).
  Eigen::Matrix<double, 8, 8> H() const { return m_sum.topLeftCorner<8, 8>(); }
  //! Sum of w J^T r (after flush()).
  Eigen::Matrix<double, 8, 1> b() const { return m_sum.topRightCorner<8, 1>(); }
  int numTerms() const { return m_numTerms; }

private:
  Eigen::Matrix<float, 9, 9> m_blockSum;
  Eigen::Matrix<double, 9, 9> m_sum;
  int m_inBlock = 0;
  int m_numTerms = 0;
};
} // namespace hslam

#endif
