/*
 * H-SLAM for ViSP.
 */
/*!
  \file PoseGraph.h
  \brief Pose-graph optimisation over Sim(3) (loop correction, paper sec. 3.4; ORB-SLAM's essential graph,
  Mur-Artal et al. TRO 2015 eq. 9).

  What it is for: after a loop is verified, the keyframe poses are corrected as Sim(3) elements so that scale drift
  can be undone as well as pose drift. Vertices are world-to-camera similarities S_iw; an edge (i, j) measures
  S_ji = S_jw S_iw^-1 and contributes the residual r = sqrtInformation * log(S_ji S_iw S_jw^-1) (7-vector in the
  tangent order of Sim3.h). Fixed vertices (the active window and the newest keyframes, which the window's priors
  tie down, and the corrected loop side) are held constant. Solved by Levenberg-Marquardt, vertices updated on the
  left on the Sim(3) manifold: in Ceres (automatic differentiation, sparse Cholesky on the normal equations) below
  kSparseSolverVertices free vertices and kSparseSolverEdges edges, by loop/SparsePoseGraphSolver.h (analytic
  Jacobians, block-sparse normal equations) from there on.

  Metric sightings (addSighting()): a keyframe's measured pose relative to a landmark (an AprilTag) in metres. The
  landmark's vertex S_lw maps the world to the landmark's frame in metres; S = A S_kw S_lw^-1 (A: a fixed factor, the
  identity but for keyframes moved as one block) maps the landmark's frame into the keyframe's camera in the
  keyframe's own unit, so S = (R, t, 1/lambda) with lambda the metres per unit there. The residual compares what that
  predicts in metres with the measurement: log(cRl_measured^T R) and t / scale(S) - ctl_measured, whatever the
  keyframe's scale: a landmark seen again after the map's scale drifted pulls the drifted keyframes back to the metres
  of the first sightings, as a loop pulls them back to the place. Both solvers take them (the sparse one with
  central-difference Jacobians and the Cauchy cost as iteratively reweighted least squares).

  Why two: at 10,000 keyframes Ceres takes 5.1 s and the sparse solver 0.7 s (loop benchmark). On the loops of the
  synthetic and real runs the two reach the same cost to the digits printed, but a run that continues after a
  correction diverges chaotically from any difference in the last digits (which loops it finds next, which frame
  loses the scale): over the 11 point budgets of the synthetic two-lap room the slam median was 0.021 m with Ceres and
  0.029 m with the sparse solver everywhere (worst run 0.130 against 0.046 m). Not a measured gain on maps of the
  size the tests and benchmarks reach, so those keep Ceres; large maps, where Ceres passes a second, get the sparse
  solver.

  Threading: an object is used from one thread (the loop-closure thread).
*/
#ifndef HSLAM_LOOP_POSE_GRAPH_H
#define HSLAM_LOOP_POSE_GRAPH_H

#include "loop/Sim3Solver.h"

#include <visp3/core/vpConfig.h>

#include <array>
#include <map>
#include <vector>

namespace hslam
{
//! A relative Sim(3) constraint.
struct PoseGraphEdge {
  int i = -1, j = -1;
  Sim3d Sji;                                                                             //!< measured S_jw S_iw^-1
  Eigen::Matrix<double, 7, 7> sqrtInformation = Eigen::Matrix<double, 7, 7>::Identity(); //!< residual weight
};

//! A metric sighting of a landmark from a keyframe (file comment).
struct PoseGraphSighting {
  int landmark = -1; //!< vertex S_lw: world to the landmark's frame, metres
  int keyframe = -1; //!< vertex S_kw (or the block the keyframe moves with, see Akw)
  Sim3d Akw;         //!< fixed left factor: the keyframe's S_kw is Akw times the vertex (identity for its own vertex)
  SE3d cMl;          //!< measured: landmark frame to camera, metres
  //! Residual weight, rotation (radians) then translation (metres): the measurement's inverse standard deviations.
  Eigen::Matrix<double, 6, 6> sqrtInformation = Eigen::Matrix<double, 6, 6>::Identity();
  //! The whitened residual's Cauchy scale (a wrong detection, off by tens of degrees, is not followed); 0: none.
  double robustScale = 0.;
  //! Weight of the robust cost against the graph's edges (their information is the identity).
  double weight = 1.;
};

/*!
  The unweighted error of a metric sighting at the landmark's vertex \e Slw and the keyframe's \e Skw (the file
  comment): rotation vector of lRc_measured R(S), then t(S) / scale(S) - ctl_measured, S = Akw Skw Slw^-1. Templated
  for Ceres' automatic differentiation; the sparse solver evaluates it in double.
*/
template <typename T>
Eigen::Matrix<T, 6, 1> metricSightingError(const PoseGraphSighting &s, const Sim3<T> &Slw, const Sim3<T> &Skw)
{
  const Sim3<T> S = s.Akw.template cast<T>() * Skw * Slw.inverse();
  const Eigen::Quaternion<T> lRc = s.cMl.unitQuaternion().conjugate().template cast<T>();
  Eigen::Matrix<T, 6, 1> e;
  e.template head<3>() = so3LogQuaternion<T>(lRc * S.unitQuaternion());
  e.template tail<3>() = S.translation() / S.scale() - s.cMl.translation().template cast<T>();
  return e;
}

//! What optimize() did.
struct PoseGraphSummary {
  bool usable = false; //!< Ceres returned a usable solution (vertices written)
  int iterations = 0;
  double initialCost = 0.; //!< 0.5 sum |r|^2 before
  double finalCost = 0.;   //!< and after
  double ms = 0.;          //!< wall time
};

class VISP_EXPORT PoseGraph
{
public:
  //! Add (or replace) vertex \e id with its initial S_iw.
  void addVertex(int id, const Sim3d &Siw, bool fixed = false);
  //! Add an edge between two vertices already added. \exception vpHSlamException::invalidArgument otherwise.
  void addEdge(const PoseGraphEdge &edge);
  //! Add a metric sighting between two vertices already added. \exception vpHSlamException::invalidArgument otherwise.
  void addSighting(const PoseGraphSighting &sighting);
  //! Edge from the current estimates of i and j (consecutive keyframes, co-visibility), weighted by \e weight.
  void addEdgeFromCurrent(int i, int j, double weight = 1.);

  //! Which solver optimize() uses.
  enum class Solver {
    automatic, //!< Ceres below kSparseSolverVertices free vertices and kSparseSolverEdges edges, else sparse
    ceres,     //!< Ceres (automatic differentiation)
    sparse     //!< loop/SparsePoseGraphSolver.h
  };
  //! Free vertices from which Solver::automatic takes the sparse solver (Ceres: 0.32 s at 1,000 keyframes here).
  static constexpr size_t kSparseSolverVertices = 1000;
  /*!
    Edges from which Solver::automatic takes the sparse solver: Ceres costs about 18 us per edge and iteration here
    (automatic differentiation), so a graph made dense by many loops (each adds an edge per pair of its two sides'
    keyframes) passes a second long before 1,000 keyframes: 6.9 s at 967 in hslam_many_laps with re-use off.
  */
  static constexpr size_t kSparseSolverEdges = 4000;

  PoseGraphSummary optimize(int maxIterations = 20, Solver solver = Solver::automatic);

  //! Current S_iw of vertex \e id. \exception vpHSlamException::invalidArgument for an unknown id.
  Sim3d vertex(int id) const;
  size_t vertexCount() const { return m_vertices.size(); }
  size_t edgeCount() const { return m_edges.size(); }
  size_t sightingCount() const { return m_sightings.size(); }

private:
  //! [qx, qy, qz, qw, tx, ty, tz, log s] (loop/Sim3Parameters.h).
  static constexpr int kVertexParameters = 8;
  struct Vertex {
    std::array<double, kVertexParameters> x;
    bool fixed = false;
  };
  PoseGraphSummary optimizeSparse(int maxIterations);

  std::map<int, Vertex> m_vertices;
  std::vector<PoseGraphEdge> m_edges;
  std::vector<PoseGraphSighting> m_sightings;
};
} // namespace hslam

#endif
