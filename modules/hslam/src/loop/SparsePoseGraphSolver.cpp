/*
 * H-SLAM for ViSP.
 */
#include "loop/SparsePoseGraphSolver.h"

#include "loop/Sim3Parameters.h"

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

namespace hslam
{
namespace
{
using Mat7 = Eigen::Matrix<double, 7, 7>;
using Vec7 = Eigen::Matrix<double, 7, 1>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat67 = Eigen::Matrix<double, 6, 7>;

/*!
  Levenberg-Marquardt settings: Ceres' defaults, which PoseGraph's Ceres path runs with (trust region 1e4, i.e.
  damping 1e-4 x diag(H); function, gradient and step tolerances 1e-6, 1e-10, 1e-8; diagonal clamped to
  [1e-6, 1e32]).
*/
constexpr double kInitialDamping = 1e-4;
constexpr double kFunctionTolerance = 1e-6;
constexpr double kGradientTolerance = 1e-10;
constexpr double kStepTolerance = 1e-8;
constexpr double kMinDiagonal = 1e-6;
constexpr double kMaxDiagonal = 1e32;

//! Error of edge \e e at the vertices (Si, Sj), before weighting: log(S_ji Si Sj^-1).
Vec7 edgeError(const PoseGraphEdge &e, const Sim3d &Si, const Sim3d &Sj)
{
  return (e.Sji * Si * Sj.inverse()).log();
}

/*!
  The normal equations' block pattern, built once per optimize(): one 7x7 block per free vertex and per pair of free
  vertices an edge joins, upper triangle (block row <= block column), column-major as Eigen's sparse Cholesky wants.
  Each block remembers where its 7 columns start in the value array, so an iteration accumulates straight into it.
*/
struct NormalEquations {
  Eigen::SparseMatrix<double> H;
  std::vector<std::array<int, 7>> blockColumns; //!< per block, index of (first row, column c) in H's values
  std::vector<int> diagonal;                    //!< index in H's values of each diagonal entry

  NormalEquations(int freeCount, const std::vector<std::pair<int, int>> &blocks)
  {
    const int n = 7 * freeCount;
    std::vector<Eigen::Triplet<double>> pattern;
    pattern.reserve(blocks.size() * 49);
    for (const auto &b : blocks) {
      for (int r = 0; r < 7; ++r) {
        for (int c = 0; c < 7; ++c) {
          pattern.emplace_back(7 * b.first + r, 7 * b.second + c, 0.);
        }
      }
    }
    H.resize(n, n);
    H.setFromTriplets(pattern.begin(), pattern.end());
    H.makeCompressed();
    const int *outer = H.outerIndexPtr();
    const int *inner = H.innerIndexPtr();
    blockColumns.resize(blocks.size());
    for (size_t k = 0; k < blocks.size(); ++k) {
      for (int c = 0; c < 7; ++c) {
        const int col = 7 * blocks[k].second + c;
        blockColumns[k][static_cast<size_t>(c)] =
            static_cast<int>(std::lower_bound(inner + outer[col], inner + outer[col + 1], 7 * blocks[k].first) - inner);
      }
    }
    diagonal.resize(static_cast<size_t>(n));
    for (int col = 0; col < n; ++col) {
      diagonal[static_cast<size_t>(col)] =
          static_cast<int>(std::lower_bound(inner + outer[col], inner + outer[col + 1], col) - inner);
    }
  }

  //! Adds the 7x7 \e M into block \e k.
  void add(int k, const Mat7 &M)
  {
    double *values = H.valuePtr();
    for (int c = 0; c < 7; ++c) {
      Eigen::Map<Vec7>(values + blockColumns[static_cast<size_t>(k)][static_cast<size_t>(c)]) += M.col(c);
    }
  }
};

/*!
  Renumbers the free vertices (\e free: per vertex its index among the free ones, or -1) in the approximate minimum
  degree order of their block graph, so the factorisation needs no permutation of its own (7x smaller than ordering
  the scalar matrix, and done once, not per iteration).
*/
void orderForFillIn(int freeCount, const std::vector<std::pair<size_t, size_t>> &ends, std::vector<int> &free)
{
  std::vector<Eigen::Triplet<double>> pattern;
  for (int f = 0; f < freeCount; ++f) {
    pattern.emplace_back(f, f, 1.);
  }
  for (const auto &end : ends) {
    const int fi = free[end.first], fj = free[end.second];
    if (fi >= 0 && fj >= 0) {
      pattern.emplace_back(fi, fj, 1.);
      pattern.emplace_back(fj, fi, 1.);
    }
  }
  Eigen::SparseMatrix<double> graph(freeCount, freeCount);
  graph.setFromTriplets(pattern.begin(), pattern.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> inverse;
  Eigen::AMDOrdering<int>()(graph, inverse);
  const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order = inverse.inverse();
  for (int &f : free) {
    f = f >= 0 ? order.indices()[f] : -1;
  }
}

/*!
  The normal equations' blocks: every free vertex's, then each pair of free vertices an edge joins (upper); per edge,
  its off-diagonal block into \e offDiagonalBlock (-1 when an end is fixed).
*/
std::vector<std::pair<int, int>> normalBlocks(int freeCount, const std::vector<int> &free,
                                              const std::vector<std::pair<size_t, size_t>> &ends,
                                              std::vector<int> &offDiagonalBlock)
{
  std::vector<std::pair<int, int>> out;
  for (int f = 0; f < freeCount; ++f) {
    out.emplace_back(f, f);
  }
  std::map<std::pair<int, int>, int> offDiagonal;
  offDiagonalBlock.assign(ends.size(), -1);
  for (size_t k = 0; k < ends.size(); ++k) {
    const int fi = free[ends[k].first], fj = free[ends[k].second];
    if (fi >= 0 && fj >= 0) {
      const std::pair<int, int> key(std::min(fi, fj), std::max(fi, fj));
      auto it = offDiagonal.emplace(key, static_cast<int>(out.size())).first;
      if (it->second == static_cast<int>(out.size())) {
        out.push_back(key);
      }
      offDiagonalBlock[k] = it->second;
    }
  }
  return out;
}

/*!
  Levenberg-Marquardt on a pose graph's free vertices (Marquardt's scaling H + damping diag(H), Nielsen's damping
  update), with the normal equations accumulated block by block and factorised by Eigen's sparse LDL^T (its AMD
  ordering and symbolic analysis done once). Vertices and edges arrive indexed (vertex ids in increasing order, so the
  solution does not depend on insertion order or heap layout).
*/
class LevenbergMarquardt
{
public:
  LevenbergMarquardt(std::vector<Sim3d> &S, const std::vector<bool> &fixed, const std::vector<PoseGraphEdge> &edges,
                     const std::vector<std::pair<size_t, size_t>> &ends,
                     const std::vector<PoseGraphSighting> &sightings,
                     const std::vector<std::pair<size_t, size_t>> &sightingEnds)
      : m_S(S), m_edges(edges), m_ends(ends), m_sightings(sightings), m_sightingEnds(sightingEnds)
  {
    m_allEnds = ends;
    m_allEnds.insert(m_allEnds.end(), sightingEnds.begin(), sightingEnds.end());
    for (bool f : fixed) {
      m_free.push_back(f ? -1 : m_freeCount++);
    }
  }

  PoseGraphSummary run(int maxIterations)
  {
    PoseGraphSummary out;
    double current = cost(m_S);
    out.initialCost = out.finalCost = current;
    out.usable = std::isfinite(current);
    if (m_allEnds.empty() || m_freeCount == 0 || !out.usable) {
      return out;
    }
    orderForFillIn(m_freeCount, m_allEnds, m_free);
    NormalEquations normal(m_freeCount, normalBlocks(m_freeCount, m_free, m_allEnds, m_offDiagonalBlock));
    Cholesky cholesky;
    cholesky.analyzePattern(normal.H);
    Eigen::VectorXd gradient(7 * m_freeCount);
    Eigen::SparseMatrix<double> damped = normal.H;
    double damping = kInitialDamping, growth = 2.;
    bool linearized = false;
    while (out.iterations < maxIterations) {
      ++out.iterations;
      if (!linearized) {
        linearize(normal, gradient);
        linearized = true;
        if (gradient.lpNorm<Eigen::Infinity>() <= kGradientTolerance) {
          break;
        }
      }
      const Eigen::VectorXd step = dampedStep(normal, gradient, damping, damped, cholesky);
      std::vector<Sim3d> candidate;
      const double next = costAfter(step, candidate);
      // The linear model's decrease: -(g.step + step.H.step / 2).
      const double predicted =
          candidate.empty() ? 0.
                            : -(gradient.dot(step) + 0.5 * step.dot(normal.H.selfadjointView<Eigen::Upper>() * step));
      if (!(next < current) || !(predicted > 0.)) {
        damping *= growth;
        growth *= 2.;
        continue;
      }
      const double rho = (current - next) / predicted;
      const double decrease = current - next;
      m_S.swap(candidate);
      current = next;
      linearized = false;
      damping *= std::max(1. / 3., 1. - std::pow(2. * rho - 1., 3));
      growth = 2.;
      if (decrease <= kFunctionTolerance * (current + decrease) ||
          step.norm() <= kStepTolerance * (parameterNorm() + kStepTolerance)) {
        break;
      }
    }
    out.finalCost = current;
    return out;
  }

private:
  using Cholesky = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>>;

  //! The step of (H + damping diag(H)) step = -gradient, \e damped holding that matrix; empty when not factorisable.
  static Eigen::VectorXd dampedStep(const NormalEquations &normal, const Eigen::VectorXd &gradient, double damping,
                                    Eigen::SparseMatrix<double> &damped, Cholesky &cholesky)
  {
    std::copy(normal.H.valuePtr(), normal.H.valuePtr() + normal.H.nonZeros(), damped.valuePtr());
    for (int d : normal.diagonal) {
      damped.valuePtr()[d] += damping * std::clamp(normal.H.valuePtr()[d], kMinDiagonal, kMaxDiagonal);
    }
    cholesky.factorize(damped);
    return cholesky.info() == Eigen::Success ? Eigen::VectorXd(cholesky.solve(-gradient)) : Eigen::VectorXd();
  }

  /*!
    The vertices moved by \e step into \e candidate and their cost; infinity, \e candidate left empty, for a step
    that is empty, not finite or would take a scale out of bounds.
  */
  double costAfter(const Eigen::VectorXd &step, std::vector<Sim3d> &candidate) const
  {
    if (step.size() == 0 || !step.allFinite() || !scalesStayUsable(step)) {
      return std::numeric_limits<double>::infinity();
    }
    candidate = m_S;
    for (size_t v = 0; v < m_S.size(); ++v) {
      if (m_free[v] >= 0) {
        candidate[v] = Sim3d::exp(step.segment<7>(7 * m_free[v])) * m_S[v];
      }
    }
    return cost(candidate);
  }

  //! 0.5 sum |W log(S_ji Si Sj^-1)|^2 and the sightings' robust costs at \e S; infinity when not finite.
  double cost(const std::vector<Sim3d> &S) const
  {
    double sum = 0.;
    for (size_t k = 0; k < m_edges.size(); ++k) {
      sum +=
          (m_edges[k].sqrtInformation * edgeError(m_edges[k], S[m_ends[k].first], S[m_ends[k].second])).squaredNorm();
    }
    for (size_t k = 0; k < m_sightings.size(); ++k) {
      const PoseGraphSighting &o = m_sightings[k];
      const double r2 = sightingResidual(o, S[m_sightingEnds[k].first], S[m_sightingEnds[k].second]).squaredNorm();
      const double c2 = o.robustScale * o.robustScale;
      sum += o.weight * o.weight * (o.robustScale > 0. ? c2 * std::log1p(r2 / c2) : r2);
    }
    return std::isfinite(sum) ? 0.5 * sum : std::numeric_limits<double>::infinity();
  }

  //! A sighting's whitened residual at the landmark's \e Sl and the keyframe's \e Sk.
  static Vec6 sightingResidual(const PoseGraphSighting &o, const Sim3d &Sl, const Sim3d &Sk)
  {
    return o.sqrtInformation * metricSightingError<double>(o, Sl, Sk);
  }

  /*!
    Linearises sighting \e k into \e normal and \e gradient: central differences under left updates (a few tens of
    sightings at most, 28 evaluations each), the Cauchy cost as iteratively reweighted least squares (weight
    weight^2 / (1 + |r|^2 / c^2), Ceres' first-order correction left out).
  */
  void linearizeSighting(size_t k, NormalEquations &normal, Eigen::VectorXd &gradient) const
  {
    const PoseGraphSighting &o = m_sightings[k];
    const size_t l = m_sightingEnds[k].first, v = m_sightingEnds[k].second;
    const int fl = m_free[l], fv = m_free[v];
    if (fl < 0 && fv < 0) {
      return;
    }
    const Vec6 r = sightingResidual(o, m_S[l], m_S[v]);
    const double c2 = o.robustScale * o.robustScale;
    const double w = o.weight * o.weight / (o.robustScale > 0. ? 1. + r.squaredNorm() / c2 : 1.);
    constexpr double h = 1e-6;
    Mat67 Jl, Jv;
    for (int d = 0; d < 7; ++d) {
      const Sim3d plus = Sim3d::exp(Vec7::Unit(d) * h), minus = Sim3d::exp(Vec7::Unit(d) * -h);
      Jl.col(d) = (sightingResidual(o, plus * m_S[l], m_S[v]) - sightingResidual(o, minus * m_S[l], m_S[v])) / (2. * h);
      Jv.col(d) = (sightingResidual(o, m_S[l], plus * m_S[v]) - sightingResidual(o, m_S[l], minus * m_S[v])) / (2. * h);
    }
    if (fl >= 0) {
      normal.add(fl, w * Jl.transpose() * Jl);
      gradient.segment<7>(7 * fl) += w * Jl.transpose() * r;
    }
    if (fv >= 0) {
      normal.add(fv, w * Jv.transpose() * Jv);
      gradient.segment<7>(7 * fv) += w * Jv.transpose() * r;
    }
    const int block = m_offDiagonalBlock[m_edges.size() + k];
    if (block >= 0) { // above the diagonal: the lower free index is the block's row
      normal.add(block, fl < fv ? Mat7(w * Jl.transpose() * Jv) : Mat7(w * Jv.transpose() * Jl));
    }
  }

  //! False when \e step would take a scale beyond e^+-kMaxAbsLogScale (no similarity a map can have): refused.
  bool scalesStayUsable(const Eigen::VectorXd &step) const
  {
    for (size_t v = 0; v < m_S.size(); ++v) {
      if (m_free[v] >= 0 && std::abs(std::log(m_S[v].scale()) + step(7 * m_free[v] + 6)) >= kMaxAbsLogScale) {
        return false;
      }
    }
    return true;
  }

  double parameterNorm() const
  {
    double sum = 0.;
    for (const Sim3d &x : m_S) {
      sum += x.translation().squaredNorm() + x.unitQuaternion().coeffs().squaredNorm() +
             std::log(x.scale()) * std::log(x.scale());
    }
    return std::sqrt(sum);
  }

  /*!
    Linearises every edge at the current vertices into \e normal (H = sum J^T J over the free vertices' blocks) and
    \e gradient (J^T r). With left updates S <- exp(delta) S, the error e = log(S_ji Si Sj^-1) moves by
    de/d(delta_i) = Jl^-1(e) Ad(S_ji) and de/d(delta_j) = -Jr^-1(e), with Jl^-1(e) ~ I - ad(e)/2 and
    Jr^-1(e) ~ I + ad(e)/2 to first order in e (a pose graph's residuals are small near its solution; where they
    vanish, the fixed point J^T r = 0 is the exact one whatever the Jacobian's approximation).
  */
  void linearize(NormalEquations &normal, Eigen::VectorXd &gradient) const
  {
    std::fill(normal.H.valuePtr(), normal.H.valuePtr() + normal.H.nonZeros(), 0.);
    gradient.setZero();
    for (size_t k = 0; k < m_edges.size(); ++k) {
      const PoseGraphEdge &e = m_edges[k];
      const int fi = m_free[m_ends[k].first], fj = m_free[m_ends[k].second];
      if (fi < 0 && fj < 0) {
        continue;
      }
      const Vec7 err = edgeError(e, m_S[m_ends[k].first], m_S[m_ends[k].second]);
      const Mat7 halfAd = 0.5 * Sim3d::ad(err);
      const Vec7 r = e.sqrtInformation * err;
      const Mat7 Ji = e.sqrtInformation * (Mat7::Identity() - halfAd) * e.Sji.adjoint();
      const Mat7 Jj = -e.sqrtInformation * (Mat7::Identity() + halfAd);
      if (fi >= 0) {
        normal.add(fi, Ji.transpose() * Ji);
        gradient.segment<7>(7 * fi) += Ji.transpose() * r;
      }
      if (fj >= 0) {
        normal.add(fj, Jj.transpose() * Jj);
        gradient.segment<7>(7 * fj) += Jj.transpose() * r;
      }
      if (m_offDiagonalBlock[k] >= 0) { // above the diagonal: the lower free index is the block's row
        normal.add(m_offDiagonalBlock[k], fi < fj ? Mat7(Ji.transpose() * Jj) : Mat7(Jj.transpose() * Ji));
      }
    }
    for (size_t k = 0; k < m_sightings.size(); ++k) {
      linearizeSighting(k, normal, gradient);
    }
  }

  std::vector<Sim3d> &m_S;
  const std::vector<PoseGraphEdge> &m_edges;
  const std::vector<std::pair<size_t, size_t>> &m_ends; //!< per edge, positions of i and j in m_S
  const std::vector<PoseGraphSighting> &m_sightings;
  const std::vector<std::pair<size_t, size_t>> &m_sightingEnds; //!< per sighting, positions of its landmark, keyframe
  std::vector<std::pair<size_t, size_t>> m_allEnds;             //!< the edges' ends, then the sightings'
  std::vector<int> m_free;                                      //!< per vertex, its index among the free ones, or -1
  int m_freeCount = 0;
  std::vector<int> m_offDiagonalBlock; //!< per edge then sighting, its off-diagonal block, or -1 (an end is fixed)
};
} // namespace

PoseGraphSummary solveSparsePoseGraph(std::vector<Sim3d> &S, const std::vector<bool> &fixed,
                                      const std::vector<PoseGraphEdge> &edges,
                                      const std::vector<std::pair<size_t, size_t>> &ends, int maxIterations,
                                      const std::vector<PoseGraphSighting> &sightings,
                                      const std::vector<std::pair<size_t, size_t>> &sightingEnds)
{
  PoseGraphSummary out = LevenbergMarquardt(S, fixed, edges, ends, sightings, sightingEnds).run(maxIterations);
  out.usable = out.usable && std::all_of(S.begin(), S.end(), [](const Sim3d &x) {
                 return x.translation().allFinite() && x.unitQuaternion().coeffs().allFinite();
               });
  return out;
}
} // namespace hslam
