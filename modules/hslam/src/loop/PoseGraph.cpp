/*
 * H-SLAM for ViSP.
 */
#include "loop/PoseGraph.h"

#include "loop/LoopSolverOptions.h"
#include "loop/Sim3Parameters.h"
#include "loop/SparsePoseGraphSolver.h"

#include <visp3/hslam/vpHSlamException.h>

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>

namespace hslam
{
namespace
{
static_assert(kSim3ParameterSize == 8, "PoseGraph stores vertices in the layout of Sim3Parameters.h");

struct RelativeSim3Error {
  explicit RelativeSim3Error(const PoseGraphEdge &e) : Sji(e.Sji), W(e.sqrtInformation) {}
  template <typename T> bool operator()(const T *xi, const T *xj, T *residual) const
  {
    if (!sim3ParametersValid(xi) || !sim3ParametersValid(xj)) {
      return false;
    }
    // log(S_ji_measured S_iw S_jw^-1): identity when the estimates agree with the measurement.
    const Sim3<T> Siw = sim3FromParameters(xi);
    const Sim3<T> Sjw = sim3FromParameters(xj);
    const Eigen::Matrix<T, 7, 1> e = (Sji.cast<T>() * Siw * Sjw.inverse()).log();
    Eigen::Map<Eigen::Matrix<T, 7, 1>> r(residual);
    r = W.cast<T>() * e;
    return true;
  }
  Sim3d Sji; //!< the measurement
  Eigen::Matrix<double, 7, 7> W;
};
//! The residual of a metric sighting (PoseGraph.h), whitened.
struct MetricSightingError {
  explicit MetricSightingError(const PoseGraphSighting &s) : sighting(s) {}
  template <typename T> bool operator()(const T *xl, const T *xk, T *residual) const
  {
    if (!sim3ParametersValid(xl) || !sim3ParametersValid(xk)) {
      return false;
    }
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual);
    r = sighting.sqrtInformation.cast<T>() *
        metricSightingError<T>(sighting, sim3FromParameters(xl), sim3FromParameters(xk));
    return true;
  }
  PoseGraphSighting sighting;
};
} // namespace

void PoseGraph::addVertex(int id, const Sim3d &Siw, bool fixed)
{
  Vertex v;
  sim3ToParameters(Siw, v.x.data());
  v.fixed = fixed;
  m_vertices[id] = v;
}

void PoseGraph::addEdge(const PoseGraphEdge &edge)
{
  if (!m_vertices.count(edge.i) || !m_vertices.count(edge.j) || edge.i == edge.j) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "PoseGraph: edge " + std::to_string(edge.i) + "-" +
                                                                  std::to_string(edge.j) +
                                                                  " joins unknown or identical vertices");
  }
  m_edges.push_back(edge);
}

void PoseGraph::addSighting(const PoseGraphSighting &sighting)
{
  if (!m_vertices.count(sighting.landmark) || !m_vertices.count(sighting.keyframe) ||
      sighting.landmark == sighting.keyframe) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "PoseGraph: sighting " + std::to_string(sighting.landmark) + "-" +
                               std::to_string(sighting.keyframe) + " joins unknown or identical vertices");
  }
  m_sightings.push_back(sighting);
}

void PoseGraph::addEdgeFromCurrent(int i, int j, double weight)
{
  PoseGraphEdge e;
  e.i = i;
  e.j = j;
  if (!m_vertices.count(i) || !m_vertices.count(j)) {
    addEdge(e); // throws
  }
  e.Sji = vertex(j) * vertex(i).inverse();
  e.sqrtInformation = weight * Eigen::Matrix<double, 7, 7>::Identity();
  addEdge(e);
}

Sim3d PoseGraph::vertex(int id) const
{
  auto it = m_vertices.find(id);
  if (it == m_vertices.end()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "PoseGraph: unknown vertex " + std::to_string(id));
  }
  return sim3FromParameters(it->second.x.data());
}

PoseGraphSummary PoseGraph::optimize(int maxIterations, Solver solver)
{
  const size_t free = static_cast<size_t>(
      std::count_if(m_vertices.begin(), m_vertices.end(), [](const auto &v) { return !v.second.fixed; }));
  if (solver == Solver::sparse ||
      (solver == Solver::automatic && (free >= kSparseSolverVertices || m_edges.size() >= kSparseSolverEdges))) {
    return optimizeSparse(maxIterations);
  }
  const auto t0 = std::chrono::steady_clock::now();
  PoseGraphSummary out;
  if (m_edges.empty() && m_sightings.empty()) {
    out.usable = true;
    return out;
  }
  for (const auto &entry : m_vertices) {
    if (!sim3ParametersValid(entry.second.x.data())) {
      return out; // not usable: Ceres aborts on a parameter block its manifold cannot be evaluated at
    }
  }
  ceres::Problem::Options problemOptions;
  problemOptions.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problemOptions);
  for (const PoseGraphEdge &e : m_edges) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<RelativeSim3Error, 7, kVertexParameters, kVertexParameters>(
            new RelativeSim3Error(e)),
        nullptr, m_vertices[e.i].x.data(), m_vertices[e.j].x.data());
  }
  for (const PoseGraphSighting &s : m_sightings) {
    ceres::LossFunction *loss = nullptr;
    if (s.robustScale > 0.) {
      loss = new ceres::ScaledLoss(new ceres::CauchyLoss(s.robustScale), s.weight * s.weight, ceres::TAKE_OWNERSHIP);
    } else if (s.weight != 1.) {
      loss = new ceres::ScaledLoss(nullptr, s.weight * s.weight, ceres::TAKE_OWNERSHIP);
    }
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<MetricSightingError, 6, kVertexParameters, kVertexParameters>(
            new MetricSightingError(s)),
        loss, m_vertices[s.landmark].x.data(), m_vertices[s.keyframe].x.data());
  }
  for (auto &entry : m_vertices) {
    double *x = entry.second.x.data();
    if (!problem.HasParameterBlock(x)) {
      continue;
    }
    problem.SetManifold(x, newSim3Manifold());
    if (entry.second.fixed) {
      problem.SetParameterBlockConstant(x);
    }
  }
  const ceres::Solver::Options options = loopSolverOptions(maxIterations, ceres::SPARSE_NORMAL_CHOLESKY);
  ceres::Solver::Summary summary;
  std::map<int, Vertex> backup = m_vertices;
  ceres::Solve(options, &problem, &summary);
  out.usable = summary.IsSolutionUsable();
  for (const auto &entry : m_vertices) {
    out.usable = out.usable && sim3ParametersValid(entry.second.x.data());
  }
  if (!out.usable) {
    m_vertices.swap(backup);
  }
  out.iterations = static_cast<int>(summary.iterations.size());
  out.initialCost = summary.initial_cost;
  out.finalCost = summary.final_cost;
  out.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

PoseGraphSummary PoseGraph::optimizeSparse(int maxIterations)
{
  const auto t0 = std::chrono::steady_clock::now();
  std::map<int, size_t> position; // vertex id -> index (increasing ids: insertion order is irrelevant)
  std::vector<Sim3d> S;
  std::vector<bool> fixed;
  for (const auto &entry : m_vertices) {
    position[entry.first] = S.size();
    S.push_back(sim3FromParameters(entry.second.x.data()));
    fixed.push_back(entry.second.fixed);
  }
  std::vector<std::pair<size_t, size_t>> ends, sightingEnds;
  for (const PoseGraphEdge &e : m_edges) {
    ends.emplace_back(position[e.i], position[e.j]);
  }
  for (const PoseGraphSighting &s : m_sightings) {
    sightingEnds.emplace_back(position[s.landmark], position[s.keyframe]);
  }
  PoseGraphSummary out = solveSparsePoseGraph(S, fixed, m_edges, ends, maxIterations, m_sightings, sightingEnds);
  if (out.usable) {
    for (auto &entry : m_vertices) {
      sim3ToParameters(S[position[entry.first]], entry.second.x.data());
    }
  }
  out.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}
} // namespace hslam
