/*
 * H-SLAM for ViSP.
 */
#include "mapping/WindowLinearization.h"

namespace hslam
{
namespace
{
//! Points whose inverse-depth Hessian is below this carry no information and are left out of the Schur
//! complement (DSO clamps H_dd at 1e-10 for the same reason: avoid dividing by ~0).
constexpr double kMinSchurIdepthHessian = 1e-10;

using Mat9d = Eigen::Matrix<double, kRelativeDims, kRelativeDims>;
using Vec9d = Eigen::Matrix<double, kRelativeDims, 1>;
} // namespace

void WindowAccumulator::reset(int n)
{
  const size_t blocks = static_cast<size_t>(kMaxWindowKeyframes * kMaxWindowKeyframes);
  if (pairH.size() != blocks) {
    pairH.resize(blocks);
    pairB.resize(blocks);
    frameH.resize(static_cast<size_t>(kMaxWindowKeyframes));
    frameB.resize(static_cast<size_t>(kMaxWindowKeyframes));
  }
  for (int f = 0; f < n; ++f) {
    frameH[static_cast<size_t>(f)].setZero();
    frameB[static_cast<size_t>(f)].setZero();
  }
  for (int h = 0; h < n; ++h) {
    for (int t = 0; t < n; ++t) {
      pairH[static_cast<size_t>(h * kMaxWindowKeyframes + t)].setZero();
      pairB[static_cast<size_t>(h * kMaxWindowKeyframes + t)].setZero();
    }
  }
  numFrames = n;
  if (Hsc.rows() != n * kFrameDims) {
    Hsc.resize(n * kFrameDims, n * kFrameDims);
    bsc.resize(n * kFrameDims);
  }
  Hsc.setZero();
  bsc.setZero();
  energy = 0.;
  inliers = outliers = outOfBounds = 0;
}

void WindowAccumulator::add(const WindowAccumulator &other)
{
  for (int h = 0; h < numFrames; ++h) {
    for (int t = 0; t < numFrames; ++t) {
      const size_t k = static_cast<size_t>(h * kMaxWindowKeyframes + t);
      pairH[k] += other.pairH[k];
      pairB[k] += other.pairB[k];
    }
  }
  for (int f = 0; f < numFrames; ++f) {
    frameH[static_cast<size_t>(f)] += other.frameH[static_cast<size_t>(f)];
    frameB[static_cast<size_t>(f)] += other.frameB[static_cast<size_t>(f)];
  }
  Hsc += other.Hsc;
  bsc += other.bsc;
  energy += other.energy;
  inliers += other.inliers;
  outliers += other.outliers;
  outOfBounds += other.outOfBounds;
}

void linearizeRange(const WindowContext &ctx, std::vector<WindowPoint> &points, const std::vector<int> &order,
                    size_t begin, size_t end, Vec8d *hxp, WindowAccumulator &acc)
{
  PatternLinearization lin;
  for (size_t i = begin; i < end; ++i) {
    const int pi = order[i];
    WindowPoint &p = points[static_cast<size_t>(pi)];
    Vec8d *cross = hxp + static_cast<size_t>(pi) * kMaxWindowKeyframes;
    for (int f = 0; f < ctx.numFrames; ++f) {
      cross[f].setZero();
    }
    double Hpp = 0., bp = 0.;
    int inliers = 0;
    for (WindowResidual &res : p.residuals) {
      const FramePairPrecalc &pair = ctx.pair(p.host, res.target);
      res.state = evaluatePattern(ctx.settings, *ctx.levels[res.target], pair, p.obs, res.energy, &lin);
      acc.energy += res.energy;
      if (res.state == ResidualState::outOfBounds) {
        ++acc.outOfBounds;
        continue;
      }
      if (res.state == ResidualState::outlier) {
        ++acc.outliers;
        continue;
      }
      ++acc.inliers;
      ++inliers;
      // J^T W J and J^T W r over the 8 pattern pixels (9 columns: relative pose, alpha, beta, rho).
      // Plain loops over the upper triangle: Eigen sends this small product (or eight rank-1 updates) through its
      // general matrix kernels, which cost 4 % of a whole slam run.
      // The weighted factors (w r and w J) are formed once, not once per product: the same products, so the same
      // sums bit for bit.
      Mat9d H;
      Vec9d b;
      double wr[kPatternSize];
      for (int k = 0; k < kPatternSize; ++k) {
        wr[k] = lin.weight[static_cast<size_t>(k)] * lin.r[static_cast<size_t>(k)];
      }
      for (int c = 0; c < kRelativeDims; ++c) {
        double wJ[kPatternSize];
        double bc = 0.;
        for (int k = 0; k < kPatternSize; ++k) {
          wJ[k] = lin.weight[static_cast<size_t>(k)] * lin.J(k, c);
          bc += wr[k] * lin.J(k, c);
        }
        b[c] = bc;
        for (int d = c; d < kRelativeDims; ++d) {
          double h = 0.;
          for (int k = 0; k < kPatternSize; ++k) {
            h += wJ[k] * lin.J(k, d);
          }
          H(c, d) = h;
          H(d, c) = h;
        }
      }
      const size_t block = static_cast<size_t>(p.host * kMaxWindowKeyframes + res.target);
      acc.pairH[block] += H.topLeftCorner<kFrameDims, kFrameDims>();
      acc.pairB[block] += b.head<kFrameDims>();
      const Vec8d crossRel = H.block<kFrameDims, 1>(0, kFrameDims);
      cross[p.host].noalias() += pair.dRelative_dHost.transpose() * crossRel;
      cross[res.target].noalias() += pair.dRelative_dTarget.transpose() * crossRel;
      Hpp += H(kFrameDims, kFrameDims);
      bp += b[kFrameDims];
    }
    if (p.obs.priorWeight > 0.) {
      // Inverse-depth prior of a re-used global point (its old estimate): one more residual on rho only.
      const double d = p.obs.idepth - p.obs.idepthPrior;
      acc.energy += p.obs.priorWeight * d * d;
      Hpp += p.obs.priorWeight;
      bp += p.obs.priorWeight * d;
    }
    if (p.anchor.active) {
      // A re-used point's tie to its stored keyframe: blocks on the host's pose and on rho only.
      AnchorLinearization al;
      acc.energy += evaluateAnchor(ctx.settings.K, ctx.poses[p.host], p.obs.u, p.obs.v, p.obs.idepth, p.anchor, &al);
      acc.frameH[static_cast<size_t>(p.host)].topLeftCorner<6, 6>() += al.Hxx;
      acc.frameB[static_cast<size_t>(p.host)].head<6>() += al.bx;
      cross[p.host].head<6>() += al.Hxr;
      Hpp += al.Hrr;
      bp += al.br;
    }
    p.Hpp = Hpp;
    p.bp = bp;
    p.inlierResiduals = inliers;
  }
}

void schurRange(const WindowContext &ctx, const std::vector<WindowPoint> &points, const std::vector<int> &order,
                size_t begin, size_t end, const Vec8d *hxp, double lambda, WindowAccumulator &acc)
{
  int touched[kMaxWindowKeyframes];
  for (size_t i = begin; i < end; ++i) {
    const int pi = order[i];
    const WindowPoint &p = points[static_cast<size_t>(pi)];
    const double H = p.Hpp * (1. + lambda);
    if (p.inlierResiduals == 0 || H < kMinSchurIdepthHessian) {
      continue;
    }
    const double Hinv = 1. / H;
    int n = 0;
    touched[n++] = p.host;
    for (const WindowResidual &res : p.residuals) {
      if (res.state == ResidualState::inlier) {
        touched[n++] = res.target;
      }
    }
    const Vec8d *cross = hxp + static_cast<size_t>(pi) * kMaxWindowKeyframes;
    for (int a = 0; a < n; ++a) {
      const int fa = touched[a];
      const Vec8d scaled = cross[fa] * Hinv;
      acc.bsc.segment<kFrameDims>(fa * kFrameDims) += scaled * p.bp;
      for (int c = 0; c < n; ++c) {
        const int fc = touched[c];
        acc.Hsc.block<kFrameDims, kFrameDims>(fa * kFrameDims, fc * kFrameDims).noalias() +=
            scaled * cross[fc].transpose();
      }
    }
  }
  (void)ctx;
}

double energyRange(const WindowContext &ctx, const std::vector<WindowPoint> &points, const std::vector<int> &order,
                   size_t begin, size_t end, int *inliers)
{
  double sum = 0.;
  int good = 0;
  for (size_t i = begin; i < end; ++i) {
    const WindowPoint &p = points[static_cast<size_t>(order[i])];
    for (const WindowResidual &res : p.residuals) {
      double e = 0.;
      if (evaluatePattern(ctx.settings, *ctx.levels[res.target], ctx.pair(p.host, res.target), p.obs, e, nullptr) ==
          ResidualState::inlier) {
        ++good;
      }
      sum += e;
    }
    if (p.obs.priorWeight > 0.) {
      const double d = p.obs.idepth - p.obs.idepthPrior;
      sum += p.obs.priorWeight * d * d;
    }
    if (p.anchor.active) {
      sum += evaluateAnchor(ctx.settings.K, ctx.poses[p.host], p.obs.u, p.obs.v, p.obs.idepth, p.anchor, nullptr);
    }
  }
  if (inliers) {
    *inliers = good;
  }
  return sum;
}
} // namespace hslam
