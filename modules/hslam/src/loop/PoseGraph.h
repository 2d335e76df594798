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
  tie down, and the corrected loop side) are held constant. Solved by Levenberg-Marquardt in Ceres (sparse Cholesky
  on the normal equations), vertices updated on the left on the Sim(3) manifold.

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
  //! Edge from the current estimates of i and j (consecutive keyframes, co-visibility), weighted by \e weight.
  void addEdgeFromCurrent(int i, int j, double weight = 1.);

  PoseGraphSummary optimize(int maxIterations = 20);

  //! Current S_iw of vertex \e id. \exception vpHSlamException::invalidArgument for an unknown id.
  Sim3d vertex(int id) const;
  size_t vertexCount() const { return m_vertices.size(); }
  size_t edgeCount() const { return m_edges.size(); }

private:
  //! [qx, qy, qz, qw, tx, ty, tz, log s] (loop/Sim3Parameters.h).
  static constexpr int kVertexParameters = 8;
  struct Vertex {
    std::array<double, kVertexParameters> x;
    bool fixed = false;
  };
  std::map<int, Vertex> m_vertices;
  std::vector<PoseGraphEdge> m_edges;
};
} // namespace hslam

#endif
